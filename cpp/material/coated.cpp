// Material "coated": a clear dielectric coat (smooth or GGX-rough) over a Lambertian
// base: plastic, car paint, varnished wood, glazed ceramics.
//
// Model (all cosines in the shading frame, eta = `ior`, rho = base `albedo`, s = `specular`):
//
//  * Coat reflection. Smooth coat: a mirror (Dirac) lobe of mass s F(cos_o), F the
//    unpolarized dielectric Fresnel reflectance. Rough coat: the microfacet reflection
//    BRDF of Walter et al. 2007, "Microfacet Models for Refraction", sec. 4 (eq. 20)
//        f_s = s F(wo.h) D(h) G2(wo, wi) / (4 cos_o cos_i)
//    with GGX D and the height-correlated Smith G2 (material/microfacet.h).
//    E(cos) = integral of f_s cos_i (s = 1) over the hemisphere is the coat's directional
//    albedo; for the smooth coat E = F.
//  * Base. Light the coat does not reflect, T(cos) = 1 - E(cos), enters the coat and hits
//    the Lambertian base; of the diffuse light travelling up inside the coat the fraction
//    Tbar / eta^2 escapes (Tbar = 2 int_0^1 T(c) c dc), the rest, F_int = 1 - Tbar / eta^2,
//    is reflected back down. Summing the inter-reflections (rho F_int)^k gives
//        f_d = rho / (1 - rho F_int) * T(cos_i) T(cos_o) / (pi eta^2),
//    the 1/eta^2 being the radiance compression of light leaving a denser medium.
//    For a smooth coat this is exactly Mitsuba 0.6's "plastic" with nonlinear = true
//    (Jakob 2010, Mitsuba 0.6 documentation, plugin "plastic"): F_int is then the internal
//    diffuse Fresnel reflectance F_dr,int, and 1 - F_dr,int = (1 - F_dr,ext) / eta^2
//    because Fresnel transmittance is the same on both sides of an interface while
//    cos dw shrinks by 1 / eta^2 under refraction (Veach 1997, sec. 5.2). F_dr,ext is
//    integrated numerically from its definition (smooth_tbar) rather than taken from the
//    polynomial fit of Egan & Hilgeman 1973, so that the model is exactly lossless. For a
//    rough coat, attenuating the base with 1 - E instead of 1 - F is the coupling of
//    Kelemen & Szirmay-Kalos 2001, "A Microfacet Based Coupled Specular-Matte BRDF Model
//    with Importance Sampling" (their matte term (1 - a(wi))(1 - a(wo)) / (1 - abar)):
//    whatever the single-scattering microfacet lobe does not
//    reflect -- including the energy a single-scattering model loses at high roughness --
//    enters the base. (Mitsuba's "roughplastic" attenuates with the tabulated rough
//    transmittance instead, which loses that energy.)
//  * Energy. With rho = 1 and s = 1 the directional albedo is s E + T = 1 for every
//    incident direction: a white base under a clear coat is lossless, up to the accuracy
//    of the tabulated E (max error ~1e-3, see CoatAlbedoTable) for rough coats. With
//    rho < 1 the albedo is s E + T rho (Tbar/eta^2) / (1 - rho F_int); s < 1 removes
//    (1 - s) E (absorbed, an artistic control).
//  * Reciprocity. f_s and f_d are both symmetric in (wo, wi).
//  * Sampling. The coat lobe is chosen with probability s E(cos_o) / (s E(cos_o) +
//    T(cos_o) lum(diffuse albedo)), i.e. proportional to the lobes' directional albedos;
//    a rough coat samples GGX visible normals, the base the cosine hemisphere. pdf() is
//    the selection-weighted sum of both lobes' pdfs and sample() returns
//    (f_s + f_d) cos / pdf (one-sample MIS over the lobes, balance heuristic; Veach 1997,
//    sec. 9.2.4). A smooth coat's mirror sample has flags k_bsdf_delta, pdf = its
//    selection probability and weight = s F(cos_o) / that probability; eval() and pdf()
//    describe the base only.
//
// The material is two-sided (both faces are coated) and reflects only.
#include <array>
#include <map>
#include <mutex>

#include "core/quadrature.h"
#include "core/sampling.h"
#include "material/lambert.h"
#include "material/material.h"
#include "material/microfacet.h"

namespace sg {

namespace {

/// NOTE: coats with alpha below 1e-3 are treated as perfectly smooth, as pbrt-v4 does
/// (TrowbridgeReitzDistribution::EffectivelySmooth): such a lobe is a fraction of a degree
/// wide, indistinguishable from a mirror in an image, while its D (up to 1 / (pi alpha^2))
/// and pdf values become extreme; the mirror is exact and noise-free.
constexpr float k_smooth_alpha = 1e-3f;


/// Directional albedo E(cos) of a rough coat's reflection lobe (specular scale 1),
/// tabulated at construction and linearly interpolated.
///
/// The table is uniform in y(c) = (sqrt(c) + (1 + alpha) c / (c + alpha)) / 2, which maps
/// [0, 1] onto [0, 1] and places nodes densely near grazing, where E varies on the scale of
/// alpha (shadowing) and of sqrt(c) (Fresnel). With 64 intervals the interpolation error
/// stays below ~1e-3 for every roughness (checked against 64x128-point quadratures).
class CoatAlbedoTable {
 public:
  static constexpr int k_size = 64;

  CoatAlbedoTable(float alpha, float eta) : m_alpha(alpha) {
    GGX ggx(alpha, alpha);
    for (int i = 0; i <= k_size; ++i) m_e[size_t(i)] = float(directional_albedo(ggx, node(i), eta));
    // Tbar = 2 int_0^1 T(c) c dc of the interpolated T (so that the normalization of the
    // base matches what eval() integrates to), with 4-point Gauss-Legendre per interval;
    // T is smooth inside each interval.
    static const GaussLegendre<4> gl;
    double tbar = 0.0;
    for (int i = 0; i < k_size; ++i) {
      double c0 = node(i), c1 = node(i + 1);
      for (int k = 0; k < 4; ++k) {
        double c = c0 + (c1 - c0) * 0.5 * (gl.x[size_t(k)] + 1.0);
        tbar += (c1 - c0) * 0.5 * gl.w[size_t(k)] * 2.0 * c * (1.0 - double(lookup(float(c))));
      }
    }
    m_tbar = float(tbar);
  }

  float lookup(float c) const {
    float f = y(c) * float(k_size);
    int i = std::min(std::max(int(f), 0), k_size - 1);
    float t = std::min(std::max(f - float(i), 0.f), 1.f);
    return m_e[size_t(i)] * (1.f - t) + m_e[size_t(i + 1)] * t;
  }
  float tbar() const { return m_tbar; }

 private:
  float y(float c) const { return 0.5f * (std::sqrt(c) + (1.f + m_alpha) * c / (c + m_alpha)); }

  /// Cosine of table node i (y(c) = i / k_size), by bisection (y is increasing).
  double node(int i) const {
    if (i == 0) return 0.0;
    if (i == k_size) return 1.0;
    double target = double(i) / k_size, lo = 0.0, hi = 1.0, a = m_alpha;
    for (int it = 0; it < 60; ++it) {
      double m = 0.5 * (lo + hi);
      double ym = 0.5 * (std::sqrt(m) + (1.0 + a) * m / (m + a));
      (ym < target ? lo : hi) = m;
    }
    return 0.5 * (lo + hi);
  }

  /// E(c) = int f_s cos_i dwi, integrated over the visible normals of wo:
  /// E = int D_wo(m) F(wo.m) G2(wo, wi) / G1(wo) dm (wi = reflect(wo, m), wi.z > 0).
  /// NOTE: the visible-normal warp of Heitz 2018 (JCGT 7(4), Listing 1) maps the unit
  /// disk, uniformly, onto D_wo; the integral over the disk in polar coordinates uses
  /// Gauss-Legendre in r and the midpoint rule in phi over half the circle (the integrand
  /// is symmetric about the plane of incidence, phi -> pi - phi). G2 / G1 is written as
  /// (1 + Lambda_o) / (1 + Lambda_o + Lambda_i) so that it stays finite at grazing wo.
  static double directional_albedo(const GGX& ggx, double c, float eta) {
    c = std::max(c, 1e-6);
    Vec3f wo(float(std::sqrt(1.0 - c * c)), 0.f, float(c));
    float lambda_o = ggx.lambda(wo);
    constexpr int n_r = 24, n_phi = 24;
    static const GaussLegendre<n_r> gl;
    double sum = 0.0;
    for (int k = 0; k < n_r; ++k) {
      double r = 0.5 * (gl.x[size_t(k)] + 1.0);
      double inner = 0.0;
      for (int j = 0; j < n_phi; ++j) {
        double phi = -0.5 + (j + 0.5) / n_phi;  // in units of pi: [-pi/2, pi/2]
        double u_phi = phi * 0.5 < 0.0 ? phi * 0.5 + 1.0 : phi * 0.5;
        Vec3f m = ggx.sample_visible(wo, Vec2f(float(r * r), float(u_phi)));
        Vec3f wi = reflect(wo, m);
        if (wi.z <= 0.f) continue;
        float lambda_i = ggx.lambda(wi);
        inner += double(fresnel_dielectric(dot(wo, m), eta)) * (1.0 + lambda_o) / (1.0 + lambda_o + lambda_i);
      }
      // (1/pi) int r dr dphi over the disk = sum_k w_k r_k (mean over phi), see above.
      sum += gl.w[size_t(k)] * r * inner / n_phi;
    }
    return std::min(std::max(sum, 0.0), 1.0);
  }

  float m_alpha;
  float m_tbar = 1.f;
  std::array<float, k_size + 1> m_e{};
};

/// Tables are shared between materials with the same (alpha, eta): building one costs
/// ~2 ms, and scenes (or per-frame update_material calls) repeat parameters.
std::shared_ptr<const CoatAlbedoTable> coat_albedo_table(float alpha, float eta) {
  static std::mutex mutex;
  static std::map<std::pair<float, float>, std::shared_ptr<const CoatAlbedoTable>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& t = cache[{alpha, eta}];
  if (!t) t = std::make_shared<const CoatAlbedoTable>(alpha, eta);
  return t;
}

/// 1 - F_dr,ext = 2 int_0^1 (1 - F(c)) c dc for a smooth coat, by composite Gauss-Legendre.
double smooth_tbar(float eta) {
  static const GaussLegendre<8> gl;
  constexpr int n_seg = 32;
  double sum = 0.0;
  for (int s = 0; s < n_seg; ++s)
    for (int k = 0; k < 8; ++k) {
      double c = (s + 0.5 * (gl.x[size_t(k)] + 1.0)) / n_seg;
      sum += 0.5 * gl.w[size_t(k)] / n_seg * 2.0 * c * (1.0 - double(fresnel_dielectric(float(c), eta)));
    }
  return sum;
}

class CoatedMaterial final : public Material {
 public:
  CoatedMaterial(std::shared_ptr<Texture> albedo, float eta, float alpha, float specular)
      : m_albedo(std::move(albedo)), m_eta(eta), m_ggx(alpha, alpha), m_specular(specular) {
    m_smooth = alpha < k_smooth_alpha;
    // ior = 1: no interface, hence no coat at all (E = 0, Tbar = 1); the Fresnel terms
    // would otherwise be float rounding noise (1 - (1 - c^2) cancels at grazing c).
    m_invisible = eta == 1.f;
    float tbar;
    if (m_invisible) {
      tbar = 1.f;
    } else if (m_smooth) {
      tbar = float(smooth_tbar(eta));
    } else {
      m_table = coat_albedo_table(alpha, eta);
      tbar = m_table->tbar();
    }
    m_inv_eta2 = 1.f / (eta * eta);
    m_escape = tbar * m_inv_eta2;
    m_f_int = 1.f - m_escape;
  }

  Color eval(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    Setup s;
    if (!setup(si, wo, &s)) return Color(0.f);
    Color f;
    float pdf;
    eval_pdf(s, si, wi, &f, &pdf);
    return f;
  }

  float pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    Setup s;
    if (!setup(si, wo, &s)) return 0.f;
    Color f;
    float pdf;
    eval_pdf(s, si, wi, &f, &pdf);
    return pdf;
  }

  Color eval_pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi, float* pdf_out) const override {
    *pdf_out = 0.f;
    Setup s;
    if (!setup(si, wo, &s)) return Color(0.f);
    Color f;
    eval_pdf(s, si, wi, &f, pdf_out);
    return f;
  }

  bool sample(const SurfaceInteraction& si, const Vec3f& wo, float u_lobe, const Vec2f& u,
              BsdfSample* out) const override {
    Setup s;
    if (!setup(si, wo, &s)) return false;
    bool coat = u_lobe < s.p_coat;
    Vec3f wi;
    if (coat && m_smooth) {
      wi = s.frame.to_world(Vec3f(-s.wo.x, -s.wo.y, s.wo.z));
      if (dot(si.ng, wi) * s.side <= 0.f) return false;
      out->wi = wi;
      out->pdf = s.p_coat;
      out->weight = Color(m_specular * s.e_o / s.p_coat);
      out->flags = k_bsdf_delta | k_bsdf_reflection;
      out->eta = 1.f;
      return true;
    }
    Vec3f wi_local;
    if (coat) {
      wi_local = reflect(s.wo, m_ggx.sample_visible(s.wo, u));
    } else {
      wi_local = square_to_cosine_hemisphere(u);
    }
    if (wi_local.z <= 0.f) return false;
    wi = s.frame.to_world(wi_local);
    // eval and pdf of the final world direction, exactly as eval() and pdf() see it.
    Color f;
    float pdf;
    eval_pdf(s, si, wi, &f, &pdf);
    if (!(pdf > 0.f)) return false;
    out->wi = wi;
    out->pdf = pdf;
    out->weight = f / pdf;
    out->flags = (coat ? k_bsdf_glossy : k_bsdf_diffuse) | k_bsdf_reflection;
    out->eta = 1.f;
    return true;
  }

  Color albedo(const SurfaceInteraction& si) const override { return eval_texture(*m_albedo, si); }

  uint32_t needs() const override { return texture_needs(*m_albedo); }
  uint32_t flags() const override {
    return k_bsdf_diffuse | k_bsdf_reflection | (m_smooth ? k_bsdf_delta : k_bsdf_glossy);
  }

 private:
  /// Quantities that depend on wo only.
  struct Setup {
    Frame frame;  ///< around the shading normal flipped to the side of wo
    Vec3f wo;     ///< local
    float side;
    Color rho, base;  ///< base albedo and rho / (1 - rho F_int)
    float e_o;        ///< coat albedo E(cos_o)
    float p_coat;     ///< probability of sampling the coat lobe
  };

  /// Coat albedo E(c): Fresnel for a smooth coat, the table for a rough one.
  float coat_albedo(float c) const {
    if (m_invisible) return 0.f;
    return m_smooth ? fresnel_dielectric(c, m_eta) : m_table->lookup(c);
  }

  bool setup(const SurfaceInteraction& si, const Vec3f& wo, Setup* s) const {
    Vec3f n;
    if (!lambert::oriented_normal(si, wo, &n, &s->side)) return false;
    s->frame = Frame(n);
    s->wo = s->frame.to_local(wo);
    if (s->wo.z <= 0.f) return false;  // below the shading horizon: black, like Mitsuba 3
    // Texture values above 1 (an image `scale`) are clamped: the inter-reflection series
    // sum (rho F_int)^k must converge.
    s->rho = vmin(vmax(eval_texture(*m_albedo, si), Color(0.f)), Color(1.f));
    for (int k = 0; k < 3; ++k) s->base[k] = s->rho[k] / (1.f - s->rho[k] * m_f_int);
    s->e_o = coat_albedo(std::min(s->wo.z, 1.f));
    float w_coat = m_specular * s->e_o;
    float w_base = (1.f - s->e_o) * m_escape * luminance(s->base);
    float total = w_coat + w_base;
    s->p_coat = total > 0.f ? w_coat / total : 0.f;
    return true;
  }

  /// eval (f cos_i) and pdf of the non-delta lobes towards world direction wi.
  void eval_pdf(const Setup& s, const SurfaceInteraction& si, const Vec3f& wi, Color* f, float* pdf) const {
    *f = Color(0.f);
    *pdf = 0.f;
    // NOTE: reflection only, judged on the geometric normal too (Veach 1997, sec. 5.3),
    // as for the diffuse material.
    if (dot(si.ng, wi) * s.side <= 0.f) return;
    Vec3f wi_l = s.frame.to_local(wi);
    float ci = wi_l.z, co = s.wo.z;
    if (ci <= 0.f) return;
    float t_i = 1.f - coat_albedo(std::min(ci, 1.f)), t_o = 1.f - s.e_o;
    *f = s.base * (t_i * t_o * ci * m_inv_eta2 * k_inv_pi);
    *pdf = (1.f - s.p_coat) * ci * k_inv_pi;
    if (!m_smooth && s.p_coat > 0.f) {
      Vec3f h = normalize(s.wo + wi_l);
      float oh = dot(s.wo, h);
      if (oh <= 0.f) return;
      float d = m_ggx.D(h);
      // f_s cos_i = s F D G2 / (4 cos_o) (Walter et al. 2007, eq. 20).
      float fs = m_specular * fresnel_dielectric(oh, m_eta) * d * m_ggx.G2(s.wo, wi_l) / (4.f * co);
      *f += Color(fs);
      // NOTE: pdf of the reflected direction = D_wo(h) / (4 wo.h): the visible-normal
      // density (Heitz 2018, JCGT 7(4), sec. 2; GGX::pdf_visible) times the reflection
      // Jacobian dw_h / dw_i = 1 / (4 |wo.h|) (Walter et al. 2007, eq. 14).
      *pdf += s.p_coat * m_ggx.pdf_visible(s.wo, h) / (4.f * oh);
    }
  }

 public:
  int specular_events(const SurfaceInteraction&, SpecularEvent out[4]) const override {
    if (m_invisible || !(m_specular > 0.f) || !m_ggx.sharp()) return 0;
    out[0] = SpecularEvent{};
    return 1;
  }

 private:
  std::shared_ptr<Texture> m_albedo;
  float m_eta;
  GGX m_ggx;
  float m_specular;
  bool m_smooth, m_invisible;
  std::shared_ptr<const CoatAlbedoTable> m_table;
  float m_inv_eta2, m_escape, m_f_int;
};

}  // namespace

namespace {

PluginInfo info() {
  return PluginInfo("material", "coated",
                    "Plastic and car paint: a rough dielectric coat over a Lambertian base, energy-conserving "
                    "layering (Kelemen & Szirmay-Kalos 2001).")
      .add(param::color_texture("albedo", Color(0.5f), "Lambertian base reflectance").in(0, 1))
      .add(param::real("ior", 1.5, "index of refraction of the coat (1: no coat)").in(1, 4))
      .add(param::real("roughness", 0.0, "coat roughness (GGX alpha = roughness^2; 0: smooth)").in(0, 1))
      .add(param::real("specular", 1.0, "scales the coat reflection (the rest is absorbed)").in(0, 1));
}

std::shared_ptr<Material> create(const Params& params, const PluginContext& ctx) {
  auto albedo = color_texture_param(params, "albedo", ctx.textures);
  float ior = params.get_float("ior");
  float roughness = params.get_float("roughness");
  float specular = params.get_float("specular");
  return std::make_shared<CoatedMaterial>(albedo, ior, roughness_to_alpha(roughness), specular);
}

}  // namespace

SG_REGISTER_PLUGIN(Material, info(), create)

}  // namespace sg
