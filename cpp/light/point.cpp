// Light "point": isotropic point light with `intensity` (W/sr per channel) at `position`.
#include "light/light.h"

namespace sg {

class PointLight final : public Light {
 public:
  PointLight(const Vec3f& pos, const Color& intensity) : m_pos(pos), m_intensity(intensity) {}
  bool sample(const LightSampleContext& ctx, const Vec2f&, LightSample* out) const override {
    return sample_point_emitter(ctx, m_pos, m_intensity, [](const Vec3f&) { return 1.f; }, out);
  }
  float power() const override { return 4.f * k_pi * luminance(m_intensity); }
  bool is_delta() const override { return true; }

  bool bounding_sphere(Vec3f* centre, float* radius) const override {
    *centre = m_pos;
    *radius = 0.f;
    return true;
  }

 private:
  Vec3f m_pos;
  Color m_intensity;
};

namespace {

PluginInfo info() {
  return PluginInfo("light", "point", "An isotropic point light.")
      .add(param::vec3("position", Vec3f(0.f), "light position"))
      .add(param::color("intensity", Color(1.f), "radiant intensity, W/sr per channel").at_least(0))
      .add(param::real("strength", 1.0, "multiplies intensity").at_least(0));
}

std::shared_ptr<Light> create(const Params& params, const PluginContext&) {
  Vec3f pos = params.get_vec3("position");
  Color intensity = params.get_color("intensity") * params.get_float("strength");
  return std::make_shared<PointLight>(pos, intensity);
}

}  // namespace

SG_REGISTER_PLUGIN(Light, info(), create)

}  // namespace sg
