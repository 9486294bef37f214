// Texture "facing": how much the surface faces a direction, dot(n, axis) of the unit shading
// normal (unperturbed by bump maps) and a unit axis, shaped like the procedural textures: e.g.
// snow that lies on up-facing surfaces and slides off steep ones (axis +y, remap
// [cos 55 deg, cos 35 deg], smooth), water standing on horizontal faces, moss on a north side.
//
// Parameters (defaults): axis (0, 1, 0), normalized; space "world" | "object" ("world": the
// normal after the instance transform, so a turned object keeps snow on whatever faces up);
// remap [lo, hi] -> [0, 1] ([-1, 1]: the cosine itself mapped to [0, 1]), smooth, invert;
// ramp_positions / ramp_colors.
#include "texture/procedural.h"

namespace sg {

namespace {

class FacingTexture final : public PointTexture {
 public:
  FacingTexture(const Vec3f& axis, bool object_space, ProceduralShaping shaping)
      : m_axis(axis), m_object(object_space), m_shaping(std::move(shaping)) {
    // Average over directions uniform on the sphere: the cosine is uniform in [-1, 1].
    Color s(0.f);
    for (int i = 0; i < 512; ++i) s += m_shaping.color(-1.f + 2.f * (float(i) + 0.5f) / 512.f);
    m_average = s / 512.f;
  }
  // The normal is part of the full TexturePoint (evaluated through eval_point).
  bool needs_position() const override { return true; }
  bool needs_uv_footprint() const override { return false; }
  Color eval_point(const TexturePoint& q) const override {
    return m_shaping.color(dot(m_object ? q.n_object : q.n_world, m_axis));
  }
  Color average() const override { return m_average; }

 private:
  Vec3f m_axis;
  bool m_object;
  ProceduralShaping m_shaping;
  Color m_average;
};

PluginInfo info() {
  PluginInfo i("texture", "facing",
               "How much the surface faces a direction: dot(shading normal, axis), shaped like the procedural "
               "textures; e.g. snow on up-facing surfaces (axis +y, remap [cos 55, cos 35], smooth).");
  i.add(param::vec3("axis", Vec3f(0.f, 1.f, 0.f), "the direction (normalized; default up, +y)"))
      .add(param::choice("space", "world", {"world", "object"},
                         "the normal in world space (after the instance transform) or object space"));
  ProceduralShaping::declare(i, Vec2f(-1.f, 1.f));
  return i;
}

std::shared_ptr<Texture> create(const Params& params, const PluginContext&) {
  Vec3f axis = params.get_vec3("axis");
  float l = length(axis);
  if (!(l > 1e-12f) || !std::isfinite(l)) throw Error("parameter 'axis': must be a non-zero direction");
  ProceduralShaping shaping = ProceduralShaping::from_params(params, Vec2f(-1.f, 1.f));
  return std::make_shared<FacingTexture>(axis / l, params.get_string("space") == "object", std::move(shaping));
}

}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
