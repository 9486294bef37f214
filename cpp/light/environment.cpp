// Light "environment": constant radiance `radiance` arriving from every direction
// (a uniform sky). Sampled by the cosine around the shading point's normal (uniformly over
// the sphere where there is none); MIS with BSDF sampling.
#include "core/sampling.h"
#include "light/light.h"

namespace sg {

class ConstantEnvironment final : public Light {
 public:
  explicit ConstantEnvironment(const Color& l) : m_radiance(l) {}
  /// NOTE: with a normal, directions are cosine-distributed around it (Malley's method,
  /// pdf cos / pi): the exact importance of a constant sky for a Lambertian surface, which
  /// uniform sphere sampling wastes half of on the side below (Pharr et al., "Physically
  /// Based Rendering", 4th ed., sec. 12.5.1, samples its uniform infinite light over the
  /// hemisphere of the normal for the same reason). Directions below the normal's horizon
  /// then have density 0 and are left to BSDF sampling.
  bool sample(const LightSampleContext& ctx, const Vec2f& u, LightSample* out) const override {
    if (has_normal(ctx)) {
      Vec3f local = square_to_cosine_hemisphere(u);
      if (!(local.z > 0.f)) return false;
      out->wi = normalize(Frame(ctx.n).to_world(local));
      out->pdf = pdf_li(ctx, out->wi);
      if (!(out->pdf > 0.f)) return false;
    } else {
      out->wi = square_to_uniform_sphere(u);
      out->pdf = uniform_sphere_pdf();
    }
    set_infinite_sample(out, out->wi, m_radiance, out->pdf);
    return true;
  }
  float pdf_li(const LightSampleContext& ctx, const Vec3f& dir) const override {
    if (!has_normal(ctx)) return uniform_sphere_pdf();
    return std::max(0.f, dot(ctx.n, dir)) * k_inv_pi;
  }
  bool is_dome() const override { return true; }
  float power() const override { return 4.f * k_pi * k_pi * m_radius * m_radius * luminance(m_radiance); }
  bool is_infinite() const override { return true; }
  Color le(const Vec3f&) const override { return m_radiance; }
  float pdf_le(const Vec3f&) const override { return uniform_sphere_pdf(); }
  void preprocess(const Bounds3& b) override { m_radius = std::max(b.radius(), 1e-3f); }

 private:
  static bool has_normal(const LightSampleContext& ctx) { return ctx.n.x != 0.f || ctx.n.y != 0.f || ctx.n.z != 0.f; }
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
