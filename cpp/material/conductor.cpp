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

#include "material/material_registry.h"
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

std::string float_range_error(const std::string& name, float v, const char* range) {
  return "parameter '" + name + "' = " + std::to_string(v) + " is out of range; allowed: " + range;
}

float get_unit_float(const ParamSet& params, const std::string& name, float def, float lo) {
  float v = params.get_float(name, def);
  if (!(v >= lo && v <= 1.f))
    throw Error(float_range_error(name, v, lo == 0.f ? "[0, 1]" : "[-1, 1]"));
  return v;
}

}  // namespace

std::shared_ptr<Material> create_conductor_material(const ParamSet& params, const MaterialContext& ctx) {
  // --- Complex index of refraction: a preset or explicit eta and k. ---
  bool has_metal = params.has("metal"), has_eta = params.has("eta"), has_k = params.has("k");
  if (has_metal && (has_eta || has_k))
    throw Error("parameters 'metal' and 'eta'/'k' are exclusive: give a metal preset or a complex IOR");
  if (has_eta != has_k) throw Error(std::string("parameter '") + (has_eta ? "k" : "eta") +
                                    "' is required together with '" + (has_eta ? "eta" : "k") + "'");
  Color eta(1.f), k(0.f);
  bool perfect = false;
  if (has_eta) {
    eta = params.get_color("eta", Color(1.f));
    k = params.get_color("k", Color(0.f));
    for (int c = 0; c < 3; ++c) {
      if (!(eta[c] > 0.f && eta[c] <= 100.f))
        throw Error("parameter 'eta': components must lie in (0, 100], got " + std::to_string(eta[c]));
      if (!(k[c] >= 0.f && k[c] <= 1000.f))
        throw Error("parameter 'k': components must lie in [0, 1000], got " + std::to_string(k[c]));
    }
  } else {
    std::string metal = params.get_string("metal", "aluminium");
    std::vector<std::string> names;
    bool found = false;
    for (const auto& p : k_metals) {
      names.push_back(p.name);
      if (metal == p.name) {
        eta = p.eta;
        k = p.k;
        found = true;
      }
    }
    names.push_back(k_perfect_mirror);
    if (metal == k_perfect_mirror) found = perfect = true;
    if (!found) {
      std::string guess = closest_match(metal, names), list;
      for (size_t i = 0; i < names.size(); ++i) list += (i ? ", " : "") + names[i];
      throw Error("parameter 'metal': unknown metal '" + metal + "'" +
                  (guess.empty() ? "" : " (did you mean '" + guess + "'?)") + "; allowed: " + list);
    }
  }

  // --- Roughness: isotropic + anisotropy, or per axis. ---
  float alpha_x, alpha_y;
  bool smooth;
  if (params.has("roughness_u") || params.has("roughness_v")) {
    if (params.has("roughness") || params.has("anisotropy"))
      throw Error("parameters 'roughness_u'/'roughness_v' and 'roughness'/'anisotropy' are exclusive");
    float ru = get_unit_float(params, "roughness_u", 0.3f, 0.f);
    float rv = get_unit_float(params, "roughness_v", 0.3f, 0.f);
    alpha_x = roughness_to_alpha(ru);
    alpha_y = roughness_to_alpha(rv);
    smooth = ru < k_smooth_roughness && rv < k_smooth_roughness;
  } else {
    float r = get_unit_float(params, "roughness", 0.3f, 0.f);
    float a = get_unit_float(params, "anisotropy", 0.f, -1.f);
    // NOTE: anisotropy as in Burley 2012, "Physically-Based Shading at Disney", addendum B.2:
    // aspect = sqrt(1 - 0.9 |a|), alpha_x = alpha / aspect, alpha_y = alpha * aspect;
    // positive values stretch the highlight along dpdu, negative ones swap the axes.
    float alpha = roughness_to_alpha(r), aspect = std::sqrt(1.f - 0.9f * std::fabs(a));
    alpha_x = alpha / aspect;
    alpha_y = alpha * aspect;
    if (a < 0.f) std::swap(alpha_x, alpha_y);
    smooth = r < k_smooth_roughness;
  }

  auto tint = get_color_texture(params, "specular_tint", Color(1.f), ctx.textures);
  Color avg = tint->average();
  if (avg.x < 0.f || avg.y < 0.f || avg.z < 0.f || max_component(avg) > 1.f)
    throw Error("parameter 'specular_tint': components must lie in [0, 1]");
  std::shared_ptr<Texture> bump;
  TextureRef ref;
  if (params.get_texture("bump_map", &ref)) {
    bump = ctx.textures ? ctx.textures(ref.id) : nullptr;
    if (!bump) throw Error("parameter 'bump_map': texture " + std::to_string(ref.id) + " does not exist");
  }
  float bump_scale = params.get_float("bump_scale", 1.f);
  if (!(bump_scale >= -100.f && bump_scale <= 100.f)) throw Error("parameter 'bump_scale': must lie in [-100, 100]");
  return std::make_shared<ConductorMaterial>(eta, k, perfect, alpha_x, alpha_y, smooth, tint, bump, bump_scale);
}

}  // namespace sg
