// Texture "edges": how much the shading point is at a convex edge or a sheet's border,
// estimated by the integrator with `samples` short rays along the surface (from a point a tenth
// of `radius` above it, 15 degrees into it, `radius` long): the fraction that finds no surface
// -- 0 on an open panel, up to 1 at a thin edge. Creases stop the rays (they are "ao"'s).
// Shaped like the procedural textures (remap, smooth, invert, colour ramp): wear that starts at
// edges (rust, chipped paint).
//
// Parameters (defaults): radius (0.03 m), samples (8), remap ([0, 1]), smooth, invert,
// ramp_positions / ramp_colors. Outside path tracing (no rays) the value is 0.
#include "texture/procedural.h"

namespace sg {

namespace {

class EdgesTexture final : public PointTexture {
 public:
  EdgesTexture(float radius, int samples, ProceduralShaping shaping)
      : m_radius(radius), m_samples(samples), m_shaping(std::move(shaping)) {
    m_average = m_shaping.color(0.05f);  // a typical value over a model, for priors only
  }
  bool needs_position() const override { return true; }
  bool needs_uv_footprint() const override { return false; }
  float edge_radius() const override { return m_radius; }
  int edge_samples() const override { return m_samples; }
  Color eval_point(const TexturePoint& q) const override { return m_shaping.color(q.edge); }
  Color average() const override { return m_average; }

 private:
  float m_radius;
  int m_samples;
  ProceduralShaping m_shaping;
  Color m_average;
};

PluginInfo info() {
  PluginInfo i("texture", "edges",
               "Convex edges and sheet borders at the shading point: the fraction of `samples` short rays along the "
               "surface that find no surface (0 on an open panel, up to 1 at a thin edge), shaped like the procedural "
               "textures.");
  i.add(param::real("radius", 0.03, "ray length in metres (edges sharper than about 0.75 of it count)")
            .above(0)
            .at_most(100))
      .add(param::integer("samples", 8, "rays per shading point").in(1, 64));
  ProceduralShaping::declare(i, Vec2f(0.f, 1.f));
  return i;
}

std::shared_ptr<Texture> create(const Params& params, const PluginContext&) {
  return std::make_shared<EdgesTexture>(params.get_float("radius"), int(params.get_int("samples")),
                                        ProceduralShaping::from_params(params, Vec2f(0.f, 1.f)));
}

}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
