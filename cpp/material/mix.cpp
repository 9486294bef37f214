// Material "mix": the linear blend (1 - w) A + w B of two existing materials, given by id
// (`material_a`, `material_b`). The weight w (the fraction of B) is a constant `weight`
// in [0, 1] or, when `weight` is a texture reference, a mask: the mask value is the
// texture's first (red) channel at the hit (eval_texture: si.uv filtered over the ray
// footprint), clamped to [0, 1]. The first
// channel rather than the luminance, so that a grey mask image reads back its stored value
// exactly and a mask can be packed into one channel of an RGB texture.
//
//   eval = (1 - w) eval_A + w eval_B,  pdf = (1 - w) pdf_A + w pdf_B,
//   emission = (1 - w) emission_A + w emission_B,  albedo = (1 - w) albedo_A + w albedo_B.
//
// sample() picks B with probability w using u_lobe, and reuses u_lobe, rescaled to [0, 1),
// for the component's own lobe choice. A non-delta sample returns
// eval_mix / pdf_mix (one-sample MIS over the components with the balance heuristic,
// Veach 1997, sec. 9.2.4): pdf_mix is the exact density of the non-delta directions the
// mix generates, since each component's pdf() is the density of its own non-delta samples.
// A delta sample of the chosen component keeps its weight (mass / probability of the
// component's delta event) and its pdf is multiplied by the component's selection
// probability: the delta event's mass in the mix is w_c * mass and its probability w_c * p.
// Where w is exactly 0 or 1 the mix forwards every call to the single component, so a
// mask that is mostly 0 or 1 (wear, rust patches) costs what the component costs.
//
// `stochastic` (false): at hits of secondary rays (not at camera-ray hits, which always
// blend exactly, so that directly seen surfaces show no selection noise), instead of
// evaluating both components where 0 < w < 1, one is chosen per shading point -- B with
// probability w -- and eval, pdf and sample are that component's alone. The choice is a
// hash of the point, the outgoing direction and the mix's nesting depth (not its id, which
// depends on what was created before), so every call at one hit (light sampling, BSDF sampling, MIS) sees the
// same component, and renders are deterministic. Unbiased (the expectation over the
// choice is the blend), at the price of some noise in indirect light where the mask is
// fractional; it halves the shading cost there (band-limited wear masks are fractional at
// most indirect hits, whose wide footprints filter the mask to its mean).
// albedo() and emission() stay the exact blend.
// NOTE: pbrt-v4's MixMaterial always selects stochastically (src/pbrt/materials.h,
// MixMaterial::ChooseMaterial, with HashFloat(p, wo, material pointers)).
//
// Materials are looked up when the mix is created (MaterialContext::materials): the mix
// holds the component objects, so ids must exist before the mix (no cycles are possible).
#include <algorithm>
#include <cstring>

#include "core/error.h"
#include "core/rng.h"
#include "material/material.h"

namespace sg {

namespace {

class MixMaterial final : public Material {
 public:
  MixMaterial(std::shared_ptr<Material> a, std::shared_ptr<Material> b, float weight,
              std::shared_ptr<Texture> mask, bool stochastic)
      : m_a(std::move(a)), m_b(std::move(b)), m_weight(weight), m_mask(std::move(mask)), m_stochastic(stochastic) {
    m_depth = 1 + std::max(m_a->mix_depth(), m_b->mix_depth());
    m_salt = mix64(uint64_t(m_depth));
    m_flags = m_a->flags() | m_b->flags();
    m_emissive = m_a->is_emissive() || m_b->is_emissive();
    m_mean_weight = m_mask ? clamp01(m_mask->average().x) : m_weight;
  }

  Color eval(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    float w = weight(si);
    if (w <= 0.f) return m_a->eval(si, wo, wi);
    if (w >= 1.f) return m_b->eval(si, wo, wi);
    if (m_stochastic && !si.primary) return choose(si, wo, w)->eval(si, wo, wi);
    return m_a->eval(si, wo, wi) * (1.f - w) + m_b->eval(si, wo, wi) * w;
  }

  float pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const override {
    float w = weight(si);
    if (w <= 0.f) return m_a->pdf(si, wo, wi);
    if (w >= 1.f) return m_b->pdf(si, wo, wi);
    if (m_stochastic && !si.primary) return choose(si, wo, w)->pdf(si, wo, wi);
    return m_a->pdf(si, wo, wi) * (1.f - w) + m_b->pdf(si, wo, wi) * w;
  }

  Color eval_pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi, float* pdf_out) const override {
    float w = weight(si);
    if (w <= 0.f) return m_a->eval_pdf(si, wo, wi, pdf_out);
    if (w >= 1.f) return m_b->eval_pdf(si, wo, wi, pdf_out);
    if (m_stochastic && !si.primary) return choose(si, wo, w)->eval_pdf(si, wo, wi, pdf_out);
    float pa, pb;
    Color fa = m_a->eval_pdf(si, wo, wi, &pa), fb = m_b->eval_pdf(si, wo, wi, &pb);
    *pdf_out = pa * (1.f - w) + pb * w;
    return fa * (1.f - w) + fb * w;
  }

  bool sample(const SurfaceInteraction& si, const Vec3f& wo, float u_lobe, const Vec2f& u,
              BsdfSample* out) const override {
    float w = weight(si);
    if (w <= 0.f) return m_a->sample(si, wo, u_lobe, u, out);
    if (w >= 1.f) return m_b->sample(si, wo, u_lobe, u, out);
    if (m_stochastic && !si.primary) return choose(si, wo, w)->sample(si, wo, u_lobe, u, out);
    bool pick_b = u_lobe < w;
    const Material* chosen = pick_b ? m_b.get() : m_a.get();
    const Material* other = pick_b ? m_a.get() : m_b.get();
    float w_chosen = pick_b ? w : 1.f - w, w_other = 1.f - w_chosen;
    // NOTE: reuse of the selection sample: u_lobe rescaled within the chosen interval is
    // again uniform on [0, 1) (as pbrt-v4's SampleDiscrete returns uRemapped,
    // src/pbrt/util/sampling.h), clamped below 1 against rounding.
    float u_rest = pick_b ? u_lobe / w : (u_lobe - w) / (1.f - w);
    u_rest = std::min(std::max(u_rest, 0.f), k_one_minus_epsilon);
    if (!chosen->sample(si, wo, u_rest, u, out)) return false;
    if (out->flags & k_bsdf_delta) {
      out->pdf *= w_chosen;
      return true;
    }
    // The chosen component's eval and pdf are weight * pdf and pdf (sample() returns
    // weight = eval / pdf), so only the other component is evaluated.
    float other_pdf;
    Color other_f = other->eval_pdf(si, wo, out->wi, &other_pdf);
    Color f = out->weight * (out->pdf * w_chosen) + other_f * w_other;
    float pdf = out->pdf * w_chosen + other_pdf * w_other;
    if (!(pdf > 0.f)) return false;
    out->weight = f / pdf;
    out->pdf = pdf;
    return true;
  }

  Color albedo(const SurfaceInteraction& si) const override {
    float w = weight(si);
    if (w <= 0.f) return m_a->albedo(si);
    if (w >= 1.f) return m_b->albedo(si);
    return m_a->albedo(si) * (1.f - w) + m_b->albedo(si) * w;
  }

  uint32_t flags() const override { return m_flags; }
  int mix_depth() const override { return m_depth; }
  /// Cut-outs pass through: the mix is a surface where every component that has an alpha
  /// map is opaque (a wear layer over a cut-out sign does not fill its holes). Independent
  /// of the mask, which may need more than uv (the traversal-time test has uv only).
  bool has_alpha() const override { return m_a->has_alpha() || m_b->has_alpha(); }
  float alpha(const SurfaceInteraction& si) const override {
    return (m_a->alpha_opaque(si) && m_b->alpha_opaque(si)) ? 1.f : 0.f;
  }
  float alpha_cutoff() const override { return 0.5f; }
  uint32_t needs() const override {
    return m_a->needs() | m_b->needs() | (m_mask ? texture_needs(*m_mask) : 0u);
  }

  Color emission(const SurfaceInteraction& si, const Vec3f& wo) const override {
    if (!m_emissive) return Color(0.f);
    float w = weight(si);
    Color e(0.f);
    if (w < 1.f && m_a->is_emissive()) e += m_a->emission(si, wo) * (1.f - w);
    if (w > 0.f && m_b->is_emissive()) e += m_b->emission(si, wo) * w;
    return e;
  }
  bool is_emissive() const override { return m_emissive; }
  /// Mean emission for light power estimates, with the mean mask value.
  Color average_emission() const override {
    return m_a->average_emission() * (1.f - m_mean_weight) + m_b->average_emission() * m_mean_weight;
  }
  bool two_sided_emission() const override {
    return (m_a->is_emissive() && m_a->two_sided_emission()) || (m_b->is_emissive() && m_b->two_sided_emission());
  }

 private:
  static float clamp01(float x) { return std::min(std::max(x, 0.f), 1.f); }
  float weight(const SurfaceInteraction& si) const {
    return m_mask ? clamp01(eval_texture(*m_mask, si).x) : m_weight;
  }
  /// The stochastic mode's component at (si.p, wo): B with probability w.
  const Material* choose(const SurfaceInteraction& si, const Vec3f& wo, float w) const {
    auto bits = [](float x) {
      uint32_t b;
      std::memcpy(&b, &x, sizeof(b));
      return uint64_t(b);
    };
    uint64_t h = mix64(m_salt ^ (bits(si.p.x) | bits(si.p.y) << 32));
    h = mix64(h ^ (bits(si.p.z) | bits(wo.x) << 32));
    h = mix64(h ^ (bits(wo.y) | bits(wo.z) << 32));
    return bits_to_unit_float(uint32_t(h >> 32)) < w ? m_b.get() : m_a.get();
  }

 public:
  /// Both components' sharp lobes (each once).
  int specular_events(const SurfaceInteraction& si, SpecularEvent out[4]) const override {
    SpecularEvent a[4], b[4];
    int na = m_a->specular_events(si, a), nb = m_b->specular_events(si, b), n = 0;
    for (int i = 0; i < na + nb; ++i) {
      const SpecularEvent& e = i < na ? a[i] : b[i - na];
      bool seen = false;
      for (int j = 0; j < n; ++j) seen = seen || (out[j].refract == e.refract && out[j].eta == e.eta);
      if (!seen && n < 4) out[n++] = e;
    }
    return n;
  }

 private:
  std::shared_ptr<Material> m_a, m_b;
  float m_weight;
  std::shared_ptr<Texture> m_mask;
  float m_mean_weight;
  bool m_stochastic;
  int m_depth;       ///< nesting depth (1 + the components')
  uint64_t m_salt;   ///< from the depth: a chain of nested mixes chooses independently
  uint32_t m_flags;
  bool m_emissive;
};

std::shared_ptr<Material> get_component(const Params& params, const std::string& name, const PluginContext& ctx) {
  int64_t id = params.get_int(name);
  std::shared_ptr<Material> m;
  if (id >= 0 && id <= int64_t(UINT32_MAX) && ctx.materials) m = ctx.materials(uint32_t(id));
  if (!m)
    throw Error("parameter '" + name + "': material " + std::to_string(id) +
                " does not exist (must be the id of an existing material)");
  return m;
}

PluginInfo info() {
  return PluginInfo("material", "mix",
                    "The linear blend (1 - w) A + w B of two existing materials, w a constant or a mask texture "
                    "(its first channel); one-sample MIS over the components.")
      .add(param::material("material_a", "material used where weight = 0"))
      .add(param::material("material_b", "material used where weight = 1"))
      .add(param::float_texture("weight", 0.5, "fraction of material_b (a texture: its first channel)").in(0, 1))
      .add(param::boolean("stochastic", false,
                          "where 0 < weight < 1, shade secondary hits with one material chosen per point "
                          "(probability = weight) instead of both: cheaper, a little noisier"));
}

std::shared_ptr<Material> create(const Params& params, const PluginContext& ctx) {
  auto a = get_component(params, "material_a", ctx);
  auto b = get_component(params, "material_b", ctx);
  std::shared_ptr<Texture> mask = texture_param(params, "weight", ctx.textures);
  float weight = mask ? 0.5f : params.get_float("weight");
  bool stochastic = params.get_bool("stochastic");
  return std::make_shared<MixMaterial>(std::move(a), std::move(b), weight, std::move(mask), stochastic);
}

}  // namespace

SG_REGISTER_PLUGIN(Material, info(), create)

}  // namespace sg
