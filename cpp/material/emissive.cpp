// Material "emissive": an area emitter with radiance `radiance` * `strength`
// (W / (m^2 sr) per channel) leaving the front face (the side the geometric normal
// points to), or both faces with `two_sided`. It may also reflect light diffusely
// with `albedo` (default 0), like a frosted lamp cover.
#include "core/error.h"
#include "material/lambert.h"
#include "material/material.h"

namespace sg {

class EmissiveMaterial final : public Material {
 public:
  EmissiveMaterial(const Color& radiance, std::shared_ptr<Texture> albedo, bool two_sided)
      : m_radiance(radiance), m_albedo(std::move(albedo)), m_two_sided(two_sided) {
    m_reflects = !is_black(m_albedo->average());
  }
  Color eval(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    return m_reflects ? lambert::eval(si, wo, wi, eval_texture(*m_albedo, si)) : Color(0.f);
  }
  float pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    return m_reflects ? lambert::pdf(si, wo, wi) : 0.f;
  }
  bool sample(const SurfaceInteraction& si, const Vec3f& wo, float, const Vec2f& u, BsdfSample* out) const override {
    return m_reflects && lambert::sample(si, wo, u, eval_texture(*m_albedo, si), out);
  }
  Color albedo(const SurfaceInteraction& si) const override { return eval_texture(*m_albedo, si); }
  uint32_t flags() const override { return m_reflects ? (k_bsdf_diffuse | k_bsdf_reflection) : k_bsdf_none; }

  Color emission(const SurfaceInteraction& si, const Vec3f& wo) const override {
    if (m_two_sided || dot(si.ng, wo) > 0.f) return m_radiance;
    return Color(0.f);
  }
  bool is_emissive() const override { return !is_black(m_radiance); }
  Color average_emission() const override { return m_radiance; }
  bool two_sided_emission() const override { return m_two_sided; }
  bool uniform_emission() const override { return true; }
  uint32_t needs() const override { return texture_needs(*m_albedo); }

 private:
  Color m_radiance;
  std::shared_ptr<Texture> m_albedo;
  bool m_two_sided;
  bool m_reflects;
};

namespace {

PluginInfo info() {
  return PluginInfo("material", "emissive",
                    "An area light: emits `radiance` x `strength` from the front face (both with two_sided), "
                    "plus diffuse reflection.")
      .add(param::color("radiance", Color(1.f), "emitted radiance, W/(m^2 sr) per channel").at_least(0))
      .add(param::real("strength", 1.0, "multiplies radiance").at_least(0))
      .add(param::color_texture("albedo", Color(0.f), "diffuse reflectance of the emitter").in(0, 1))
      .add(param::boolean("two_sided", false, "emit from both faces (default: the front face only)"));
}

std::shared_ptr<Material> create(const Params& params, const PluginContext& ctx) {
  Color radiance = params.get_color("radiance") * params.get_float("strength");
  auto albedo = color_texture_param(params, "albedo", ctx.textures);
  bool two_sided = params.get_bool("two_sided");
  return std::make_shared<EmissiveMaterial>(radiance, albedo, two_sided);
}

}  // namespace

SG_REGISTER_PLUGIN(Material, info(), create)

}  // namespace sg
