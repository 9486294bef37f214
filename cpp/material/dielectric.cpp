// Material "dielectric": glass, water, plastic films. Fresnel-weighted reflection and
// refraction at an interface between the exterior (index `exterior_ior`, the side the
// normals point to) and the interior (`ior`); eta = ior / exterior_ior.
//
// * roughness 0 (below 1e-3): smooth interface, two Dirac lobes (mirror reflection and
//   Snell refraction) chosen with probability Fresnel R and 1 - R.
// * roughness > 0: GGX microfacet reflection and refraction (Walter et al. 2007) with
//   visible-normal sampling (Heitz 2018) and height-correlated Smith G2.
// * thin = true: a thin-walled slab (window pane, car glass) in the exterior medium on both
//   sides: light is reflected with the slab reflectance R' (multiple reflections inside the
//   slab summed) or passes straight through (wi = -wo, no bending, no change of medium).
//
// Conventions:
// * Radiance transport. synthgen traces paths from the camera, so sample() and eval() give
//   the adjoint of light transport for radiance: refraction into a medium of relative index
//   eta_t / eta_o (eta_t on the side of wi, eta_o on the side of wo) scales the BTDF by
//   (eta_o / eta_t)^2. NOTE: radiance is not conserved across a refractive interface
//   (L / eta^2 is), so the BTDF is not symmetric and radiance transport must use
//   f(wo, wi) = (eta_o / eta_t)^2 f*(wi, wo) (Veach 1997, "Robust Monte Carlo Methods for
//   Light Transport Simulation", sec. 5.2; pbrt-v4 sec. 9.5.2). Consequently
//   f(wo, wi) / eta_o^2 = f(wi, wo) / eta_t^2 (generalized reciprocity, Veach sec. 5.2), and
//   a smooth refraction sample has weight T (eta_o / eta_t)^2 / T = (eta_o / eta_t)^2.
//   Particle tracers (light paths) would need the unscaled BTDF; synthgen has none.
// * BsdfSample::eta of a refraction event is eta_t / eta_o (1 for reflection and for the
//   straight transmission of a thin slab); multiplying the weight by eta^2 undoes the radiance
//   scaling (e.g. for Russian roulette, as pbrt-v4's path integrator does with "etaScale").
// * Sides are judged on the geometric normal (which side wo is on decides entering or
//   exiting; reflection keeps wi on that side, refraction puts it on the other) and must
//   agree with the shading normal, so shading normals cannot leak light (Veach 1997,
//   sec. 5.3); otherwise eval/pdf are 0 and sample() fails.
// * `transmittance` multiplies every transmission event (once per interface crossing, so a
//   solid glass object is tinted twice); reflection is never tinted (a dielectric reflects
//   white). Lobe selection uses the Fresnel terms only.
#include <string>

#include "material/material.h"
#include "material/microfacet.h"

namespace sg {

namespace {

constexpr float k_smooth_roughness = 1e-3f;

/// Reflectance of a thin slab: the interface reflectance R plus all paths that enter,
/// bounce 2j+1 times inside and leave on the same side (T^2 R^(2j+1)); without absorption.
/// NOTE: R' = R + T^2 R / (1 - R^2) = 2R / (1 + R) with T = 1 - R (pbrt-v4, Pharr et al. 2023,
/// sec. 9.5.1 "Thin Dielectric BSDF"; Mitsuba 3 "thindielectric"). The unpolarized R is
/// summed, as in both references; summing the s and p polarizations separately would be more
/// accurate and gives up to 8% (relative) less R' for glass near Brewster's angle (cos 0.43).
inline float thin_slab_reflectance(float cos_i, float eta) {
  float r = fresnel_dielectric(cos_i, eta);
  return r < 1.f ? 2.f * r / (1.f + r) : 1.f;
}

/// Fresnel reflectance of a refraction pair whose two cosines with the (micro)normal are both
/// known: cos_i on the side of index 1, cos_t on the side of index eta (both positive).
/// NOTE: Fresnel equations (pbrt-v4 eq. 9.5) with cos_t taken from the refracted direction
/// instead of sqrt(1 - sin_i^2 / eta^2): the latter cancels catastrophically when the light
/// leaves the dense medium close to the critical angle (cos_t -> 0), and the two ends of a
/// pair would then disagree by up to 1e-2 (relative, measured); with both cosines the
/// expression is symmetric (r -> -r when the sides are swapped) and well conditioned.
inline float fresnel_dielectric_pair(float cos_i, float cos_t, float eta) {
  float r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return 0.5f * (r_parl * r_parl + r_perp * r_perp);
}

class DielectricMaterial final : public Material {
 public:
  DielectricMaterial(float eta, float alpha, bool smooth, bool thin, std::shared_ptr<Texture> transmittance)
      : m_eta(eta), m_ggx(alpha, alpha), m_smooth(smooth), m_thin(thin), m_transmittance(std::move(transmittance)) {}

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

  bool sample(const SurfaceInteraction& si, const Vec3f& wo, float u_lobe, const Vec2f& u,
              BsdfSample* out) const override {
    float side;
    Frame f;
    if (!sided_frame(si, wo, &f, &side)) return false;
    Vec3f lo = sided_to_local(f, side, wo);
    if (lo.z <= 0.f) return false;
    float eta = side > 0.f ? m_eta : 1.f / m_eta;  // eta_t / eta_o for a refraction
    Vec3f li;
    if (m_smooth) {
      float r, cos_t = 0.f;
      if (m_thin) r = thin_slab_reflectance(lo.z, m_eta);
      else r = fresnel_dielectric(lo.z, eta, &cos_t);
      if (u_lobe < r) {
        li = Vec3f(-lo.x, -lo.y, lo.z);
        out->weight = Color(1.f);
        out->pdf = r;  // discrete probability of the chosen Dirac lobe
        out->flags = k_bsdf_delta | k_bsdf_reflection;
        out->eta = 1.f;
      } else if (m_thin) {
        out->wi = -wo;  // exactly: the slab does not deflect
        out->weight = transmittance(si);
        out->pdf = 1.f - r;
        out->flags = k_bsdf_delta | k_bsdf_transmission;
        out->eta = 1.f;
        return true;
      } else {
        // NOTE: Snell's law in vector form (pbrt-v4 sec. 9.3, Refract()): wt = -wo / eta +
        // (cos_i / eta - cos_t) n, with cos_t from the Fresnel computation (sin_t = sin_i / eta).
        li = Vec3f(-lo.x / eta, -lo.y / eta, -cos_t);
        out->weight = transmittance(si) * (1.f / (eta * eta));
        out->pdf = 1.f - r;
        out->flags = k_bsdf_delta | k_bsdf_transmission;
        out->eta = eta;
      }
      Vec3f wi = normalize(sided_to_world(f, side, li));
      if (dot(si.ng, wi) * side * li.z <= 0.f) return false;  // geometric side must agree
      out->wi = wi;
      return true;
    }

    Vec3f m = m_ggx.sample_visible(lo, u);
    float co = dot(lo, m);
    if (!(co > 0.f)) return false;
    float r = m_thin ? thin_slab_reflectance(co, m_eta) : fresnel_dielectric(co, eta);
    if (u_lobe < r) {
      li = reflect(lo, m);
      if (li.z <= 0.f) return false;  // masked: the single-scattering model loses this energy
    } else if (m_thin) {
      // NOTE: a thin slab whose faces share the microfacet normal m displaces a ray but does
      // not deflect it: refraction in and out through parallel faces leaves the direction
      // unchanged, so transmission stays a Dirac lobe at -wo whatever the roughness and only
      // the reflection is blurred. Choosing it with probability 1 - R'(o.m) for m drawn from
      // the visible normals makes its discrete probability equal to its energy
      // E_m[1 - R'(o.m)], hence the weight is exactly the transmittance (no closed form for
      // that expectation is needed).
      Vec3f wi = -wo;
      out->wi = wi;
      out->weight = transmittance(si);
      out->pdf = 1.f - r;  // probability of this lobe given the sampled microfacet normal
      out->flags = k_bsdf_delta | k_bsdf_transmission;
      out->eta = 1.f;
      return true;
    } else {
      if (!refract(lo, m, eta, &li)) return false;  // cannot happen for r < 1
      if (li.z >= 0.f) return false;
    }
    // The pdf and weight come from evaluate() on (wo, wi) (the half vector recomputed from
    // the two directions), exactly as eval() and pdf() compute them.
    Vec3f wi = normalize(sided_to_world(f, side, li));
    Color fv;
    float pdf;
    if (!evaluate(si, wo, wi, &fv, &pdf) || !(pdf > 0.f)) return false;
    bool reflected = li.z > 0.f;
    out->wi = wi;
    out->pdf = pdf;
    out->weight = fv / pdf;
    out->flags = k_bsdf_glossy | (reflected ? k_bsdf_reflection : k_bsdf_transmission);
    out->eta = reflected ? 1.f : eta;
    return true;
  }

  /// A dielectric has no diffuse reflectance; as recommended for denoiser albedo features of
  /// specular surfaces, report the transmittance tint (1 for clear glass).
  Color albedo(const SurfaceInteraction& si) const override { return transmittance(si); }

  uint32_t needs() const override { return texture_needs(*m_transmittance); }
  uint32_t flags() const override {
    if (m_smooth) return k_bsdf_delta | k_bsdf_reflection | k_bsdf_transmission;
    if (m_thin) return k_bsdf_glossy | k_bsdf_reflection | k_bsdf_delta | k_bsdf_transmission;
    return k_bsdf_glossy | k_bsdf_reflection | k_bsdf_transmission;
  }

 private:
  /// A pair of directions in the local frame mirrored to the side of wo (wo.z > 0), with the
  /// (generalized) half vector h (h.z > 0) and eta = eta_t / eta_o.
  struct Local {
    Vec3f wo, wi, h;
    float eta;
    bool reflect;
  };

  Color transmittance(const SurfaceInteraction& si) const { return eval_texture(*m_transmittance, si); }


  bool make_local(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi, Local* l) const {
    Frame f;
    float side;
    if (!sided_frame(si, wo, &f, &side)) return false;
    float ci_g = dot(si.ng, wi) * side;
    if (ci_g == 0.f) return false;
    l->reflect = ci_g > 0.f;
    l->wo = sided_to_local(f, side, wo);
    l->wi = sided_to_local(f, side, wi);
    if (l->wo.z <= 0.f) return false;
    if (l->reflect ? l->wi.z <= 0.f : l->wi.z >= 0.f) return false;  // shading side must agree
    l->eta = side > 0.f ? m_eta : 1.f / m_eta;
    if (l->reflect) {
      l->h = normalize(l->wo + l->wi);
      return true;
    }
    if (m_thin) return true;  // straight transmission only: no half vector
    // NOTE: generalized half vector of refraction h = -(eta_o o + eta_t i) / |.| (Walter et
    // al. 2007, eq. 16), here o + eta i, turned to the upper hemisphere.
    Vec3f h = l->wo + l->wi * l->eta;
    float len = length(h);
    if (!(len > 0.f)) return false;
    h = h / len;
    if (h.z < 0.f) h = -h;
    l->h = h;
    // Refraction requires wo in front of the microfacet and wi behind it.
    return dot(l->wo, h) > 0.f && dot(l->wi, h) < 0.f;
  }

  /// f cos_i (*f) and the sampling density (*pdf) of the rough lobes; false when zero.
  /// NOTE: one out-of-line evaluation shared by eval(), pdf() and sample(): with FMA
  /// contraction (-march=native, GCC's default -ffp-contract=fast) the same expression
  /// inlined at two call sites may round differently, which grazing directions amplify to
  /// ~1e-4 relative (measured on the conductor); one copy of the code makes them agree exactly.
  [[gnu::noinline]] bool evaluate(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi, Color* f,
                                  float* pdf) const {
    Local l;
    if (!make_local(si, wo, wi, &l)) return false;
    if (l.reflect) {
      float c = reflection_cos(l);
      float fr = m_thin ? thin_slab_reflectance(c, m_eta) : fresnel_dielectric(c, l.eta);
      // NOTE: f_r = F D G2 / (4 cos_o cos_i) (Walter et al. 2007, eq. 20), times cos_i.
      *f = Color(fr * m_ggx.D(l.h) * m_ggx.G2(l.wo, l.wi) / (4.f * l.wo.z));
      *pdf = pdf_local(l);
      return true;
    }
    if (m_thin) return false;  // straight transmission is a Dirac lobe
    float co = dot(l.wo, l.h), ci = dot(l.wi, l.h);
    float ft = 1.f - fresnel_dielectric_pair(co, -ci, l.eta);
    float denom = ci + co / l.eta;
    // NOTE: Walter et al. 2007, eq. 21, with i = wi (index eta_i = eta_t here) and o = wo:
    // f_t = |i.h| |o.h| / (|i.n| |o.n|) eta_o^2 (1 - F) G2 D / (eta_i i.h + eta_o o.h)^2.
    // With eta = eta_i / eta_o the last factor is 1 / (eta^2 (i.h + o.h / eta)^2): Walter's
    // BTDF is the radiance form, carrying the 1 / eta^2 of the file header (Veach 1997,
    // sec. 5.2). Times |cos_i|:
    // f_t |cos_i| = (1 - F) D G2 |i.h| (o.h) / (cos_o (i.h + o.h / eta)^2) / eta^2.
    float v = ft * m_ggx.D(l.h) * m_ggx.G2(l.wo, l.wi) * std::fabs(ci) * co / (l.wo.z * denom * denom);
    *f = transmittance(si) * (v / (l.eta * l.eta));
    *pdf = pdf_local(l);
    return true;
  }

  /// cos(wo, h) = cos(wi, h) of a reflection pair, symmetrized: the float sum is the same for
  /// (wo, wi) and (wi, wo), so F is bitwise reciprocal. Close to the critical angle dF/dcos is
  /// unbounded and the ~1e-7 difference between the two dot products alone moved F by 1.5e-5
  /// (relative, measured).
  static float reflection_cos(const Local& l) { return 0.5f * (dot(l.wo, l.h) + dot(l.wi, l.h)); }

  float pdf_local(const Local& l) const {
    float co = dot(l.wo, l.h);
    if (l.reflect) {
      if (!(co > 0.f)) return 0.f;
      float c = reflection_cos(l);
      float r = m_thin ? thin_slab_reflectance(c, m_eta) : fresnel_dielectric(c, l.eta);
      // NOTE: dh/dwi = 1 / (4 |i.h|) for reflection (Walter et al. 2007, eq. 14).
      return r * m_ggx.pdf_visible(l.wo, l.h) / (4.f * co);
    }
    if (m_thin) return 0.f;
    float ci = dot(l.wi, l.h);
    float denom = ci + co / l.eta;
    // NOTE: dh/dwi = eta_t^2 |i.h| / (eta_o o.h + eta_t i.h)^2 for refraction (Walter et al.
    // 2007, eq. 17) = |i.h| / (i.h + o.h / eta)^2 with eta = eta_t / eta_o.
    float dh_dwi = std::fabs(ci) / (denom * denom);
    return (1.f - fresnel_dielectric_pair(co, -ci, l.eta)) * m_ggx.pdf_visible(l.wo, l.h) * dh_dwi;
  }

 public:
  int specular_events(const SurfaceInteraction&, SpecularEvent out[4]) const override {
    if (!m_ggx.sharp()) return 0;
    out[0] = SpecularEvent{};
    out[1] = SpecularEvent{true, m_thin ? 1.f : m_eta};
    return 2;
  }

 private:
  float m_eta;  ///< ior / exterior_ior
  GGX m_ggx;
  bool m_smooth, m_thin;
  std::shared_ptr<Texture> m_transmittance;
};

}  // namespace

namespace {

PluginInfo info() {
  return PluginInfo("material", "dielectric",
                    "Rough GGX glass (Walter et al. 2007), or a thin-walled slab (windows, car glass: no "
                    "bending, slab reflectance); refraction scales radiance by (eta_o / eta_t)^2.")
      .add(param::real("ior", 1.5, "index of refraction inside (must differ from exterior_ior unless thin)")
               .in(1, 10))
      .add(param::real("exterior_ior", 1.0, "index of refraction outside").in(1, 10))
      .add(param::real("roughness", 0.0, "GGX roughness (0: smooth glass)").in(0, 1))
      .add(param::boolean("thin", false, "thin-walled: no bending, slab reflectance"))
      .add(param::color_texture("transmittance", Color(1.f), "tint of the transmitted light").in(0, 1));
}

std::shared_ptr<Material> create(const Params& params, const PluginContext& ctx) {
  float ior = params.get_float("ior");
  float ext = params.get_float("exterior_ior");
  bool thin = params.get_bool("thin");
  // An index-matched interface is invisible (and its refraction half vector degenerate); a
  // thin slab of matched index is allowed (it transmits everything).
  if (!thin && std::fabs(ior - ext) < 1e-4f * ext)
    throw Error("parameters 'ior' and 'exterior_ior' must differ (an index-matched interface is invisible)");
  float roughness = params.get_float("roughness");
  auto transmittance = color_texture_param(params, "transmittance", ctx.textures);
  return std::make_shared<DielectricMaterial>(ior / ext, roughness_to_alpha(roughness),
                                              roughness < k_smooth_roughness, thin, transmittance);
}

}  // namespace

SG_REGISTER_PLUGIN(Material, info(), create)

}  // namespace sg
