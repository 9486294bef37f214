// Light "environment": constant radiance `radiance` arriving from every direction
// (a uniform sky). Sampled uniformly over the sphere; MIS with BSDF sampling.
#include "core/sampling.h"
#include "light/light.h"

namespace sg {

class ConstantEnvironment final : public Light {
 public:
  explicit ConstantEnvironment(const Color& l) : m_radiance(l) {}
  bool sample(const LightSampleContext&, const Vec2f& u, LightSample* out) const override {
    out->wi = square_to_uniform_sphere(u);
    out->li = m_radiance;
    out->pdf = uniform_sphere_pdf();
    out->delta = false;
    out->infinite = true;
    out->p_light_error = Vec3f(0.f);
    out->n_light = Vec3f(0.f);
    return true;
  }
  float power() const override { return 4.f * k_pi * k_pi * m_radius * m_radius * luminance(m_radiance); }
  bool is_infinite() const override { return true; }
  Color le(const Vec3f&) const override { return m_radiance; }
  float pdf_le(const Vec3f&) const override { return uniform_sphere_pdf(); }
  void preprocess(const Bounds3& b) override { m_radius = std::max(b.radius(), 1e-3f); }

 private:
  Color m_radiance;
  float m_radius = 1.f;
};

namespace {

PluginInfo info() {
  return PluginInfo("light", "environment", "A constant environment: the same radiance from every direction.")
      .add(param::color("radiance", Color(1.f), "constant sky radiance per channel").at_least(0))
      .add(param::real("strength", 1.0, "multiplies radiance").at_least(0));
}

std::shared_ptr<Light> create(const Params& params, const PluginContext&) {
  Color l = params.get_color("radiance") * params.get_float("strength");
  return std::make_shared<ConstantEnvironment>(l);
}

}  // namespace

SG_REGISTER_PLUGIN(Light, info(), create)

}  // namespace sg
