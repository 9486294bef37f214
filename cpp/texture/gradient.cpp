// Texture "gradient": one coordinate of a mapping as a value, shaped like the procedural
// textures: e.g. relative-local height (mapping "relative", axis "y") to confine rust or dirt
// to the lower part of any model, whatever its size and position.
//
// Parameters (defaults): axis "x" | "y" | "z" ("y"); mapping "relative" (or uv, object, world),
// scale, offset; remap [lo, hi] -> [0, 1] ([0, 1]), smooth, invert; ramp_positions /
// ramp_colors.
#include "texture/procedural.h"

namespace sg {

namespace {

class GradientTexture final : public PointTexture {
 public:
  GradientTexture(int axis, ProceduralMapping mapping, ProceduralShaping shaping)
      : m_axis(axis), m_mapping(mapping), m_shaping(std::move(shaping)) {
    // Average over the unit interval of the coordinate (the relative-local range).
    Color s(0.f);
    for (int i = 0; i < 256; ++i) s += m_shaping.color((float(i) + 0.5f) / 256.f);
    m_average = s / 256.f;
  }
  bool needs_position() const override { return m_mapping.needs_position(); }
  bool needs_uv_footprint() const override { return !m_mapping.needs_position(); }
  Color eval_point(const TexturePoint& q) const override {
    return m_shaping.color(m_mapping.point(q)[m_axis]);
  }
  Color average() const override { return m_average; }

 private:
  int m_axis;
  ProceduralMapping m_mapping;
  ProceduralShaping m_shaping;
  Color m_average;
};

}  // namespace

namespace {

PluginInfo info() {
  PluginInfo i("texture", "gradient",
               "One coordinate of a mapping as a value, shaped like the procedural textures: e.g. relative-local "
               "height (mapping relative, axis y) confines rust or dirt to the lower part of any model.");
  i.add(param::choice("axis", "y", {"x", "y", "z"}, "the coordinate used")).add(ProceduralMapping::params("relative"));
  ProceduralShaping::declare(i, Vec2f(0.f, 1.f));
  return i;
}

std::shared_ptr<Texture> create(const Params& params, const PluginContext&) {
  std::string a = params.get_string("axis");
  ProceduralMapping mapping = ProceduralMapping::from_params(params);
  ProceduralShaping shaping = ProceduralShaping::from_params(params, Vec2f(0.f, 1.f));
  return std::make_shared<GradientTexture>(a == "x" ? 0 : (a == "y" ? 1 : 2), mapping, std::move(shaping));
}

}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
