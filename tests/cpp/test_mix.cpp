// Material "mix" (material/mix.cpp), created through sg::create_material.
#include <gtest/gtest.h>

#include <map>

#include "core/error.h"
#include "material/microfacet.h"
#include "material_checks.h"

using namespace sg;
using namespace sgtest;

namespace {

/// Quadrature tolerance of the expected chi-square counts (see check_sampling_with_deltas).
constexpr double k_glossy_cell_eps = 1e-7;

/// Texture whose first channel is uv.x (the mask value), the others distractors.
class UvTexture final : public Texture {
 public:
  Color eval(const Vec2f& uv, float) const override { return Color(uv.x, 0.9f, 0.1f); }
  Color average() const override { return Color(0.5f, 0.9f, 0.1f); }
};

/// A small material library: ids 0.. as added, texture 5 is a UvTexture.
struct Library {
  std::map<uint32_t, std::shared_ptr<Material>> materials;
  std::shared_ptr<Texture> mask = std::make_shared<UvTexture>();

  MaterialContext context() const {
    MaterialContext ctx;
    ctx.textures = [this](uint32_t id) -> std::shared_ptr<Texture> { return id == 5 ? mask : nullptr; };
    ctx.materials = [this](uint32_t id) -> std::shared_ptr<Material> {
      auto it = materials.find(id);
      return it == materials.end() ? nullptr : it->second;
    };
    return ctx;
  }
  uint32_t add(const std::string& type, const ParamSet& p) {
    uint32_t id = uint32_t(materials.size());
    materials[id] = create_material(type, p, context(), "material " + std::to_string(id));
    return id;
  }
  uint32_t add_diffuse(const Color& albedo) {
    ParamSet p;
    p.set("albedo", std::vector<double>{albedo.x, albedo.y, albedo.z});
    return add("diffuse", p);
  }
  uint32_t add_coated(const Color& albedo, double roughness) {
    ParamSet p;
    p.set("albedo", std::vector<double>{albedo.x, albedo.y, albedo.z});
    p.set("roughness", roughness);
    return add("coated", p);
  }
  std::shared_ptr<Material> mix(uint32_t a, uint32_t b, ParamSet::Value weight, bool stochastic = false) {
    ParamSet p;
    p.set("material_a", int64_t(a));
    p.set("material_b", int64_t(b));
    p.set("weight", weight);
    if (stochastic) p.set("stochastic", true);
    return create_material("mix", p, context(), "material 9");
  }
  std::string error_of(const ParamSet& p) const {
    try {
      create_material("mix", p, context(), "material 9");
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
};

double fresnel_d(double cos_i, double eta) {
  double s2 = (1.0 - cos_i * cos_i) / (eta * eta);
  double ct = std::sqrt(1.0 - s2);
  double rs = (cos_i - eta * ct) / (cos_i + eta * ct), rp = (eta * cos_i - ct) / (eta * cos_i + ct);
  return 0.5 * (rs * rs + rp * rp);
}

bool same_sample(const BsdfSample& x, const BsdfSample& y) {
  return x.wi == y.wi && x.weight == y.weight && x.pdf == y.pdf && x.flags == y.flags && x.eta == y.eta;
}

/// `mat` samples exactly as `ref` for the same random numbers (success and sample).
void expect_same_sampling(const Material& mat, const Material& ref, const SurfaceInteraction& si, const Vec3f& wo,
                          float u_lobe, const Vec2f& u) {
  BsdfSample s_mat, s_ref;
  ASSERT_EQ(mat.sample(si, wo, u_lobe, u, &s_mat), ref.sample(si, wo, u_lobe, u, &s_ref));
  if (ref.sample(si, wo, u_lobe, u, &s_ref)) {
    ASSERT_TRUE(same_sample(s_mat, s_ref));
  }
}

}  // namespace

TEST(mix, weight_zero_equals_a_and_weight_one_equals_b) {
  // Exactly (bitwise): the mix forwards to the single component.
  Library lib;
  uint32_t a = lib.add_diffuse(Color(0.2f, 0.5f, 0.8f)), b = lib.add_coated(Color(0.7f), 0.3);
  auto mat_a = lib.materials[a], mat_b = lib.materials[b];
  auto mix0 = lib.mix(a, b, 0.0), mix1 = lib.mix(a, b, 1.0);
  Pcg32 rng(301);
  for (int i = 0; i < 10000; ++i) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(random_unit(rng)), wi = to_f(random_unit(rng));
    ASSERT_EQ(mix0->eval(si, wo, wi), mat_a->eval(si, wo, wi));
    ASSERT_EQ(mix0->pdf(si, wo, wi), mat_a->pdf(si, wo, wi));
    ASSERT_EQ(mix1->eval(si, wo, wi), mat_b->eval(si, wo, wi));
    ASSERT_EQ(mix1->pdf(si, wo, wi), mat_b->pdf(si, wo, wi));
    float u_lobe = rng.next_float();
    Vec2f u = rng.next_2d();
    ASSERT_NO_FATAL_FAILURE(expect_same_sampling(*mix0, *mat_a, si, wo, u_lobe, u));
    ASSERT_NO_FATAL_FAILURE(expect_same_sampling(*mix1, *mat_b, si, wo, u_lobe, u));
    ASSERT_EQ(mix0->albedo(si), mat_a->albedo(si));
    ASSERT_EQ(mix1->albedo(si), mat_b->albedo(si));
  }
  EXPECT_EQ(mix0->flags(), mat_a->flags() | mat_b->flags());
}

TEST(mix, blend_is_linear) {
  Library lib;
  uint32_t a = lib.add_diffuse(Color(0.2f, 0.5f, 0.8f)), b = lib.add_coated(Color(0.9f, 0.1f, 0.4f), 0.0);
  auto mat_a = lib.materials[a], mat_b = lib.materials[b];
  auto mix = lib.mix(a, b, 0.3);
  Pcg32 rng(302);
  for (int i = 0; i < 10000; ++i) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(random_unit(rng)), wi = to_f(random_unit(rng));
    Color ea = mat_a->eval(si, wo, wi), eb = mat_b->eval(si, wo, wi), em = mix->eval(si, wo, wi);
    for (int k = 0; k < 3; ++k) ASSERT_NEAR(em[k], 0.7 * ea[k] + 0.3 * eb[k], 1e-6 * (ea[k] + eb[k]) + 1e-9);
    double pa = mat_a->pdf(si, wo, wi), pb = mat_b->pdf(si, wo, wi);
    ASSERT_NEAR(mix->pdf(si, wo, wi), 0.7 * pa + 0.3 * pb, 1e-6 * (pa + pb) + 1e-9);
  }
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  Color al = mix->albedo(si);
  EXPECT_NEAR(al.x, 0.7 * 0.2 + 0.3 * 0.9, 1e-6);
  EXPECT_NEAR(al.y, 0.7 * 0.5 + 0.3 * 0.1, 1e-6);
  EXPECT_NEAR(al.z, 0.7 * 0.8 + 0.3 * 0.4, 1e-6);
  EXPECT_EQ(mix->flags(), uint32_t(k_bsdf_diffuse | k_bsdf_delta | k_bsdf_reflection));
  EXPECT_FALSE(mix->is_emissive());
  EXPECT_TRUE(is_black(mix->emission(si, Vec3f(0, 0, 1))));
}

// Chi-square tests: 3 (rough coat) + 2 (smooth coat, with delta cell) = 5 (see chi2.h).
TEST(mix, diffuse_and_rough_coated_sample_matches_pdf_chi2) {
  // One-sample MIS over components; also catches a u_lobe that is not remapped (the
  // coat's lobe choice would then correlate with the component choice).
  Library lib;
  uint32_t a = lib.add_diffuse(Color(0.8f, 0.4f, 0.2f)), b = lib.add_coated(Color(0.3f, 0.5f, 0.6f), 0.45);
  auto mix = lib.mix(a, b, 0.35);
  Pcg32 rng(303);
  uint64_t seed = 6000;
  for (double c : {0.9, 0.3, 0.02}) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    auto deltas = check_sampling_with_deltas(*mix, si, wo, seed++, "diffuse + rough coated, cos(wo) = " +
                                             std::to_string(c), 1000000, k_glossy_cell_eps);
    EXPECT_TRUE(deltas.empty());
  }
}

TEST(mix, diffuse_and_smooth_coated_sample_matches_pdf_chi2_with_delta) {
  // The delta lobe of the coat appears in the mix with mass w * F(cos_o) and is drawn
  // with the probability the mix reports.
  Library lib;
  uint32_t a = lib.add_diffuse(Color(0.5f)), b = lib.add_coated(Color(0.2f, 0.6f, 0.3f), 0.0);
  const double w = 0.6;
  auto mix = lib.mix(a, b, w);
  Pcg32 rng(304);
  uint64_t seed = 6100;
  for (double c : {0.8, 0.04}) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    std::string what = "diffuse + smooth coated, cos(wo) = " + std::to_string(c);
    auto deltas = check_sampling_with_deltas(*mix, si, wo, seed++, what);
    ASSERT_EQ(deltas.size(), 1u) << what;
    double f = fresnel_d(std::fabs(ddot(to_d(si.ns), to_d(wo))), 1.5);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(deltas[0].mass[k], w * f, 1e-4 * w * f + 1e-6) << what;
    // The component's delta probability times the component's selection probability.
    BsdfSample bs;
    ASSERT_TRUE(lib.materials[b]->sample(si, wo, 0.f, Vec2f(0.5f, 0.5f), &bs));
    EXPECT_NEAR(deltas[0].probability, w * bs.pdf, 1e-6) << what;
  }
}

// Stochastic selection: at each (point, wo) every call is the chosen component's, exactly;
// B is chosen with probability w (binomial bound); averaged over points the mix is the blend;
// nested mixes choose independently.
TEST(mix, stochastic_selection_is_one_component_chosen_with_probability_w) {
  Library lib;
  uint32_t a = lib.add_diffuse(Color(0.2f, 0.5f, 0.8f)), b = lib.add_coated(Color(0.9f, 0.1f, 0.4f), 0.3);
  auto mat_a = lib.materials[a], mat_b = lib.materials[b];
  const double w = 0.3;
  auto mix = lib.mix(a, b, w, true);
  Pcg32 rng(311);
  const int n = 40000;
  int n_b = 0;
  double sum_mix = 0, sum_blend = 0;
  for (int i = 0; i < n; ++i) {
    DVec3 nrm = random_unit(rng);
    SurfaceInteraction si = make_si(nrm, nrm);
    si.p = Vec3f(rng.next_float(), rng.next_float(), rng.next_float()) * 10.f;
    Vec3f wo = to_f(direction_at_cos(nrm, 0.2 + 0.8 * rng.next_float(), rng)), wi = to_f(random_unit(rng));
    // Which component was chosen: a probe direction above the surface, where the two differ.
    Vec3f probe = to_f(direction_at_cos(nrm, 0.7, rng));
    Color pm = mix->eval(si, wo, probe), pa = mat_a->eval(si, wo, probe), pb = mat_b->eval(si, wo, probe);
    ASSERT_FALSE(pa == pb);
    ASSERT_TRUE(pm == pa || pm == pb) << "the mix returns one component's value";
    bool is_b = pm == pb;
    const Material* chosen = is_b ? mat_b.get() : mat_a.get();
    Color em = mix->eval(si, wo, wi);
    Color ea = mat_a->eval(si, wo, wi), eb = mat_b->eval(si, wo, wi);
    ASSERT_EQ(em, chosen->eval(si, wo, wi));
    ASSERT_EQ(mix->pdf(si, wo, wi), chosen->pdf(si, wo, wi));
    float p_joint;
    ASSERT_EQ(mix->eval_pdf(si, wo, wi, &p_joint), chosen->eval(si, wo, wi));
    ASSERT_EQ(p_joint, chosen->pdf(si, wo, wi));
    float u_lobe = rng.next_float();
    Vec2f u = rng.next_2d();
    ASSERT_NO_FATAL_FAILURE(expect_same_sampling(*mix, *chosen, si, wo, u_lobe, u));
    n_b += is_b;
    sum_mix += em.x;
    sum_blend += (1 - w) * ea.x + w * eb.x;
    // albedo stays the exact blend.
    ASSERT_NEAR(mix->albedo(si).x, (1 - w) * mat_a->albedo(si).x + w * mat_b->albedo(si).x, 1e-6);
  }
  // 5 sigma of Binomial(n, w).
  double sigma = std::sqrt(n * w * (1 - w));
  EXPECT_NEAR(n_b, n * w, 5 * sigma) << "B chosen " << n_b << " of " << n;
  EXPECT_NEAR(sum_mix / sum_blend, 1.0, 0.03) << "the expectation over the choice is the blend";
  // Nested: mix(mix(A, B, 1/2), A', 1/2) picks the inner B a quarter of the time.
  uint32_t inner = uint32_t(lib.materials.size());
  lib.materials[inner] = lib.mix(a, b, 0.5, true);
  uint32_t c = lib.add_diffuse(Color(0.9f, 0.9f, 0.1f));
  auto outer = lib.mix(inner, c, 0.5, true);
  int n_inner_b = 0;
  const int m = 20000;
  for (int i = 0; i < m; ++i) {
    SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
    si.p = Vec3f(rng.next_float(), rng.next_float(), rng.next_float()) * 10.f;
    Vec3f wo(0.f, 0.f, 1.f), wi = normalize(Vec3f(0.3f, 0.1f, 1.f));
    ASSERT_FALSE(mat_b->eval(si, wo, wi) == mat_a->eval(si, wo, wi));
    n_inner_b += outer->eval(si, wo, wi) == mat_b->eval(si, wo, wi);
  }
  EXPECT_NEAR(n_inner_b, 0.25 * m, 5 * std::sqrt(m * 0.25 * 0.75)) << "nested mixes choose independently";
}

TEST(mix, texture_mask_uses_first_channel_at_uv) {
  Library lib;
  uint32_t a = lib.add_diffuse(Color(0.2f, 0.5f, 0.8f)), b = lib.add_coated(Color(0.9f), 0.3);
  auto mat_a = lib.materials[a], mat_b = lib.materials[b];
  auto mix = lib.mix(a, b, TextureRef{5});
  Pcg32 rng(305);
  for (float mask : {0.25f, 0.8f}) {
    for (int i = 0; i < 2000; ++i) {
      DVec3 n = random_unit(rng);
      SurfaceInteraction si = make_si(n, n);
      si.uv = Vec2f(mask, 0.4f);
      Vec3f wo = to_f(random_unit(rng)), wi = to_f(random_unit(rng));
      Color ea = mat_a->eval(si, wo, wi), eb = mat_b->eval(si, wo, wi), em = mix->eval(si, wo, wi);
      for (int k = 0; k < 3; ++k)
        ASSERT_NEAR(em[k], (1.0 - mask) * ea[k] + mask * eb[k], 1e-6 * (ea[k] + eb[k]) + 1e-9) << "mask " << mask;
      double pa = mat_a->pdf(si, wo, wi), pb = mat_b->pdf(si, wo, wi);
      ASSERT_NEAR(mix->pdf(si, wo, wi), (1.0 - mask) * pa + mask * pb, 1e-6 * (pa + pb) + 1e-9);
    }
  }
  // Mask values outside [0, 1] are clamped: exactly a or b.
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  Vec3f wo = normalize(Vec3f(0.3f, 0.1f, 0.9f)), wi = normalize(Vec3f(-0.2f, 0.3f, 0.7f));
  si.uv = Vec2f(-0.5f, 0.f);
  EXPECT_EQ(mix->eval(si, wo, wi), mat_a->eval(si, wo, wi));
  EXPECT_EQ(mix->albedo(si), mat_a->albedo(si));
  si.uv = Vec2f(1.5f, 0.f);
  si.tex_cache.clear();  // the point moved: texture values cached at the old uv are stale
  EXPECT_EQ(mix->eval(si, wo, wi), mat_b->eval(si, wo, wi));
  EXPECT_EQ(mix->albedo(si), mat_b->albedo(si));
  si.uv = Vec2f(0.5f, 0.f);
  si.tex_cache.clear();
  Color al = mix->albedo(si);
  EXPECT_NEAR(al.x, 0.5 * 0.2 + 0.5 * 0.9, 1e-6);
}

TEST(mix, reciprocity) {
  Library lib;
  uint32_t a = lib.add_diffuse(Color(0.3f, 0.6f, 0.9f)), b = lib.add_coated(Color(0.5f, 0.4f, 0.3f), 0.35);
  check_reciprocity(*lib.mix(a, b, 0.45), 306);
}

TEST(mix, white_furnace_with_delta_component) {
  // White diffuse mixed with a white smooth-coated material (both lossless): albedo 1 at
  // every angle, both by quadrature + delta mass and by the mean sample weight.
  Library lib;
  uint32_t a = lib.add_diffuse(Color(1.f)), b = lib.add_coated(Color(1.f), 0.0);
  auto mix = lib.mix(a, b, 0.4);
  Pcg32 rng(307);
  uint64_t seed = 6200;
  for (double c : {1.0, 0.4, 0.05}) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    double delta = 0.0, s = 0.0, s2 = 0.0;
    const int n_samples = 200000;
    Pcg32 r(seed++);
    for (int i = 0; i < n_samples; ++i) {
      BsdfSample bs;
      float u_lobe = r.next_float();
      Vec2f u = r.next_2d();
      double wgt = mix->sample(si, wo, u_lobe, u, &bs) ? double(luminance(bs.weight)) : 0.0;
      if (wgt > 0.0 && (bs.flags & k_bsdf_delta)) delta = double(luminance(bs.weight)) * bs.pdf;
      s += wgt;
      s2 += wgt * wgt;
    }
    double mean = s / n_samples, se = std::sqrt(std::max(0.0, s2 / n_samples - mean * mean) / n_samples);
    EXPECT_NEAR(mean, 1.0, 4.0 * se + 1e-4) << "cos(wo) = " << c;
    EXPECT_NEAR(eval_integral(*mix, si, wo) + delta, 1.0, 1e-3) << "cos(wo) = " << c;
  }
}

TEST(mix, emission_is_blended) {
  Library lib;
  ParamSet pe;
  pe.set("radiance", 2.0);
  pe.set("albedo", 0.3);
  uint32_t e = lib.add("emissive", pe), d = lib.add_diffuse(Color(0.5f));
  auto mix = lib.mix(e, d, 0.25);
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  EXPECT_TRUE(mix->is_emissive());
  EXPECT_EQ(mix->emission(si, Vec3f(0, 0, 1)), Color(1.5f));
  EXPECT_TRUE(is_black(mix->emission(si, Vec3f(0, 0, -1))));  // back face of a one-sided emitter
  EXPECT_EQ(mix->average_emission(), Color(1.5f));
  EXPECT_FALSE(mix->two_sided_emission());
  EXPECT_EQ(mix->flags(), uint32_t(k_bsdf_diffuse | k_bsdf_reflection));
  Color al = mix->albedo(si);
  EXPECT_NEAR(al.x, 0.75 * 0.3 + 0.25 * 0.5, 1e-6);
  // Non-emissive components: not emissive.
  auto nested = lib.mix(d, d, 0.5);
  EXPECT_FALSE(nested->is_emissive());
}

TEST(mix, parameter_errors) {
  Library lib;
  uint32_t a = lib.add_diffuse(Color(0.5f)), b = lib.add_diffuse(Color(0.2f));
  auto expect_error = [&](const ParamSet& p, const std::vector<std::string>& parts) {
    std::string msg = lib.error_of(p);
    EXPECT_FALSE(msg.empty()) << "no error";
    for (const auto& part : parts) EXPECT_NE(msg.find(part), std::string::npos) << msg;
  };
  ParamSet missing_a;
  missing_a.set("material_b", int64_t(b));
  expect_error(missing_a, {"'material_a'", "required", "material 9"});
  ParamSet missing_b;
  missing_b.set("material_a", int64_t(a));
  expect_error(missing_b, {"'material_b'", "required"});
  ParamSet unknown_id;
  unknown_id.set("material_a", int64_t(a));
  unknown_id.set("material_b", int64_t(17));
  expect_error(unknown_id, {"'material_b'", "material 17 does not exist"});
  ParamSet negative_id;
  negative_id.set("material_a", int64_t(-1));
  negative_id.set("material_b", int64_t(b));
  expect_error(negative_id, {"'material_a'", "does not exist"});
  ParamSet float_id;
  float_id.set("material_a", 0.5);
  float_id.set("material_b", int64_t(b));
  expect_error(float_id, {"'material_a'", "integer"});
  for (double w : {-0.1, 1.5}) {
    ParamSet bad_weight;
    bad_weight.set("material_a", int64_t(a));
    bad_weight.set("material_b", int64_t(b));
    bad_weight.set("weight", w);
    expect_error(bad_weight, {"'weight'", "[0, 1]"});
  }
  ParamSet missing_mask;
  missing_mask.set("material_a", int64_t(a));
  missing_mask.set("material_b", int64_t(b));
  missing_mask.set("weight", TextureRef{8});
  expect_error(missing_mask, {"'weight'", "texture 8 does not exist"});
  ParamSet typo;
  typo.set("material_a", int64_t(a));
  typo.set("material_b", int64_t(b));
  typo.set("wieght", 0.5);
  expect_error(typo, {"did you mean 'weight'"});
  // Default weight 0.5, and the same material twice is allowed.
  ParamSet ok;
  ok.set("material_a", int64_t(a));
  ok.set("material_b", int64_t(b));
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  EXPECT_NEAR(create_material("mix", ok, lib.context(), "t")->albedo(si).x, 0.35, 1e-6);
  EXPECT_NO_THROW(lib.mix(a, a, 0.5));
}
