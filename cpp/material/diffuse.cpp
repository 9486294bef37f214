// Material "diffuse": Lambertian reflection; `albedo` is a colour or a texture.
// Alpha cut-out (glTF alphaMode MASK): `alpha` is a scalar or a texture (its alpha channel
// if it has one, else its first channel; see eval_alpha_texture), `alpha_cutoff` in [0, 1]
// (0.5): where alpha < alpha_cutoff there is no surface (Material::has_alpha).
// Bump mapping: `bump_map` (a height texture, e.g. procedural noise) times `bump_scale`
// (normal_mapping.h apply_bump_map).
#include "material/lambert.h"
#include "material/normal_mapping.h"
#include "material/material.h"

namespace sg {

class DiffuseMaterial final : public Material {
 public:
  DiffuseMaterial(std::shared_ptr<Texture> albedo, std::shared_ptr<Texture> alpha, float alpha_cutoff,
                  std::shared_ptr<Texture> bump, float bump_scale)
      : m_albedo(std::move(albedo)), m_alpha(std::move(alpha)), m_alpha_cutoff(alpha_cutoff), m_bump(std::move(bump)),
        m_bump_scale(bump_scale) {}
  Color eval(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    return lambert::eval(normals(si), wo, wi, eval_texture(*m_albedo, si));
  }
  float pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    return lambert::pdf(normals(si), wo, wi);
  }
  Color eval_pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi, float* pdf_out) const override {
    return lambert::eval_pdf(normals(si), wo, wi, eval_texture(*m_albedo, si), pdf_out);
  }
  bool sample(const SurfaceInteraction& si, const Vec3f& wo, float, const Vec2f& u, BsdfSample* out) const override {
    return lambert::sample(normals(si), wo, u, eval_texture(*m_albedo, si), out);
  }
  Color albedo(const SurfaceInteraction& si) const override { return eval_texture(*m_albedo, si); }
  uint32_t flags() const override { return k_bsdf_diffuse | k_bsdf_reflection; }
  float alpha(const SurfaceInteraction& si) const override { return m_alpha ? eval_alpha_texture(*m_alpha, si) : 1.f; }
  bool has_alpha() const override { return m_alpha != nullptr; }
  uint32_t needs() const override {
    // A 3D height needs no uv tangent (bump_normal is frame-independent then).
    return texture_needs(*m_albedo) |
           (m_bump ? (m_bump->needs_position() ? 0u : uint32_t(k_needs_tangent)) | texture_needs(*m_bump) : 0u);
  }
  float alpha_cutoff() const override { return m_alpha_cutoff; }

 private:
  /// The geometric and the (bump-mapped) shading normal; the bumped normal is computed once
  /// per hit (SurfaceInteraction::tex_cache).
  lambert::Normals normals(const SurfaceInteraction& si) const {
    return m_bump ? lambert::Normals(si.ng, bump_normal(si, *m_bump, m_bump_scale)) : lambert::Normals(si);
  }

  std::shared_ptr<Texture> m_albedo;
  std::shared_ptr<Texture> m_alpha;  ///< null: opaque everywhere (no alpha test)
  float m_alpha_cutoff = 0.5f;
  std::shared_ptr<Texture> m_bump;   ///< height map (null: none)
  float m_bump_scale = 1.f;
};

namespace {

PluginInfo info() {
  return PluginInfo("material", "diffuse", "Lambertian reflection, with alpha cut-outs and bump mapping.")
      .add(param::color_texture("albedo", Color(0.5f), "Lambertian reflectance").in(0, 1))
      .add(param::float_texture("alpha", 1.0, "coverage for cut-outs (texture: its alpha channel, else the first)")
               .in(0, 1))
      .add(param::real("alpha_cutoff", 0.5, "hits with alpha below this are no surface").in(0, 1))
      .add(param::texture("bump_map", "height map (first channel)"))
      .add(param::real("bump_scale", 1.0, "height in uv units").in(-100, 100));
}

std::shared_ptr<Material> create(const Params& params, const PluginContext& ctx) {
  auto albedo = color_texture_param(params, "albedo", ctx.textures);
  float cutoff = params.get_float("alpha_cutoff");
  std::shared_ptr<Texture> alpha = texture_param(params, "alpha", ctx.textures);
  if (!alpha) {
    float a = params.get_float("alpha");
    // A constant alpha at or above the cutoff is an opaque material: no alpha test at all.
    if (a < cutoff) alpha = make_constant_texture(Color(a));
  }
  std::shared_ptr<Texture> bump = texture_param(params, "bump_map", ctx.textures);
  float bump_scale = params.get_float("bump_scale");
  return std::make_shared<DiffuseMaterial>(albedo, alpha, cutoff, bump, bump_scale);
}

}  // namespace

SG_REGISTER_PLUGIN(Material, info(), create)

}  // namespace sg
