// Material "conductor" (material/conductor.cpp), created through sg::create_material.
#include <gtest/gtest.h>

#include "core/error.h"
#include "material/normal_mapping.h"
#include "microfacet_checks.h"

using namespace sg;
using namespace sgtest;

namespace {

ParamSet conductor_params(const std::string& metal, double roughness, double anisotropy = 0.0) {
  ParamSet p;
  p.set("metal", metal);
  p.set("roughness", roughness);
  p.set("anisotropy", anisotropy);
  return p;
}

std::shared_ptr<Material> make(const ParamSet& p) { return create_material("conductor", p, no_textures(), "test"); }

std::string error_of(const ParamSet& p) {
  try {
    create_material("conductor", p, no_textures(), "material 7");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// The incoming directions of the sampling tests: normal incidence to grazing (0.03) on the
// front side and one from the back side (the material is two-sided).
const double k_cosines[] = {1.0, 0.7, 0.3, 0.1, 0.03, -0.5};

struct RoughCase {
  double roughness, anisotropy;
};
// Two isotropic roughness values and two anisotropic ones (either sign of the anisotropy).
const RoughCase k_rough_cases[] = {{0.3, 0.0}, {0.7, 0.0}, {0.5, 0.8}, {0.3, -0.7}};

}  // namespace

TEST(conductor, sample_matches_pdf_chi2) {
  // 4 roughness cases x 6 directions = 24 chi-square tests (counted in chi2.h).
  Pcg32 rng(201);
  uint64_t seed = 5000;
  for (const RoughCase& rc : k_rough_cases) {
    auto mat = make(conductor_params("gold", rc.roughness, rc.anisotropy));
    for (double c : k_cosines) {
      DVec3 n = random_unit(rng);
      SurfaceInteraction si = make_si(n, n);
      Vec3f wo = to_f(direction_at_cos(n, c, rng));
      MixedSamplingStats st =
          check_sampling_mixed(*mat, si, wo, seed++,
                               "conductor roughness " + std::to_string(rc.roughness) + " anisotropy " +
                                   std::to_string(rc.anisotropy) + ", cos(wo) = " + std::to_string(c));
      EXPECT_EQ(st.delta, 0);
    }
  }
}

TEST(conductor, sample_matches_pdf_chi2_with_shading_normal) {
  // Shading normal tilted 25 degrees: directions below the geometric surface must get pdf 0
  // and be rejected by sample(), and sampled ones must match pdf().
  auto mat = make(conductor_params("copper", 0.5, 0.4));
  Pcg32 rng(202);
  DVec3 ng = random_unit(rng);
  DVec3 ns = direction_at_cos(ng, std::cos(25.0 * k_pi_d / 180.0), rng);
  SurfaceInteraction si = make_si(ng, ns);
  Vec3f wo = to_f(direction_at_cos(ng, 0.3, rng));
  check_sampling_mixed(*mat, si, wo, 5100, "conductor with tilted shading normal");
}

TEST(conductor, reflection_only_and_two_sided) {
  auto mat = make(conductor_params("silver", 0.4));
  Pcg32 rng(203);
  int front = 0, back = 0;
  for (int i = 0; i < 2000; ++i) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(random_unit(rng)), wi = to_f(random_unit(rng));
    float co = dot(si.ng, wo), ci = dot(si.ng, wi);
    Color f = mat->eval(si, wo, wi);
    float pdf = mat->pdf(si, wo, wi);
    if (co * ci <= 0.f) {
      EXPECT_TRUE(is_black(f));
      EXPECT_EQ(pdf, 0.f);
    } else {
      EXPECT_GT(f.x, 0.f);
      EXPECT_GT(pdf, 0.f);
      (co > 0.f ? front : back)++;
    }
    BsdfSample bs;
    if (mat->sample(si, wo, 0.5f, rng.next_2d(), &bs)) {
      EXPECT_GT(dot(si.ng, bs.wi) * co, 0.f);
    }
  }
  EXPECT_GT(front, 300);
  EXPECT_GT(back, 300);
  // Mirror symmetry: flipping both normals and directions gives the same value.
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  SurfaceInteraction si_flip = si;
  si_flip.ng = -si.ng;
  si_flip.ns = -si.ns;
  Vec3f wo = normalize(Vec3f(0.3f, 0.2f, 0.8f)), wi = normalize(Vec3f(-0.4f, 0.1f, 0.7f));
  Color a = mat->eval(si, wo, wi), b = mat->eval(si_flip, -wo, -wi), c = mat->eval(si, -wo, -wi);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(a[k], b[k], 1e-6 * a[k]);
    EXPECT_NEAR(a[k], c[k], 1e-6 * a[k]);
  }
  EXPECT_EQ(mat->flags(), uint32_t(k_bsdf_glossy | k_bsdf_reflection));
}

TEST(conductor, reciprocity) {
  for (const RoughCase& rc : k_rough_cases) check_reciprocity(*make(conductor_params("gold", rc.roughness, rc.anisotropy)), 204);
}

TEST(conductor, white_furnace_with_unit_fresnel) {
  // metal "none": Fresnel = 1, so the directional albedo is the single-scattering GGX albedo
  // E(wo) = integral of D_wo(m) G2 / G1(wo) dm <= 1 (each weight G2 / G1 <= 1). It must not
  // exceed 1 (+ MC tolerance), must agree with the quadrature of eval() (independent of
  // sample()), and must stay above a lower bound: single scattering loses the energy of
  // inter-reflections between microfacets (Heitz et al. 2016, "Multiple-Scattering Microfacet
  // BSDFs with the Smith Model"). Anchor: at alpha = 1 (roughness 1) D = 1 / pi and, for
  // normal incidence, G2 = 2 cos_i / (1 + cos_i), so E = (1 / 4 pi) integral G2 = 1 - ln 2 =
  // 0.3069 exactly. The other bounds are the quadrature values (0.991, 0.946, 0.907, 0.698,
  // 0.749, 0.914, 0.848, 0.811, 0.838 in table order) less 0.02-0.03. At grazing wo the
  // loss shrinks again: G2 / G1(wo) -> 1 as Lambda(wo) grows.
  struct Case {
    double roughness, anisotropy, cos_o, lower;
  };
  const Case cases[] = {{0.3, 0.0, 1.0, 0.97},  {0.3, 0.0, 0.3, 0.92},  {0.3, 0.0, 0.05, 0.88},
                        {0.7, 0.0, 1.0, 0.67},  {0.7, 0.0, 0.3, 0.72},  {0.7, 0.0, 0.05, 0.88},
                        {1.0, 0.0, 1.0, 0.29},  {1.0, 0.0, 0.05, 0.82}, {0.5, 0.8, 0.5, 0.78},
                        {0.5, -0.8, 0.05, 0.81}};
  Pcg32 rng(205);
  uint64_t seed = 5200;
  for (const Case& c : cases) {
    auto mat = make(conductor_params("none", c.roughness, c.anisotropy));
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c.cos_o, rng));
    std::string what = "roughness " + std::to_string(c.roughness) + " anisotropy " + std::to_string(c.anisotropy) +
                       " cos " + std::to_string(c.cos_o);
    FurnaceMc mc = furnace_mc(*mat, si, wo, seed++, 200000, false);
    double quad = furnace_quadrature(*mat, si, wo);
    EXPECT_LE(mc.mean, 1.0 + 4.0 * mc.stddev_of_mean) << what;
    EXPECT_LE(mc.mean, 1.01) << what;
    EXPECT_LE(mc.max_weight, 1.0 + 1e-5) << what << ": a single weight G2/G1 exceeds 1";
    EXPECT_LE(quad, 1.001) << what;
    EXPECT_GT(mc.mean, c.lower) << what;
    EXPECT_NEAR(mc.mean, quad, 4.0 * mc.stddev_of_mean + 1e-3) << what << ": sample weights vs integral of eval";
  }
  // The analytic anchor: roughness 1, normal incidence, E = 1 - ln 2.
  {
    auto mat = make(conductor_params("none", 1.0));
    SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
    EXPECT_NEAR(furnace_quadrature(*mat, si, Vec3f(0, 0, 1)), 1.0 - std::log(2.0), 1e-4);
    FurnaceMc mc = furnace_mc(*mat, si, Vec3f(0, 0, 1), 5301, 200000, false);
    EXPECT_NEAR(mc.mean, 1.0 - std::log(2.0), 4.0 * mc.stddev_of_mean);
  }
  // Low roughness is (nearly) lossless at moderate angles.
  auto mat = make(conductor_params("none", 0.1));
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  FurnaceMc mc = furnace_mc(*mat, si, normalize(Vec3f(0.3f, 0.f, 0.9f)), 5300, 100000, false);
  EXPECT_NEAR(mc.mean, 1.0, 2e-3);
}

TEST(conductor, smooth_mirror_is_delta_with_exact_fresnel) {
  // Roughness below 1e-3 is a Dirac lobe: eval and pdf are 0, the sample is the mirror
  // direction with weight = Fresnel (checked against an independent complex-arithmetic Fresnel).
  const Color eta(0.2f, 0.9f, 1.1f), k(3.9f, 2.5f, 2.1f);
  ParamSet p;
  p.set("eta", std::vector<double>{eta.x, eta.y, eta.z});
  p.set("k", std::vector<double>{k.x, k.y, k.z});
  p.set("roughness", 0.0005);
  p.set("specular_tint", std::vector<double>{1.0, 0.5, 1.0});
  auto mat = make(p);
  EXPECT_EQ(mat->flags(), uint32_t(k_bsdf_delta | k_bsdf_reflection));
  Pcg32 rng(206);
  for (double c : {1.0, 0.8, 0.5, 0.2, 0.05, 0.01, -0.6}) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    DVec3 wod = direction_at_cos(n, c, rng);
    Vec3f wo = to_f(wod);
    BsdfSample bs;
    ASSERT_TRUE(mat->sample(si, wo, 0.3f, rng.next_2d(), &bs)) << c;
    EXPECT_TRUE(bs.flags & k_bsdf_delta);
    DVec3 mirror{2 * c * n.x - wod.x, 2 * c * n.y - wod.y, 2 * c * n.z - wod.z};
    EXPECT_NEAR(ddot(to_d(bs.wi), mirror), 1.0, 1e-6) << c;
    for (int ch = 0; ch < 3; ++ch) {
      double ref = fresnel_conductor_ref(std::fabs(c), eta[ch], k[ch]) * (ch == 1 ? 0.5 : 1.0);
      EXPECT_NEAR(bs.weight[ch], ref, 2e-5) << "cos " << c << " channel " << ch;
    }
    EXPECT_TRUE(is_black(mat->eval(si, wo, bs.wi)));
    EXPECT_EQ(mat->pdf(si, wo, bs.wi), 0.f);
  }
}

TEST(conductor, rough_eval_matches_closed_form) {
  // eval = F D G2 / (4 cos_o) evaluated independently in double for an isotropic lobe at
  // normal incidence of wo: h = normalize(wo + wi), D = alpha^2 / (pi (cos_h^2 (alpha^2 - 1) + 1)^2),
  // Lambda(w) = (-1 + sqrt(1 + alpha^2 tan^2)) / 2.
  double r = 0.6, alpha = r * r;
  ParamSet p;
  p.set("eta", std::vector<double>{1.5, 1.5, 1.5});
  p.set("k", std::vector<double>{4.0, 4.0, 4.0});
  p.set("roughness", r);
  auto mat = make(p);
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  for (double ti : {0.1, 0.5, 1.0, 1.4}) {
    for (double to : {0.0, 0.3, 1.2}) {
      DVec3 wo{std::sin(to), 0, std::cos(to)}, wi{-std::sin(ti) * 0.6, std::sin(ti) * 0.8, std::cos(ti)};
      DVec3 h = dnormalize({wo.x + wi.x, wo.y + wi.y, wo.z + wi.z});
      double a2 = alpha * alpha, c2 = h.z * h.z;
      double d = a2 / (k_pi_d * std::pow(c2 * (a2 - 1) + 1, 2));
      auto lambda = [&](const DVec3& w) { return 0.5 * (-1 + std::sqrt(1 + a2 * (1 - w.z * w.z) / (w.z * w.z))); };
      double g2 = 1 / (1 + lambda(wo) + lambda(wi));
      double f = fresnel_conductor_ref(ddot(wo, h), 1.5, 4.0);
      double ref = f * d * g2 / (4 * wo.z);
      EXPECT_NEAR(mat->eval(si, to_f(wo), to_f(wi)).x, ref, 2e-5 * ref + 1e-7) << ti << " " << to;
    }
  }
}

TEST(conductor, anisotropy_follows_dpdu) {
  // anisotropy > 0: alpha_x > alpha_y along dpdu, so at normal incidence the lobe is wider in
  // the dpdu direction; rotating dpdu by 90 degrees swaps the two.
  auto mat = make(conductor_params("aluminium", 0.5, 0.8));
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  si.dpdu = Vec3f(1, 0, 0);
  Vec3f wo(0, 0, 1);
  float t = 0.6f;
  Vec3f along_u(std::sin(t), 0, std::cos(t)), along_v(0, std::sin(t), std::cos(t));
  Color fu = mat->eval(si, wo, along_u), fv = mat->eval(si, wo, along_v);
  EXPECT_GT(fu.x, 2.f * fv.x);
  SurfaceInteraction si_rot = si;
  si_rot.dpdu = Vec3f(0, 1, 0);
  EXPECT_NEAR(mat->eval(si_rot, wo, along_v).x, fu.x, 1e-6f * fu.x);
  EXPECT_NEAR(mat->eval(si_rot, wo, along_u).x, fv.x, 1e-6f * fv.x);
  // Negative anisotropy swaps the axes; roughness_u / roughness_v give the axes directly.
  auto neg = make(conductor_params("aluminium", 0.5, -0.8));
  EXPECT_NEAR(neg->eval(si, wo, along_v).x, fu.x, 1e-6f * fu.x);
  ParamSet uv;
  uv.set("metal", std::string("aluminium"));
  uv.set("roughness_u", 0.7);
  uv.set("roughness_v", 0.2);
  auto muv = make(uv);
  EXPECT_GT(muv->eval(si, wo, along_u).x, 2.f * muv->eval(si, wo, along_v).x);
}

TEST(conductor, presets_and_albedo) {
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  auto albedo = [&](const std::string& metal) { return make(conductor_params(metal, 0.2))->albedo(si); };
  Color gold = albedo("gold"), al = albedo("aluminium"), cu = albedo("copper"), ag = albedo("silver"),
        fe = albedo("iron"), cr = albedo("chrome");
  // Gold reflects red much more than blue; copper too; silver and aluminium are nearly white.
  EXPECT_GT(gold.x, 0.9f);
  EXPECT_LT(gold.z, 0.5f);
  EXPECT_GT(cu.x, cu.z + 0.2f);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(al[c], 0.92, 0.03) << "aluminium reflects ~0.9 at normal incidence";
    EXPECT_GT(ag[c], 0.9f);
    EXPECT_GT(fe[c], 0.45f);
    EXPECT_LT(fe[c], 0.6f);
    EXPECT_GT(cr[c], 0.55f);
    EXPECT_LT(cr[c], 0.75f);
  }
  // The albedo is the normal-incidence Fresnel reflectance ((n-1)^2 + k^2) / ((n+1)^2 + k^2).
  double n = 0.1431, k = 3.9832;
  EXPECT_NEAR(gold.x, ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k), 1e-4);
  EXPECT_EQ(albedo("aluminum"), al);
  EXPECT_EQ(albedo("chromium"), cr);
  EXPECT_EQ(albedo("none"), Color(1.f));
  // Default: aluminium, roughness 0.3.
  EXPECT_EQ(make(ParamSet{})->albedo(si), al);
}

TEST(conductor, parameter_errors) {
  ParamSet bad_metal;
  bad_metal.set("metal", std::string("gld"));
  std::string msg = error_of(bad_metal);
  EXPECT_NE(msg.find("did you mean 'gold'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("material 7"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'metal'"), std::string::npos) << msg;

  for (double r : {-0.1, 1.5}) {
    ParamSet p;
    p.set("roughness", r);
    msg = error_of(p);
    EXPECT_NE(msg.find("'roughness'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("[0, 1]"), std::string::npos) << msg;
  }
  ParamSet aniso;
  aniso.set("anisotropy", 1.2);
  msg = error_of(aniso);
  EXPECT_NE(msg.find("[-1, 1]"), std::string::npos) << msg;
  ParamSet ru;
  ru.set("roughness_u", 2.0);
  EXPECT_NE(error_of(ru).find("'roughness_u'"), std::string::npos);
  ParamSet both;
  both.set("roughness", 0.5);
  both.set("roughness_v", 0.5);
  EXPECT_NE(error_of(both).find("cannot be combined"), std::string::npos);
  ParamSet metal_and_eta;
  metal_and_eta.set("metal", std::string("gold"));
  metal_and_eta.set("eta", 1.0);
  metal_and_eta.set("k", 1.0);
  EXPECT_NE(error_of(metal_and_eta).find("cannot be combined"), std::string::npos);
  ParamSet eta_only;
  eta_only.set("eta", 1.0);
  EXPECT_NE(error_of(eta_only).find("'k'"), std::string::npos);
  ParamSet neg_eta;
  neg_eta.set("eta", -1.0);
  neg_eta.set("k", 1.0);
  EXPECT_NE(error_of(neg_eta).find("'eta'"), std::string::npos);
  ParamSet tint;
  tint.set("specular_tint", 1.5);
  EXPECT_NE(error_of(tint).find("'specular_tint'"), std::string::npos);
  ParamSet typo;
  typo.set("roughnes", 0.5);
  msg = error_of(typo);
  EXPECT_NE(msg.find("did you mean 'roughness'"), std::string::npos) << msg;
  ParamSet wrong_type;
  wrong_type.set("metal", 3.0);
  EXPECT_THROW(make(wrong_type), Error);
}

// A bump map (a 3D noise height) makes the conductor reflect like the plain one evaluated with
// the bumped shading normal; sampling stays consistent with pdf() (1 chi-square test).
TEST(conductor, bump_map_tilts_the_shading_normal) {
  ParamSet tp;
  tp.set("mapping", std::string("object"));
  tp.set("scale", 5.0);
  tp.set("pattern", std::string("turbulence"));
  auto height = create_texture("noise", tp, "test");
  MaterialContext ctx;
  ctx.textures = [&](uint32_t id) -> std::shared_ptr<Texture> { return id == 0 ? height : nullptr; };
  ParamSet p = conductor_params("gold", 0.4);
  p.set("bump_map", TextureRef{0});
  p.set("bump_scale", 0.05);
  auto bumped = create_material("conductor", p, ctx, "test");
  auto plain = make(conductor_params("gold", 0.4));
  EXPECT_EQ(bumped->needs() & k_needs_tangent, 0u) << "a 3D height needs no uv tangent";
  const Transform identity;
  Pcg32 rng(207);
  int tilted = 0;
  SurfaceInteraction last;
  for (int i = 0; i < 300; ++i) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    si.p_object = si.p = Vec3f(rng.next_float(), rng.next_float(), rng.next_float()) * 2.f;
    si.world_from_object = &identity;
    SurfaceInteraction t = si;
    t.ns = bump_normal(si, *height, 0.05f);
    t.dpdu = normalize(si.dpdu - t.ns * dot(t.ns, si.dpdu));  // the frame the material builds
    tilted += dot(t.ns, si.ns) < 0.9999f;
    for (int k = 0; k < 4; ++k) {
      Vec3f wo = to_f(direction_at_cos(n, 0.2 + 0.8 * rng.next_float(), rng));
      Vec3f wi = to_f(direction_at_cos(n, 0.2 + 0.8 * rng.next_float(), rng));
      Color a = bumped->eval(si, wo, wi), b = plain->eval(t, wo, wi);
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(a[c], b[c], 1e-5 * b[c] + 1e-8) << i;
      ASSERT_NEAR(bumped->pdf(si, wo, wi), plain->pdf(t, wo, wi), 1e-5 * plain->pdf(t, wo, wi) + 1e-8);
    }
    last = si;
  }
  EXPECT_GT(tilted, 250) << "the bump changes the normal";
  Vec3f wo = to_f(direction_at_cos(to_d(last.ng), 0.5, rng));
  check_sampling_mixed(*bumped, last, wo, 5200, "conductor with a bump map");
}
