// Material "diffuse": Lambertian reflection; `albedo` is a colour or a texture.
#include "material/lambert.h"
#include "material/material_registry.h"

namespace sg {

class DiffuseMaterial final : public Material {
 public:
  explicit DiffuseMaterial(std::shared_ptr<Texture> albedo) : m_albedo(std::move(albedo)) {}
  Color eval(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    return lambert::eval(si, wo, wi, eval_texture(*m_albedo, si));
  }
  float pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    return lambert::pdf(si, wo, wi);
  }
  bool sample(const SurfaceInteraction& si, const Vec3f& wo, float, const Vec2f& u, BsdfSample* out) const override {
    return lambert::sample(si, wo, u, eval_texture(*m_albedo, si), out);
  }
  Color albedo(const SurfaceInteraction& si) const override { return eval_texture(*m_albedo, si); }
  uint32_t flags() const override { return k_bsdf_diffuse | k_bsdf_reflection; }

 private:
  std::shared_ptr<Texture> m_albedo;
};

std::shared_ptr<Material> create_diffuse_material(const ParamSet& params, const MaterialContext& ctx) {
  auto albedo = get_color_texture(params, "albedo", Color(0.5f), ctx.textures);
  Color avg = albedo->average();
  if (avg.x < 0.f || avg.y < 0.f || avg.z < 0.f || max_component(avg) > 1.f)
    throw Error("parameter 'albedo': components must lie in [0, 1]");
  return std::make_shared<DiffuseMaterial>(albedo);
}

}  // namespace sg
