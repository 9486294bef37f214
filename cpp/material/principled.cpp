// Material "principled": the glTF 2.0 metallic-roughness material (and Blender-style
// "Principled BSDF" controls): base colour, metallic, roughness, specular, clearcoat,
// transmission, emission, alpha, normal / bump maps.
//
// Model (cosines in the shading frame flipped to the side of wo; C = base colour,
// m = metallic, t = transmission, a = roughness^2, F_s(F0, c) = F0 + (1 - F0)(1 - c)^5 the
// Schlick Fresnel, NOTE: Schlick 1994, "An Inexpensive BRDF Model for Physically-based
// Rendering", eq. 15; glTF 2.0 spec appendix B.3.3/B.3.4):
//
//   f = f_cc + A_cc(wo) A_cc(wi) [ (1 - m)(1 - t) (f_spec + f_diff) + m f_metal + (1 - m) t f_glass ]
//
//  * f_metal = F_s(C, o.h) D G2 / (4 cos_o cos_i): GGX conductor whose F0 is the base
//    colour (glTF appendix B.3.4 "conductor_fresnel"; Burley 2012, "Physically-Based
//    Shading at Disney", sec. 5.5 metallic), height-correlated Smith G2 (Heitz 2014).
//  * f_spec = F_s(F0_d, o.h) D G2 / (4 cos_o cos_i), F0_d = 0.08 specular (Burley 2012,
//    sec. 5.5 "specular": 0.5 -> F0 = 0.04, the glTF dielectric F0 of ior 1.5).
//  * f_diff: a Lambertian base under the specular layer, coupled to it with the
//    directional albedo E_d(c) of f_spec (Kelemen & Szirmay-Kalos 2001, "A Microfacet
//    Based Coupled Specular-Matte BRDF Model with Importance Sampling", eq. matte term):
//        f_diff = C / pi (1 - E_d(cos_o)) (1 - E_d(cos_i)) / (1 - Ebar_d).
//    Its albedo is C (1 - E_d(cos_o)), so spec + diffuse = E_d + C (1 - E_d) <= 1, exactly 1
//    for white C (the white furnace; up to the ~1e-3 accuracy of the tables). glTF's
//    fresnel_mix (appendix B.3.5) weights the diffuse by 1 - F(V.H) instead, which gains
//    energy at grazing angles (up to ~1.9 at cos_o = 0.01), hence the coupled form.
//    E_d = F0_d A(c, a) + (1 - F0_d) B(c, a) with A = int D G2 / (4 cos_o) dwi and
//    B = int (1 - o.h)^5 D G2 / (4 cos_o) dwi: Schlick's F0 enters linearly, so two tables
//    cover every F0 (NOTE: the split-sum factorization of Karis 2013, "Real Shading in
//    Unreal Engine 4", sec. "Image based lighting", environment BRDF).
//  * f_glass: rough dielectric (Walter et al. 2007, "Microfacet Models for Refraction",
//    eq. 20/21) with the exact Fresnel of `ior`, refraction tinted by C (glTF
//    KHR_materials_transmission: "the base colour tints transmitted light"); radiance
//    form with the 1/eta^2 factor, as material "dielectric" (Veach 1997, sec. 5.2). The
//    surface is thin-less: a transmission event changes the medium (BsdfSample::eta).
//  * f_cc: clearcoat, F_s(0.04, o.h) D_cc G2_cc / (4 cos_o cos_i) times `clearcoat`
//    (glTF KHR_materials_clearcoat: ior 1.5, F0 = 0.04; Burley 2012 sec. 5.6). Light it
//    does not reflect passes it: A_cc(w) = 1 - clearcoat E_cc(cos w) on both directions
//    (symmetric, so reciprocal; albedo <= cc E_cc(o) + (1 - cc E_cc(o)) * 1 <= 1).
//
// Energy: every bracketed term has albedo <= 1 and the weights are convex, so the total
// albedo is <= 1 (+ table error). Reciprocity: every reflection term is symmetric (the
// Fresnel cosine is symmetrized); transmission is not (radiance scaling, as "dielectric").
// Sampling: one of clearcoat GGX / base GGX (spec + metal + glass share the visible-normal
// distribution of alpha) / cosine hemisphere / glass (GGX visible normal, then reflect or
// refract with probability F) is picked with probabilities proportional to the lobes'
// estimated directional albedos at wo; pdf() is the probability-weighted sum of all lobe
// densities and sample() returns f / pdf of the chosen direction (one-sample MIS, balance
// heuristic; Veach 1997, sec. 9.2.4). No Dirac lobes: roughness is clamped to >= 0.03
// (alpha >= 9e-4, a lobe a fraction of a degree wide).
//
// Two-sided for reflection (the frame is flipped to the side of wo); emission leaves the
// front face. albedo() reports the base colour for every metallic value (for metals it is
// the normal-incidence reflectance F0, the recommended denoiser albedo of a specular
// surface). alpha() is the coverage for alpha cut-outs (Material::has_alpha): `alpha_mode`
// "opaque" ignores it, "mask" cuts at `alpha_cutoff`, "blend" (the default) cuts at 0.5
// (glTF BLEND rendered as MASK 0.5: deterministic, labels stay exact).
#include <array>
#include <mutex>
#include <string>

#include "core/quadrature.h"
#include "core/sampling.h"
#include "material/material.h"
#include "material/microfacet.h"
#include "material/normal_mapping.h"

namespace sg {

namespace {

constexpr float k_min_roughness = 0.03f;
constexpr float k_clearcoat_f0 = 0.04f;

inline float schlick_weight(float c) {
  float x = std::min(std::max(1.f - c, 0.f), 1.f);
  float x2 = x * x;
  return x2 * x2 * x;
}


/// Directional albedo tables of the GGX reflection lobe with Schlick Fresnel:
/// E(c, r; F0) = F0 A(c, r) + (1 - F0) B(c, r), bilinear in (c^(1/4), roughness r) on a
/// 65 x 49 grid (the fourth root puts nodes densely near grazing, where shadowing makes E
/// vary on the scale of alpha), and the hemispherical averages Ebar = 2 int E c dc of the
/// interpolated rows (so that the coupled diffuse term integrates exactly to what eval()
/// returns).
class SchlickAlbedoTables {
 public:
  static constexpr int k_n = 64;   ///< intervals in c^(1/4)
  static constexpr int k_nr = 48;  ///< intervals in roughness

  SchlickAlbedoTables() {
    for (int j = 0; j <= k_nr; ++j) {
      float r = std::max(float(j) / k_nr, k_min_roughness);
      GGX ggx(roughness_to_alpha(r), roughness_to_alpha(r));
      for (int i = 0; i <= k_n; ++i) {
        double x = double(i) / k_n;
        integrate(ggx, x * x * x * x, &m_a[size_t(j)][size_t(i)], &m_b[size_t(j)][size_t(i)]);
      }
      // 2 int_0^1 E(c) c dc = int_0^1 8 E x^7 dx (c = x^4), E piecewise linear in x.
      static const GaussLegendre<4> gl;
      double sa = 0.0, sb = 0.0;
      for (int i = 0; i < k_n; ++i)
        for (int k = 0; k < 4; ++k) {
          double s = 0.5 * (gl.x[size_t(k)] + 1.0), x = (i + s) / k_n, w = 0.5 * gl.w[size_t(k)] / k_n;
          double a = m_a[size_t(j)][size_t(i)] * (1 - s) + m_a[size_t(j)][size_t(i + 1)] * s;
          double b = m_b[size_t(j)][size_t(i)] * (1 - s) + m_b[size_t(j)][size_t(i + 1)] * s;
          double x7 = x * x * x * x * x * x * x;
          sa += w * 8.0 * a * x7;
          sb += w * 8.0 * b * x7;
        }
      m_abar[size_t(j)] = float(sa);
      m_bbar[size_t(j)] = float(sb);
    }
  }

  /// E(c) and Ebar for roughness r and Schlick F0.
  void lookup(float c, float r, float f0, float* e, float* ebar) const {
    float fx = std::sqrt(std::sqrt(std::min(std::max(c, 0.f), 1.f))) * k_n;
    float fy = std::min(std::max(r, 0.f), 1.f) * k_nr;
    int i = std::min(int(fx), k_n - 1), j = std::min(int(fy), k_nr - 1);
    float s = fx - float(i), t = fy - float(j);
    auto bil = [&](const Table& m) {
      return (m[size_t(j)][size_t(i)] * (1 - s) + m[size_t(j)][size_t(i + 1)] * s) * (1 - t) +
             (m[size_t(j + 1)][size_t(i)] * (1 - s) + m[size_t(j + 1)][size_t(i + 1)] * s) * t;
    };
    *e = f0 * bil(m_a) + (1.f - f0) * bil(m_b);
    float abar = m_abar[size_t(j)] * (1 - t) + m_abar[size_t(j + 1)] * t;
    float bbar = m_bbar[size_t(j)] * (1 - t) + m_bbar[size_t(j + 1)] * t;
    *ebar = f0 * abar + (1.f - f0) * bbar;
  }

  static const SchlickAlbedoTables& get() {
    static const SchlickAlbedoTables tables;  // thread-safe initialization (C++11)
    return tables;
  }

 private:
  using Table = std::array<std::array<float, k_n + 1>, k_nr + 1>;

  /// A = int D_wo(m) G2/G1 dm and B = int D_wo(m) (1 - o.m)^5 G2/G1 dm over the visible
  /// normals. NOTE: as CoatAlbedoTable in coated.cpp: the visible-normal warp of Heitz 2018
  /// (JCGT 7(4), Listing 1) maps the unit disk uniformly onto D_wo; Gauss-Legendre in r,
  /// midpoint rule in phi over half the circle (symmetric about the plane of incidence).
  static void integrate(const GGX& ggx, double c, float* a_out, float* b_out) {
    c = std::max(c, 1e-6);
    Vec3f wo(float(std::sqrt(1.0 - c * c)), 0.f, float(c));
    float lambda_o = ggx.lambda(wo);
    constexpr int n_r = 24, n_phi = 32;
    static const GaussLegendre<n_r> gl;
    double sa = 0.0, sb = 0.0;
    for (int k = 0; k < n_r; ++k) {
      double r = 0.5 * (gl.x[size_t(k)] + 1.0);
      double ia = 0.0, ib = 0.0;
      for (int j = 0; j < n_phi; ++j) {
        double phi = -0.5 + (j + 0.5) / n_phi;
        double u_phi = phi * 0.5 < 0.0 ? phi * 0.5 + 1.0 : phi * 0.5;
        Vec3f m = ggx.sample_visible(wo, Vec2f(float(r * r), float(u_phi)));
        Vec3f wi = reflect(wo, m);
        if (wi.z <= 0.f) continue;
        double g = (1.0 + lambda_o) / (1.0 + lambda_o + ggx.lambda(wi));
        ia += g;
        ib += g * schlick_weight(dot(wo, m));
      }
      sa += gl.w[size_t(k)] * r * ia / n_phi;
      sb += gl.w[size_t(k)] * r * ib / n_phi;
    }
    *a_out = float(std::min(std::max(sa, 0.0), 1.0));
    *b_out = float(std::min(std::max(sb, 0.0), 1.0));
  }

  Table m_a{}, m_b{};
  std::array<float, k_nr + 1> m_abar{}, m_bbar{};
};

/// A scalar parameter: a constant, or the first (red) channel of a texture times `factor`.
struct ScalarInput {
  std::shared_ptr<Texture> tex;
  float value = 0.f;
  float eval(const SurfaceInteraction& si) const { return tex ? value * eval_texture(*tex, si).x : value; }
};

struct PrincipledParams {
  std::shared_ptr<Texture> base_color, emission, normal_map, bump_map, metallic_roughness;
  ScalarInput metallic, roughness, alpha;
  float specular = 0.5f, clearcoat = 0.f, clearcoat_roughness = 0.03f, transmission = 0.f, ior = 1.5f;
  float emission_strength = 1.f, normal_scale = 1.f, bump_scale = 1.f, alpha_cutoff = 0.5f, alpha_factor = 1.f;
  enum class AlphaMode { Opaque, Mask, Blend } alpha_mode = AlphaMode::Blend;
};

inline float clamp01(float x) { return std::min(std::max(x, 0.f), 1.f); }

class PrincipledMaterial final : public Material {
 public:
  explicit PrincipledMaterial(PrincipledParams p) : m_p(std::move(p)), m_tables(SchlickAlbedoTables::get()) {
    m_cc_alpha = roughness_to_alpha(std::max(m_p.clearcoat_roughness, k_min_roughness));
    m_emission_avg = m_p.emission->average() * m_p.emission_strength;
    m_emissive = !is_black(m_emission_avg);
    m_flags = k_bsdf_reflection | k_bsdf_glossy | k_bsdf_diffuse | (m_p.transmission > 0.f ? k_bsdf_transmission : 0u);
  }

  Color eval(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    Setup s;
    if (!setup(si, wo, &s)) return Color(0.f);
    Color f;
    float pdf;
    evaluate(s, wi, &f, &pdf);
    return f;
  }

  float pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    Setup s;
    if (!setup(si, wo, &s)) return 0.f;
    Color f;
    float pdf;
    evaluate(s, wi, &f, &pdf);
    return pdf;
  }

  Color eval_pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi, float* pdf_out) const override {
    *pdf_out = 0.f;
    Setup s;
    if (!setup(si, wo, &s)) return Color(0.f);
    Color f;
    evaluate(s, wi, &f, pdf_out);
    return f;
  }

  bool sample(const SurfaceInteraction& si, const Vec3f& wo, float u_lobe, const Vec2f& u,
              BsdfSample* out) const override {
    Setup s;
    if (!setup(si, wo, &s)) return false;
    Vec3f li;
    uint32_t flags = k_bsdf_glossy | k_bsdf_reflection;
    if (u_lobe < s.p_cc) {
      li = reflect(s.lo, GGX(m_cc_alpha, m_cc_alpha).sample_visible(s.lo, u));
    } else if ((u_lobe -= s.p_cc) < s.p_gloss) {
      li = reflect(s.lo, s.ggx.sample_visible(s.lo, u));
    } else if ((u_lobe -= s.p_gloss) < s.p_diff) {
      li = square_to_cosine_hemisphere(u);
      flags = k_bsdf_diffuse | k_bsdf_reflection;
    } else if (s.p_glass > 0.f) {
      u_lobe -= s.p_diff;
      // NOTE: reuse of the selection sample, rescaled to [0, 1) within the chosen interval
      // (pbrt-v4 SampleDiscrete's uRemapped, src/pbrt/util/sampling.h).
      float u_fresnel = std::min(u_lobe / s.p_glass, k_one_minus_epsilon);
      Vec3f m = s.ggx.sample_visible(s.lo, u);
      float co = dot(s.lo, m);
      if (!(co > 0.f)) return false;
      if (u_fresnel < fresnel_dielectric(co, s.eta)) {
        li = reflect(s.lo, m);
      } else {
        if (!refract(s.lo, m, s.eta, &li)) return false;
        flags = k_bsdf_glossy | k_bsdf_transmission;
      }
    } else {
      return false;
    }
    bool transmit = flags & k_bsdf_transmission;
    if (transmit ? li.z >= 0.f : li.z <= 0.f) return false;
    Vec3f wi = normalize(s.frame.to_world(Vec3f(li.x, li.y, li.z * s.side)));
    // eval and pdf of the final world direction, exactly as eval() and pdf() see it.
    Color f;
    float pdf;
    evaluate(s, wi, &f, &pdf);
    if (!(pdf > 0.f)) return false;
    out->wi = wi;
    out->pdf = pdf;
    out->weight = f / pdf;
    out->flags = flags;
    out->eta = transmit ? s.eta : 1.f;
    return true;
  }

  Color albedo(const SurfaceInteraction& si) const override { return eval_texture(*m_p.base_color, si); }
  uint32_t flags() const override { return m_flags; }

  Color emission(const SurfaceInteraction& si, const Vec3f& wo) const override {
    if (!m_emissive || dot(si.ng, wo) <= 0.f) return Color(0.f);
    return eval_texture(*m_p.emission, si) * m_p.emission_strength;
  }
  bool is_emissive() const override { return m_emissive; }
  Color average_emission() const override { return m_emission_avg; }

  /// Coverage: `alpha_factor` x the alpha texture (its alpha channel, or its first channel
  /// when it has none: eval_alpha_texture) or the scalar `alpha`. Point-sampled and using
  /// only si.uv, as the cut-out test inside traversal requires (Material::has_alpha).
  float alpha(const SurfaceInteraction& si) const override {
    if (m_p.alpha_mode == PrincipledParams::AlphaMode::Opaque) return 1.f;
    float a = m_p.alpha.tex ? eval_alpha_texture(*m_p.alpha.tex, si) : m_p.alpha.value;
    return clamp01(a * m_p.alpha_factor);
  }
  bool has_alpha() const override {
    if (m_p.alpha_mode == PrincipledParams::AlphaMode::Opaque) return false;
    return m_p.alpha.tex != nullptr || m_p.alpha.value * m_p.alpha_factor < alpha_cutoff();
  }
  /// glTF MASK: `alpha_cutoff`; BLEND is rendered as a cut-out at 0.5 (deterministic, so
  /// labels stay exact; stochastic transparency would make them noisy).
  float alpha_cutoff() const override {
    return m_p.alpha_mode == PrincipledParams::AlphaMode::Mask ? m_p.alpha_cutoff : 0.5f;
  }

 private:
  /// Everything that depends on wo only.
  struct Setup {
    SurfaceInteraction si;  ///< with the normal / bump map applied
    Frame frame;            ///< shading frame; local z is flipped by `side`
    float side = 1.f;       ///< +1 if wo is on the front (ng) side
    Vec3f lo;               ///< wo, local (z > 0)
    Color base;
    float metallic = 0.f, r = 0.5f, f0_d = 0.04f, eta = 1.5f;
    GGX ggx{0.25f, 0.25f};
    float e_d_o = 0.f, one_minus_ebar_d = 1.f, e_cc_o = 0.f;
    float w_spec = 0.f, w_metal = 0.f, w_glass = 0.f;  ///< weights of the base lobes
    float p_cc = 0.f, p_gloss = 0.f, p_diff = 0.f, p_glass = 0.f;
  };

  float cc_albedo(float c) const {
    float e, ebar;
    m_tables.lookup(c, std::max(m_p.clearcoat_roughness, k_min_roughness), k_clearcoat_f0, &e, &ebar);
    return e;
  }

  bool setup(const SurfaceInteraction& si_in, const Vec3f& wo, Setup* s) const {
    s->si = si_in;
    if (m_p.normal_map) apply_normal_map(&s->si, *m_p.normal_map, m_p.normal_scale);
    if (m_p.bump_map) apply_bump_map(&s->si, *m_p.bump_map, m_p.bump_scale);
    const SurfaceInteraction& si = s->si;
    float cg = dot(si.ng, wo);
    if (!(cg != 0.f)) return false;
    s->side = cg > 0.f ? 1.f : -1.f;
    s->frame = si.shading_frame();
    s->lo = s->frame.to_local(wo);
    s->lo.z *= s->side;
    if (s->lo.z <= 0.f) return false;  // below the shading horizon: black, like "coated"
    s->base = vmin(vmax(eval_texture(*m_p.base_color, si), Color(0.f)), Color(1.f));
    float metallic = m_p.metallic.eval(si), rough = m_p.roughness.eval(si);
    if (m_p.metallic_roughness) {
      // glTF 2.0 sec. 3.9.2: metalness in the blue channel, roughness in the green one.
      Color mr = eval_texture(*m_p.metallic_roughness, si);
      metallic *= mr.z;
      rough *= mr.y;
    }
    // Keep what this setup evaluated (textures, bump gradient) for the next call at this hit.
    si_in.tex_cache = si.tex_cache;
    s->metallic = clamp01(metallic);
    s->r = std::max(clamp01(rough), k_min_roughness);
    float alpha = roughness_to_alpha(s->r);
    s->ggx = GGX(alpha, alpha);
    s->f0_d = 0.08f * m_p.specular;
    s->eta = s->side > 0.f ? m_p.ior : 1.f / m_p.ior;
    float co = std::min(s->lo.z, 1.f), ebar;
    m_tables.lookup(co, s->r, s->f0_d, &s->e_d_o, &ebar);
    s->one_minus_ebar_d = 1.f - ebar;
    s->e_cc_o = m_p.clearcoat > 0.f ? m_p.clearcoat * cc_albedo(co) : 0.f;
    float t = m_p.transmission, m = s->metallic;
    s->w_spec = (1.f - m) * (1.f - t);
    s->w_metal = m;
    s->w_glass = (1.f - m) * t;
    // Lobe selection proportional to estimated directional albedos at wo.
    float lum = luminance(s->base);
    float e_metal, dummy;
    m_tables.lookup(co, s->r, lum, &e_metal, &dummy);
    float rest = 1.f - s->e_cc_o;
    float a_cc = s->e_cc_o;
    float a_gloss = rest * (s->w_spec * s->e_d_o + s->w_metal * e_metal);
    float a_diff = rest * s->w_spec * lum * (1.f - s->e_d_o);
    float a_glass = rest * s->w_glass;
    float total = a_cc + a_gloss + a_diff + a_glass;
    if (!(total > 0.f)) return true;  // black: eval 0, pdf 0
    s->p_cc = a_cc / total;
    s->p_gloss = a_gloss / total;
    s->p_diff = a_diff / total;
    s->p_glass = a_glass / total;
    return true;
  }

  /// f cos_i and pdf towards world direction wi.
  /// NOTE: one out-of-line evaluation shared by eval(), pdf() and sample() so that the three
  /// agree bit for bit (FMA contraction may round inlined copies differently; see
  /// conductor.cpp).
  [[gnu::noinline]] void evaluate(const Setup& s, const Vec3f& wi, Color* f, float* pdf) const {
    *f = Color(0.f);
    *pdf = 0.f;
    float cg = dot(s.si.ng, wi) * s.side;
    if (cg == 0.f) return;
    Vec3f li = s.frame.to_local(wi);
    li.z *= s.side;
    const Vec3f& lo = s.lo;
    float co = lo.z;
    if (cg > 0.f) {
      // --- Reflection (judged on the geometric normal and the shading normal: Veach 1997,
      // sec. 5.3, no light leaks). ---
      if (li.z <= 0.f) return;
      float ci = li.z;
      Vec3f h = normalize(lo + li);
      // Symmetrized cos(o, h) = cos(i, h): F is bitwise reciprocal.
      float oh = 0.5f * (dot(lo, h) + dot(li, h));
      if (!(oh > 0.f)) return;
      float ci1 = std::min(ci, 1.f);
      float att = 1.f;
      if (m_p.clearcoat > 0.f) {
        GGX cc(m_cc_alpha, m_cc_alpha);
        float e_cc_i = m_p.clearcoat * cc_albedo(ci1);
        att = (1.f - s.e_cc_o) * (1.f - e_cc_i);
        // NOTE: f_r cos_i = F D G2 / (4 cos_o) (Walter et al. 2007, eq. 20).
        float fcc = m_p.clearcoat * (k_clearcoat_f0 + (1.f - k_clearcoat_f0) * schlick_weight(oh)) * cc.D(h) *
                    cc.G2(lo, li) / (4.f * co);
        *f += Color(fcc);
        // NOTE: reflection pdf D_wo(h) / (4 o.h) (Heitz 2018, sec. 2; Walter et al. 2007, eq. 14).
        *pdf += s.p_cc * cc.pdf_visible(lo, h) / (4.f * dot(lo, h));
      }
      float dg = s.ggx.D(h) * s.ggx.G2(lo, li) / (4.f * co);
      float sw = schlick_weight(oh);
      Color base(0.f);
      if (s.w_spec > 0.f) {
        base += Color(s.w_spec * (s.f0_d + (1.f - s.f0_d) * sw) * dg);
        float e_d_i, ebar;
        m_tables.lookup(ci1, s.r, s.f0_d, &e_d_i, &ebar);
        // NOTE: coupled matte term (Kelemen & Szirmay-Kalos 2001), see the header.
        base += s.base * (s.w_spec * (1.f - s.e_d_o) * (1.f - e_d_i) / s.one_minus_ebar_d * ci * k_inv_pi);
      }
      if (s.w_metal > 0.f) base += (s.base + (Color(1.f) - s.base) * sw) * (s.w_metal * dg);
      float fr_glass = 0.f;
      if (s.w_glass > 0.f) {
        fr_glass = fresnel_dielectric(oh, s.eta);
        base += Color(s.w_glass * fr_glass * dg);
      }
      *f += base * att;
      float vis = s.ggx.pdf_visible(lo, h) / (4.f * dot(lo, h));
      *pdf += s.p_gloss * vis + s.p_diff * ci * k_inv_pi + s.p_glass * fr_glass * vis;
      return;
    }
    // --- Transmission (glass lobe only). ---
    if (!(s.w_glass > 0.f) || li.z >= 0.f) return;
    // NOTE: generalized half vector of refraction (Walter et al. 2007, eq. 16): o + eta i.
    Vec3f h = lo + li * s.eta;
    float len = length(h);
    if (!(len > 0.f)) return;
    h = h / len;
    if (h.z < 0.f) h = -h;
    float oh = dot(lo, h), ih = dot(li, h);
    if (!(oh > 0.f && ih < 0.f)) return;
    float fr = fresnel_dielectric(oh, s.eta);
    float denom = ih + oh / s.eta;
    float dg = s.ggx.D(h) * s.ggx.G2(lo, li);
    // NOTE: Walter et al. 2007, eq. 21, times |cos_i|, radiance form (1 / eta^2), exactly as
    // material "dielectric": (1 - F) D G2 |i.h| (o.h) / (cos_o (i.h + o.h / eta)^2) / eta^2.
    float v = (1.f - fr) * dg * std::fabs(ih) * oh / (co * denom * denom) / (s.eta * s.eta);
    float att = 1.f;
    if (m_p.clearcoat > 0.f) att = (1.f - s.e_cc_o) * (1.f - m_p.clearcoat * cc_albedo(std::min(-li.z, 1.f)));
    *f = s.base * (s.w_glass * v * att);
    // NOTE: dh/dwi = |i.h| / (i.h + o.h / eta)^2 (Walter et al. 2007, eq. 17).
    *pdf = s.p_glass * (1.f - fr) * s.ggx.pdf_visible(lo, h) * std::fabs(ih) / (denom * denom);
  }

 public:
  int specular_events(const SurfaceInteraction& si, SpecularEvent out[4]) const override {
    float rough = m_p.roughness.eval(si);
    if (m_p.metallic_roughness) rough *= eval_texture(*m_p.metallic_roughness, si).y;
    bool sharp = clamp01(rough) <= k_sharp_roughness;
    int n = 0;
    if (sharp || (m_p.clearcoat > 0.f && m_p.clearcoat_roughness <= k_sharp_roughness)) out[n++] = SpecularEvent{};
    if (sharp && m_p.transmission > 0.f) out[n++] = SpecularEvent{true, m_p.ior};
    return n;
  }

 private:
  PrincipledParams m_p;
  const SchlickAlbedoTables& m_tables;
  float m_cc_alpha;
  Color m_emission_avg;
  bool m_emissive = false;
  uint32_t m_flags;
};

/// A [0, 1] scalar or a texture (its red channel, as the "mix" weight).
ScalarInput scalar_input(const Params& params, const std::string& name, const PluginContext& ctx) {
  ScalarInput in;
  in.tex = texture_param(params, name, ctx.textures);
  in.value = in.tex ? 1.f : params.get_float(name);
  return in;
}

PluginInfo info() {
  return PluginInfo("material", "principled",
                    "glTF 2.0 metallic-roughness / Principled BSDF: Schlick GGX metal and GGX specular over a "
                    "coupled Lambertian base, clear coat, rough transmission, emission, normal and bump maps, "
                    "alpha cut-outs.")
      .add(param::color_texture("base_color", Color(0.8f), "base colour (F0 of metals)").in(0, 1))
      .add(param::float_texture("metallic", 0.0, "metalness (texture: its first channel)").in(0, 1))
      .add(param::float_texture("roughness", 0.5, "GGX roughness, clamped to >= 0.03 (texture: its first channel)")
               .in(0, 1))
      .add(param::texture("metallic_roughness",
                          "glTF packed texture: metallic = blue x metallic, roughness = green x roughness"))
      .add(param::real("specular", 0.5, "dielectric F0 = 0.08 specular").in(0, 1))
      .add(param::real("clearcoat", 0.0, "clear coat strength").in(0, 1))
      .add(param::real("clearcoat_roughness", 0.03, "clear coat roughness").in(0, 1))
      .add(param::real("transmission", 0.0, "rough glass fraction, tinted by base_color").in(0, 1))
      .add(param::real("ior", 1.5, "index of refraction (transmission)").in(1.01, 3))
      .add(param::color_texture("emission", Color(0.f), "emitted radiance (front face)").at_least(0))
      .add(param::real("emission_strength", 1.0, "multiplies emission").in(0, 1e6))
      .add(param::texture("normal_map", "tangent-space normal map (glTF convention, +Y up; linear)"))
      .add(param::real("normal_scale", 1.0, "scales the normal map's X and Y").in(-10, 10))
      .add(param::texture("bump_map", "height map (first channel)"))
      .add(param::real("bump_scale", 1.0, "height in uv units").in(-100, 100))
      .add(param::float_texture("alpha", 1.0, "coverage (texture: its alpha channel, else the first)").in(0, 1))
      .add(param::real("alpha_factor", 1.0, "multiplies alpha").in(0, 1))
      .add(param::choice("alpha_mode", "blend", {"opaque", "mask", "blend"}, "glTF alpha mode (blend: cut-out at 0.5)"))
      .add(param::real("alpha_cutoff", 0.5, "coverage threshold of the mask mode").in(0, 1));
}

std::shared_ptr<Material> create(const Params& params, const PluginContext& ctx) {
  PrincipledParams p;
  p.base_color = color_texture_param(params, "base_color", ctx.textures);
  p.metallic = scalar_input(params, "metallic", ctx);
  p.roughness = scalar_input(params, "roughness", ctx);
  p.metallic_roughness = texture_param(params, "metallic_roughness", ctx.textures);
  p.specular = params.get_float("specular");
  p.clearcoat = params.get_float("clearcoat");
  p.clearcoat_roughness = params.get_float("clearcoat_roughness");
  p.transmission = params.get_float("transmission");
  p.ior = params.get_float("ior");
  p.emission = color_texture_param(params, "emission", ctx.textures);
  p.emission_strength = params.get_float("emission_strength");
  p.normal_map = texture_param(params, "normal_map", ctx.textures);
  p.normal_scale = params.get_float("normal_scale");
  p.bump_map = texture_param(params, "bump_map", ctx.textures);
  p.bump_scale = params.get_float("bump_scale");
  p.alpha = scalar_input(params, "alpha", ctx);
  p.alpha_factor = params.get_float("alpha_factor");
  p.alpha_cutoff = params.get_float("alpha_cutoff");
  std::string mode = params.get_string("alpha_mode");
  p.alpha_mode = mode == "opaque" ? PrincipledParams::AlphaMode::Opaque
                 : mode == "mask" ? PrincipledParams::AlphaMode::Mask
                                  : PrincipledParams::AlphaMode::Blend;
  return std::make_shared<PrincipledMaterial>(std::move(p));
}

}  // namespace

SG_REGISTER_PLUGIN(Material, info(), create)

}  // namespace sg
