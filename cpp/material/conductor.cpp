// Material "conductor": rough metal. GGX microfacet reflection (Walter et al. 2007) with
// visible-normal sampling (Heitz 2018), height-correlated Smith masking-shadowing and the
// exact Fresnel reflectance of a conductor with a complex index of refraction eta + i k
// per RGB channel, given directly (`eta`, `k`) or by a measured `metal` preset.
//
// Parameters (see create_conductor_material): metal | eta + k, roughness + anisotropy |
// roughness_u + roughness_v, specular_tint. Roughness below 1e-3 (on both axes) is a smooth
// mirror: a single Dirac lobe (k_bsdf_delta; eval() and pdf() return 0, sample() returns the
// mirror direction with weight Fresnel * tint).
//
// Side rules: reflection only. The surface is two-sided: the shading frame is mirrored to the
// side of wo (judged on the geometric normal), wi must lie on that same side of the
// geometric normal and both directions above the (mirrored) shading normal, so shading
// normals cannot leak light through the surface (Veach 1997, sec. 5.3).
//
// Bump mapping: `bump_map` (a height texture) times `bump_scale` tilts the shading normal
// (normal_mapping.h bump_normal; e.g. the walls of a scratch's groove, synthgen.wear.scratches).
#include <string>
#include <vector>

#include "material/material.h"
#include "material/microfacet.h"
#include "material/normal_mapping.h"

namespace sg {

namespace {

struct MetalPreset {
  const char* name;
  Color eta, k;
};

// NOTE: complex indices of refraction of measured metals, reduced to linear-sRGB primaries.
// Silver, aluminium, gold, chromium and copper: the spectral data shipped with Mitsuba 0.6
// (data/ior/{Ag,Al,Au,Cr,Cu}.{eta,k}.spd, from the luxpop.com database of Palik's
// "Handbook of Optical Constants of Solids"), each spectrum integrated against the CIE 1931
// colour-matching functions, normalized by the integral of y-bar and converted XYZ -> linear
// sRGB (the reduction of Mitsuba 3's spectrum_list_to_srgb used for its RGB-mode conductor
// presets); the values are those tabulated by Tungsten (B. Bitterli,
// src/core/bsdfs/ComplexIorData.hpp). We re-derived Au and Al from the .spd files with the
// analytic CIE fit of Wyman, Sloan & Shirley 2013 (JCGT 2(2)) and agree within 1.5%.
// Iron is not in that data set: its values are refractiveindex.info data (Johnson & Christy
// 1974, Phys. Rev. B 9, 5056) sampled at 650 / 550 / 450 nm, as tabulated in V. Koylazov,
// "Understanding metalness" (Chaos Group blog, 2014): point samples, not CIE integrals.
// Normal-incidence reflectances ((n-1)^2 + k^2) / ((n+1)^2 + k^2) of these values:
// silver (0.97, 0.96, 0.92), aluminium (0.93, 0.92, 0.92), gold (0.97, 0.80, 0.32),
// chromium (0.68, 0.64, 0.64), copper (0.96, 0.66, 0.58), iron (0.53, 0.51, 0.50).
const MetalPreset k_metals[] = {
    {"aluminium", {1.6575f, 0.8804f, 0.5212f}, {9.2239f, 6.2695f, 4.8370f}},
    {"aluminum", {1.6575f, 0.8804f, 0.5212f}, {9.2239f, 6.2695f, 4.8370f}},
    {"chrome", {4.3697f, 2.9167f, 1.6547f}, {5.2064f, 4.2314f, 3.7549f}},
    {"chromium", {4.3697f, 2.9167f, 1.6547f}, {5.2064f, 4.2314f, 3.7549f}},
    {"copper", {0.2004f, 0.9240f, 1.1022f}, {3.9129f, 2.4528f, 2.1422f}},
    {"gold", {0.1431f, 0.3750f, 1.4425f}, {3.9832f, 2.3857f, 1.6032f}},
    {"iron", {2.9114f, 2.9497f, 2.5845f}, {3.0893f, 2.9318f, 2.7670f}},
    {"silver", {0.1553f, 0.1167f, 0.1384f}, {4.8283f, 3.1222f, 2.1470f}},
};
/// Preset name of an ideal reflector (Fresnel = 1 at every angle), as Mitsuba's "none".
constexpr const char* k_perfect_mirror = "none";

/// Roughness at or below which (on both axes) the surface is a smooth mirror.
constexpr float k_smooth_roughness = 1e-3f;

class ConductorMaterial final : public Material {
 public:
  ConductorMaterial(const Color& eta, const Color& k, bool perfect, float alpha_x, float alpha_y, bool smooth,
                    std::shared_ptr<Texture> tint, std::shared_ptr<Texture> bump, float bump_scale)
      : m_eta(eta), m_k(k), m_perfect(perfect), m_ggx(alpha_x, alpha_y), m_smooth(smooth), m_tint(std::move(tint)),
        m_bump(std::move(bump)), m_bump_scale(bump_scale) {}

  Color eval(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    Color f;
    float p;
    return !m_smooth && evaluate(si, wo, wi, &f, &p) ? f : Color(0.f);
  }

  float pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    Color f;
    float p;
    return !m_smooth && evaluate(si, wo, wi, &f, &p) ? p : 0.f;
  }

  Color eval_pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi, float* pdf_out) const override {
    Color f;
    if (!m_smooth && evaluate(si, wo, wi, &f, pdf_out)) return f;
    *pdf_out = 0.f;
    return Color(0.f);
  }

  int specular_events(const SurfaceInteraction&, SpecularEvent out[4]) const override {
    if (!m_ggx.sharp()) return 0;
    out[0] = SpecularEvent{};
    return 1;
  }

  bool sample(const SurfaceInteraction& si, const Vec3f& wo, float, const Vec2f& u, BsdfSample* out) const override {
    Frame f;
    float side;
    if (!sided(si, wo, &f, &side)) return false;
    Vec3f lo = sided_to_local(f, side, wo);
    if (lo.z <= 0.f) return false;
    if (m_smooth) {
      Vec3f wi = normalize(sided_to_world(f, side, Vec3f(-lo.x, -lo.y, lo.z)));
      if (dot(si.ng, wi) * side <= 0.f) return false;
      out->wi = wi;
      out->weight = fresnel(lo.z) * tint(si);
      out->pdf = 1.f;  // discrete probability of the only lobe (the density is a Dirac delta)
      out->flags = k_bsdf_delta | k_bsdf_reflection;
      out->eta = 1.f;
      return true;
    }
    Vec3f m = m_ggx.sample_visible(lo, u);
    Vec3f li = reflect(lo, m);
    if (li.z <= 0.f) return false;
    Vec3f wi = normalize(sided_to_world(f, side, li));
    // The pdf and the weight come from evaluate() on (wo, wi), exactly as eval() and pdf()
    // compute them (half vector recomputed from the two directions). Mathematically the
    // weight is F G2 / G1(wo) (Heitz & d'Eon 2014, "Importance Sampling Microfacet-Based
    // BSDFs using the Distribution of Visible Normals": D and the cosines cancel), but that
    // separate expression differed from eval() / pdf() by up to 1e-4 (relative, measured)
    // for grazing wi, where G2 ~ 1 / Lambda(wi) ~ wi.z amplifies rounding differences.
    Color fv;
    float pdf;
    if (!evaluate(si, wo, wi, &fv, &pdf) || !(pdf > 0.f)) return false;
    out->wi = wi;
    out->pdf = pdf;
    out->weight = fv / pdf;
    out->flags = k_bsdf_glossy | k_bsdf_reflection;
    out->eta = 1.f;
    return true;
  }

  Color albedo(const SurfaceInteraction& si) const override { return fresnel(1.f) * tint(si); }

  uint32_t flags() const override { return (m_smooth ? k_bsdf_delta : k_bsdf_glossy) | k_bsdf_reflection; }
  uint32_t needs() const override {
    // Isotropic roughness does not depend on the tangent's direction (any frame around ns);
    // a 3D height needs no tangent either (bump_normal), a uv one does.
    bool uv_bump = m_bump && !m_bump->needs_position();
    return (m_ggx.ax != m_ggx.ay || uv_bump ? uint32_t(k_needs_tangent) : 0u) | texture_needs(*m_tint) |
           (m_bump ? texture_needs(*m_bump) : 0u);
  }

 private:
  /// sided_frame (microfacet.h) around the bump-mapped normal when there is a bump map: the
  /// tangent re-orthogonalized against it (anisotropy keeps following dpdu).
  bool sided(const SurfaceInteraction& si, const Vec3f& wo, Frame* f, float* side) const {
    if (!sided_frame(si, wo, f, side)) return false;
    if (m_bump) {
      Vec3f n = bump_normal(si, *m_bump, m_bump_scale);
      Vec3f t = si.dpdu - n * dot(n, si.dpdu);
      float tl = length(t);
      if (tl > 1e-6f && std::isfinite(tl)) {
        f->n = n;
        f->s = t / tl;
        f->t = cross(n, f->s);
      } else {
        *f = Frame(n);
      }
    }
    return true;
  }

  Color fresnel(float cos_i) const { return m_perfect ? Color(1.f) : fresnel_conductor(cos_i, m_eta, m_k); }
  Color tint(const SurfaceInteraction& si) const { return eval_texture(*m_tint, si); }

  /// f cos_i (returned in *f) and the sampling density (*pdf) of the rough lobe; false when
  /// (wo, wi) is not a valid reflection pair.
  /// NOTE: one out-of-line evaluation shared by eval(), pdf() and sample(): with FMA
  /// contraction (-march=native, GCC's default -ffp-contract=fast) the same expression
  /// inlined at two call sites may round differently, which grazing directions amplify to
  /// ~1e-4 relative (measured); a single copy of the code makes the three agree bit for bit.
  [[gnu::noinline]] bool evaluate(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi, Color* f,
                                  float* pdf) const {
    Vec3f lo, li;
    if (!local_pair(si, wo, wi, &lo, &li)) return false;
    Vec3f h = normalize(lo + li);
    // D and Lambda(wo) are shared by the BSDF and the density (computed once).
    const float d = m_ggx.D(h), lambda_o = m_ggx.lambda(lo), lambda_i = m_ggx.lambda(li);
    // NOTE: f = F D G2 / (4 cos_o cos_i) (Walter et al. 2007, eq. 20); times cos_i; G2 the
    // height-correlated 1 / (1 + Lambda(wo) + Lambda(wi)) (Heitz 2014, eq. 99).
    float dg = d / ((1.f + lambda_o + lambda_i) * (4.f * lo.z));
    // cos(wo, h) = cos(wi, h), symmetrized so that F is bitwise reciprocal (the float sum is
    // the same for (wo, wi) and (wi, wo)).
    *f = fresnel(0.5f * (dot(lo, h) + dot(li, h))) * tint(si) * dg;
    // Reflection through the distribution of visible normals: pdf(wi) = D_wo(h) / (4 wo.h)
    // with D_wo(h) = G1(wo) (wo.h) D(h) / wo.z, so the cosines cancel.
    // NOTE: Jacobian of the reflection half vector dh/dwi = 1 / (4 |wi.h|) (Walter et al.
    // 2007, eq. 14); D_wo as in Heitz 2018, eq. 1.
    *pdf = dot(lo, h) > 0.f ? d / ((1.f + lambda_o) * (4.f * lo.z)) : 0.f;
    return true;
  }

  /// Both directions in the (mirrored) local frame; false unless both lie on the side of
  /// wo, above the geometric and the shading surface.
  bool local_pair(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi, Vec3f* lo, Vec3f* li) const {
    Frame f;
    float side;
    if (!sided(si, wo, &f, &side)) return false;
    if (dot(si.ng, wi) * side <= 0.f) return false;
    *lo = sided_to_local(f, side, wo);
    *li = sided_to_local(f, side, wi);
    return lo->z > 0.f && li->z > 0.f;
  }

  Color m_eta, m_k;
  bool m_perfect;
  GGX m_ggx;
  bool m_smooth;
  std::shared_ptr<Texture> m_tint;
  std::shared_ptr<Texture> m_bump;  ///< height map (null: none)
  float m_bump_scale;
};

PluginInfo info() {
  std::vector<std::string> metals;
  for (const auto& p : k_metals) metals.push_back(p.name);
  metals.push_back(k_perfect_mirror);
  return PluginInfo("material", "conductor",
                    "Rough GGX metal with visible-normal sampling (Heitz 2018) and the exact complex-IOR Fresnel: "
                    "a measured metal preset or eta/k per channel, optionally anisotropic.")
      .add(param::choice("metal", "aluminium", metals,
                         "measured metal preset (none: a perfect mirror; not with eta/k)"))
      .add(param::color("eta", "real part of the complex IOR per channel (with k, instead of metal)").above(0).at_most(100))
      .add(param::color("k", "imaginary part (extinction) of the complex IOR per channel").in(0, 1000))
      .add(param::real("roughness", 0.3, "GGX roughness (alpha = roughness^2; 0: mirror)").in(0, 1))
      .add(param::real("anisotropy", 0.0, "stretches the highlight along the surface tangent").in(-1, 1))
      .add(param::real("roughness_u", 0.3, "roughness along the tangent (instead of roughness/anisotropy)").in(0, 1))
      .add(param::real("roughness_v", 0.3, "roughness along the bitangent").in(0, 1))
      .add(param::color_texture("specular_tint", Color(1.f), "multiplies the reflection").in(0, 1))
      .add(param::texture("bump_map", "height map (first channel)"))
      .add(param::real("bump_scale", 1.0, "height in uv units").in(-100, 100))
      .exclusive_of({"metal"}, {"eta", "k"})
      .requires_all("eta", {"k"})
      .requires_all("k", {"eta"})
      .exclusive_of({"roughness", "anisotropy"}, {"roughness_u", "roughness_v"});
}

std::shared_ptr<Material> create(const Params& params, const PluginContext& ctx) {
  // --- Complex index of refraction: a preset or explicit eta and k. ---
  Color eta(1.f), k(0.f);
  bool perfect = false;
  if (params.has("eta")) {
    eta = params.get_color("eta");
    k = params.get_color("k");
  } else {
    std::string metal = params.get_string("metal");
    for (const auto& p : k_metals)
      if (metal == p.name) {
        eta = p.eta;
        k = p.k;
      }
    perfect = metal == k_perfect_mirror;
  }

  // --- Roughness: isotropic + anisotropy, or per axis. ---
  float alpha_x, alpha_y;
  bool smooth;
  if (params.has("roughness_u") || params.has("roughness_v")) {
    float ru = params.get_float("roughness_u");
    float rv = params.get_float("roughness_v");
    alpha_x = roughness_to_alpha(ru);
    alpha_y = roughness_to_alpha(rv);
    smooth = ru < k_smooth_roughness && rv < k_smooth_roughness;
  } else {
    float r = params.get_float("roughness");
    float a = params.get_float("anisotropy");
    // NOTE: anisotropy as in Burley 2012, "Physically-Based Shading at Disney", addendum B.2:
    // aspect = sqrt(1 - 0.9 |a|), alpha_x = alpha / aspect, alpha_y = alpha * aspect;
    // positive values stretch the highlight along dpdu, negative ones swap the axes.
    float alpha = roughness_to_alpha(r), aspect = std::sqrt(1.f - 0.9f * std::fabs(a));
    alpha_x = alpha / aspect;
    alpha_y = alpha * aspect;
    if (a < 0.f) std::swap(alpha_x, alpha_y);
    smooth = r < k_smooth_roughness;
  }

  auto tint = color_texture_param(params, "specular_tint", ctx.textures);
  std::shared_ptr<Texture> bump = texture_param(params, "bump_map", ctx.textures);
  float bump_scale = params.get_float("bump_scale");
  return std::make_shared<ConductorMaterial>(eta, k, perfect, alpha_x, alpha_y, smooth, tint, bump, bump_scale);
}

}  // namespace

SG_REGISTER_PLUGIN(Material, info(), create)

}  // namespace sg
