// Texture "ao": ambient occlusion at the shading point, estimated by the integrator with
// `samples` short rays of length `radius` (cosine-weighted over the hemisphere of the shading
// normal): the fraction of unoccluded rays, 1 in the open, lower in creases and corners.
// Shaped like the procedural textures (remap [lo, hi] -> [0, 1], smooth, invert, colour ramp):
// e.g. invert: true for a mask that grows in creases (dirt accumulation).
//
// Parameters (defaults): radius (0.2 m), samples (4), remap ([0, 1]), smooth, invert,
// ramp_positions / ramp_colors. Outside path tracing (no AO computed) the value is 1.
#include "texture/procedural.h"

namespace sg {

namespace {

class AoTexture final : public PointTexture {
 public:
  AoTexture(float radius, int samples, ProceduralShaping shaping)
      : m_radius(radius), m_samples(samples), m_shaping(std::move(shaping)) {
    m_average = m_shaping.color(0.8f);  // a typical open-surface value, for priors only
  }
  bool needs_position() const override { return true; }
  bool needs_uv_footprint() const override { return false; }
  float ao_radius() const override { return m_radius; }
  int ao_samples() const override { return m_samples; }
  Color eval_point(const TexturePoint& q) const override { return m_shaping.color(q.ao); }
  Color average() const override { return m_average; }

 private:
  float m_radius;
  int m_samples;
  ProceduralShaping m_shaping;
  Color m_average;
};

}  // namespace

namespace {

PluginInfo info() {
  PluginInfo i("texture", "ao",
               "Ambient occlusion at the shading point: the fraction of `samples` short rays of length `radius` "
               "that escape (1 in the open, lower in creases), shaped like the procedural textures.");
  i.add(param::real("radius", 0.2, "ray length in metres").above(0).at_most(1e4))
      .add(param::integer("samples", 4, "rays per shading point").in(1, 64));
  ProceduralShaping::declare(i, Vec2f(0.f, 1.f));
  return i;
}

std::shared_ptr<Texture> create(const Params& params, const PluginContext&) {
  float radius = params.get_float("radius");
  int64_t samples = params.get_int("samples");
  return std::make_shared<AoTexture>(radius, int(samples), ProceduralShaping::from_params(params, Vec2f(0.f, 1.f)));
}

}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
