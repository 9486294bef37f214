// Material "dielectric" (material/dielectric.cpp), created through sg::create_material.
//
// Convention under test (see the file header of dielectric.cpp): eval() and sample() give the
// BSDF for radiance transport from the camera: refraction from the side of wo (index eta_o)
// into the side of wi (index eta_t) carries the factor (eta_o / eta_t)^2, and
// BsdfSample::eta = eta_t / eta_o. Energy checks multiply refraction weights by eta^2.
#include <gtest/gtest.h>

#include "core/error.h"
#include "microfacet_checks.h"

using namespace sg;
using namespace sgtest;

namespace {

constexpr double k_ior = 1.5;

std::shared_ptr<Material> make_dielectric(double roughness, bool thin = false, double ior = k_ior,
                                          double exterior = 1.0) {
  ParamSet p;
  p.set("ior", ior);
  p.set("exterior_ior", exterior);
  p.set("roughness", roughness);
  p.set("thin", thin);
  return create_material("dielectric", p, no_textures(), "test");
}

std::string error_of(const ParamSet& p) {
  try {
    create_material("dielectric", p, no_textures(), "material 9");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

/// Unpolarized Fresnel reflectance in double; eta = eta_t / eta_i (Born & Wolf, sec. 1.5.2).
double fresnel_ref(double cos_i, double eta) {
  double sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0) return 1.0;
  double cos_t = std::sqrt(1.0 - sin2_t);
  double rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  double rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  return 0.5 * (rs * rs + rp * rp);
}

BsdfSample sample_lobe(const Material& m, const SurfaceInteraction& si, const Vec3f& wo, float u_lobe, bool* ok) {
  BsdfSample bs;
  *ok = m.sample(si, wo, u_lobe, Vec2f(0.5f, 0.5f), &bs);
  return bs;
}

}  // namespace

TEST(dielectric, rough_sample_matches_pdf_chi2_entering_and_exiting) {
  // Whole-sphere chi-square (reflection + refraction). Entering: wo outside (cos > 0), down to
  // grazing 0.03; exiting: wo inside, below and beyond the critical angle (cos 0.745 for 1.5).
  // 2 roughness values x 8 directions = 16 chi-square tests (counted in chi2.h).
  const double cosines[] = {1.0, 0.7, 0.3, 0.1, 0.03, -0.9, -0.6, -0.2};
  Pcg32 rng(301);
  uint64_t seed = 7000;
  for (double r : {0.3, 0.7}) {
    auto mat = make_dielectric(r);
    for (double c : cosines) {
      DVec3 n = random_unit(rng);
      SurfaceInteraction si = make_si(n, n);
      Vec3f wo = to_f(direction_at_cos(n, c, rng));
      MixedSamplingStats st = check_sampling_mixed(
          *mat, si, wo, seed++, "dielectric roughness " + std::to_string(r) + ", cos(wo) = " + std::to_string(c));
      EXPECT_EQ(st.delta, 0);
    }
  }
}

TEST(dielectric, rough_sample_matches_pdf_chi2_with_shading_normal) {
  // Shading normal tilted 20 degrees: directions whose side differs between the geometric
  // and the shading normal get pdf 0 and must be rejected by sample(). 1 chi-square test.
  auto mat = make_dielectric(0.5);
  Pcg32 rng(302);
  DVec3 ng = random_unit(rng);
  DVec3 ns = direction_at_cos(ng, std::cos(20.0 * k_pi_d / 180.0), rng);
  SurfaceInteraction si = make_si(ng, ns);
  check_sampling_mixed(*mat, si, to_f(direction_at_cos(ng, 0.4, rng)), 7100, "dielectric, tilted shading normal");
}

TEST(dielectric, thin_rough_sample_matches_pdf_chi2) {
  // Rough thin slab: the glossy reflection is chi-square tested against pdf(); the straight
  // transmission is a Dirac lobe (wi = -wo exactly, weight = transmittance). 3 chi-square tests.
  ParamSet p;
  p.set("roughness", 0.4);
  p.set("thin", true);
  p.set("transmittance", std::vector<double>{0.9, 0.8, 0.7});
  auto mat = create_material("dielectric", p, no_textures(), "test");
  EXPECT_EQ(mat->flags(), uint32_t(k_bsdf_glossy | k_bsdf_reflection | k_bsdf_delta | k_bsdf_transmission));
  Pcg32 rng(303);
  uint64_t seed = 7200;
  for (double c : {0.8, 0.1, -0.5}) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    MixedSamplingStats st = check_sampling_mixed(*mat, si, wo, seed++, "thin dielectric, cos " + std::to_string(c));
    EXPECT_GT(st.delta, 100000) << "the straight transmission carries most of the energy";
    for (int i = 0; i < 1000; ++i) {
      BsdfSample bs;
      if (!mat->sample(si, wo, rng.next_float(), rng.next_2d(), &bs) || !(bs.flags & k_bsdf_delta)) continue;
      EXPECT_EQ(bs.wi, -wo);
      EXPECT_EQ(bs.weight, Color(0.9f, 0.8f, 0.7f));
      EXPECT_EQ(bs.eta, 1.f);
    }
  }
}

TEST(dielectric, smooth_fresnel_lossless_and_normal_incidence) {
  auto mat = make_dielectric(0.0);
  EXPECT_EQ(mat->flags(), uint32_t(k_bsdf_delta | k_bsdf_reflection | k_bsdf_transmission));
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  // Normal incidence: R = ((n - 1) / (n + 1))^2 = 0.04 from either side.
  for (float side : {1.f, -1.f}) {
    bool ok;
    BsdfSample r = sample_lobe(*mat, si, Vec3f(0, 0, side), 0.f, &ok);
    ASSERT_TRUE(ok);
    EXPECT_TRUE(r.flags & k_bsdf_reflection);
    EXPECT_NEAR(r.pdf, std::pow((k_ior - 1) / (k_ior + 1), 2), 1e-6);
  }
  // At every angle, entering and exiting: R + T = 1 (the lobe probabilities), reflection
  // weight 1 and refraction weight (eta_o / eta_t)^2, i.e. lossless once the radiance scaling
  // is undone; R matches the Fresnel equations evaluated in double.
  Pcg32 rng(304);
  for (int i = 0; i < 2000; ++i) {
    double c = 2.0 * rng.next_float() - 1.0;
    if (std::fabs(c) < 1e-3) continue;
    DVec3 n = random_unit(rng);
    SurfaceInteraction s = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    double co = ddot(n, to_d(wo));
    double eta = co > 0 ? k_ior : 1.0 / k_ior;  // eta_t / eta_o
    bool ok_r, ok_t;
    BsdfSample r = sample_lobe(*mat, s, wo, 0.f, &ok_r);
    BsdfSample t = sample_lobe(*mat, s, wo, k_one_minus_epsilon, &ok_t);
    ASSERT_TRUE(ok_r);
    // Next to the critical angle dR/dcos is unbounded (R = 1 - O(sqrt(cos_t))): the float
    // rounding of cos(wo) alone moves R by more than 2e-6 there.
    double cos_crit = std::sqrt(1.0 - 1.0 / (k_ior * k_ior));
    if (co > 0 || std::fabs(-co - cos_crit) > 1e-3) {
      EXPECT_NEAR(r.pdf, fresnel_ref(std::fabs(co), eta), 2e-6) << co;
    }
    EXPECT_EQ(r.weight, Color(1.f));
    EXPECT_EQ(r.eta, 1.f);
    if (r.pdf >= 1.f) {  // total internal reflection: both samples reflect
      EXPECT_LT(co, 0.0);
      EXPECT_TRUE(ok_t && (t.flags & k_bsdf_reflection));
      continue;
    }
    ASSERT_TRUE(ok_t) << co;
    EXPECT_TRUE(t.flags & k_bsdf_transmission);
    EXPECT_NEAR(r.pdf + t.pdf, 1.0, 1e-6);
    EXPECT_NEAR(t.eta, eta, 1e-6);
    EXPECT_NEAR(t.weight.y * t.eta * t.eta, 1.0, 1e-5) << "refraction weight is (eta_o / eta_t)^2";
    // Neither lobe is visible to eval() / pdf().
    EXPECT_TRUE(is_black(mat->eval(s, wo, t.wi)));
    EXPECT_EQ(mat->pdf(s, wo, r.wi), 0.f);
  }
  // Monte Carlo furnace through sample(): mean of weight * eta^2 is exactly 1.
  for (double c : {0.9, 0.2, -0.9, -0.3}) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction s = make_si(n, n);
    FurnaceMc mc = furnace_mc(*mat, s, to_f(direction_at_cos(n, c, rng)), 7300, 100000, true);
    EXPECT_NEAR(mc.mean, 1.0, 1e-3) << c;
  }
}

TEST(dielectric, snell_law_and_total_internal_reflection) {
  auto mat = make_dielectric(0.0);
  Pcg32 rng(305);
  double cos_crit = std::sqrt(1.0 - 1.0 / (k_ior * k_ior));
  int refracted = 0, tir = 0;
  for (int i = 0; i < 2000; ++i) {
    double c = 2.0 * rng.next_float() - 1.0;
    if (std::fabs(c) < 1e-3) continue;
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    DVec3 wod = to_d(wo);
    double co = ddot(n, wod);
    double eta_o = co > 0 ? 1.0 : k_ior, eta_t = co > 0 ? k_ior : 1.0;
    bool ok;
    BsdfSample t = sample_lobe(*mat, si, wo, k_one_minus_epsilon, &ok);
    ASSERT_TRUE(ok);
    if (co < 0 && -co < cos_crit - 1e-4) {
      // Beyond the critical angle: total internal reflection, whatever the lobe sample.
      EXPECT_TRUE(t.flags & k_bsdf_reflection) << co;
      EXPECT_EQ(t.pdf, 1.f);
      EXPECT_EQ(t.weight, Color(1.f));
      ++tir;
      continue;
    }
    if (co < 0 && -co < cos_crit + 1e-4) continue;  // too close to the critical angle to call
    ASSERT_TRUE(t.flags & k_bsdf_transmission) << co;
    ++refracted;
    DVec3 wi = to_d(t.wi);
    double ci = ddot(n, wi);
    EXPECT_LT(ci * co, 0.0) << "refraction crosses the surface";
    // Snell: eta_o sin(theta_o) = eta_t sin(theta_t), and wi lies in the plane of (n, wo).
    // Sines as lengths of the cross products (accurate near normal incidence too).
    auto sine = [&](const DVec3& w) {
      DVec3 c = dcross(n, w);
      return std::sqrt(ddot(c, c));
    };
    EXPECT_NEAR(eta_o * sine(wod), eta_t * sine(wi), 1e-6) << co;
    DVec3 plane_normal = dcross(n, wod);
    EXPECT_NEAR(ddot(plane_normal, wi), 0.0, 2e-6);
    // The tangential components point in opposite directions (the ray goes straight on).
    DVec3 to{wod.x - co * n.x, wod.y - co * n.y, wod.z - co * n.z}, ti{wi.x - ci * n.x, wi.y - ci * n.y, wi.z - ci * n.z};
    EXPECT_LE(ddot(to, ti), 1e-9);
  }
  EXPECT_GT(refracted, 1000);
  EXPECT_GT(tir, 200);
}

TEST(dielectric, rough_eval_matches_walter_btdf) {
  // eval() against Walter et al. 2007, eqs. 16, 20 and 21, evaluated independently in double
  // with wo = o and wi = i (light arrives along wi): the radiance-form BTDF with eta_o^2 in
  // the numerator. Isotropic GGX, height-correlated Smith G2.
  double r = 0.5, a = r * r, a2 = a * a;
  auto mat = make_dielectric(r);
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  auto D = [&](const DVec3& h) {
    double c2 = h.z * h.z;
    return a2 / (k_pi_d * std::pow(c2 * (a2 - 1) + 1, 2));
  };
  auto lambda = [&](const DVec3& w) { return 0.5 * (-1 + std::sqrt(1 + a2 * (1 - w.z * w.z) / (w.z * w.z))); };
  int checked = 0;
  Pcg32 rng(306);
  for (int i = 0; i < 400; ++i) {
    DVec3 o = random_unit(rng), in = random_unit(rng);
    if (std::fabs(o.z) < 0.05 || std::fabs(in.z) < 0.05) continue;
    double eta_o = o.z > 0 ? 1.0 : k_ior, eta_i = in.z > 0 ? 1.0 : k_ior;
    double g2 = 1 / (1 + lambda(o) + lambda(in));
    double ref;
    if (o.z * in.z > 0) {
      DVec3 h = dnormalize({o.x + in.x, o.y + in.y, o.z + in.z});
      if (h.z < 0) h = {-h.x, -h.y, -h.z};
      double eta_other = o.z > 0 ? k_ior : 1.0;  // index beyond the interface, seen from o
      double f = fresnel_ref(std::fabs(ddot(o, h)), eta_other / eta_o);
      ref = f * D(h) * g2 / (4 * std::fabs(o.z));  // f_r |cos_i|
    } else {
      DVec3 h = dnormalize({-(eta_i * in.x + eta_o * o.x), -(eta_i * in.y + eta_o * o.y), -(eta_i * in.z + eta_o * o.z)});
      if (h.z < 0) h = {-h.x, -h.y, -h.z};
      double ih = ddot(in, h), oh = ddot(o, h);
      // wo must face the microfacet from its own side and wi from the other.
      if (oh * o.z <= 0 || ih * in.z <= 0) {
        ref = 0;
      } else {
        double f = fresnel_ref(std::fabs(oh), eta_i / eta_o);
        double denom = eta_i * ih + eta_o * oh;
        ref = std::fabs(ih) * std::fabs(oh) / (std::fabs(in.z) * std::fabs(o.z)) * eta_o * eta_o * (1 - f) * g2 * D(h) /
              (denom * denom) * std::fabs(in.z);
      }
    }
    double got = mat->eval(si, to_f(o), to_f(in)).y;
    EXPECT_NEAR(got, ref, 1e-4 * ref + 1e-6) << "o.z " << o.z << " i.z " << in.z;
    ++checked;
  }
  EXPECT_GT(checked, 300);
}

TEST(dielectric, reciprocity) {
  // Reflection: f(a, b) = f(b, a) within 1e-5 (plus the float-cosine allowance of
  // check_reciprocity for grazing pairs). Refraction: generalized reciprocity
  // f(a, b) / eta_a^2 = f(b, a) / eta_b^2 (Veach 1997, sec. 5.2), eta_x the index on the side
  // of x. The two evaluations build the generalized half vector h from opposite ends, so they
  // round differently: 2e-5, plus the same 4e-7 / cos allowance for the microfacet cosines
  // min(|a.h|, |b.h|) (f_t is proportional to |i.h| (1 - F), both linear in the cosine of a
  // direction grazing its microfacet, and a float dot product is off by ~1e-7 absolute).
  for (double r : {0.3, 0.6}) {
    for (bool thin : {false, true}) {
      auto mat = make_dielectric(r, thin);
      Pcg32 rng(307);
      int refl = 0, refr = 0, bad = 0;
      std::string first;
      for (int i = 0; i < 10000; ++i) {
        DVec3 n = random_unit(rng);
        SurfaceInteraction si = make_si(n, n);
        Vec3f a = to_f(random_unit(rng)), b = to_f(random_unit(rng));
        double ca = ddot(to_d(si.ns), to_d(a)), cb = ddot(to_d(si.ns), to_d(b));
        if (std::fabs(ca) < 1e-4 || std::fabs(cb) < 1e-4) continue;
        bool reflect = ca * cb > 0;
        double tol = reflect ? 1e-5 : 2e-5;
        double m = std::min(std::fabs(ca), std::fabs(cb));
        if (m < 0.05) tol += 4e-7 / m;
        double na2 = ca > 0 ? 1.0 : k_ior * k_ior, nb2 = cb > 0 ? 1.0 : k_ior * k_ior;
        if (!reflect) {
          DVec3 ad = to_d(a), bd = to_d(b);
          double na = std::sqrt(na2), nb = std::sqrt(nb2);
          DVec3 h = dnormalize({na * ad.x + nb * bd.x, na * ad.y + nb * bd.y, na * ad.z + nb * bd.z});
          tol += 4e-7 / std::max(1e-7, std::min(std::fabs(ddot(ad, h)), std::fabs(ddot(bd, h))));
        }
        double fab = mat->eval(si, a, b).y / std::fabs(cb) / (reflect ? 1.0 : na2);
        double fba = mat->eval(si, b, a).y / std::fabs(ca) / (reflect ? 1.0 : nb2);
        if (fab == 0 && fba == 0) continue;
        (reflect ? refl : refr)++;
        if (rel_diff(fab, fba) > tol && bad++ == 0)
          first = std::to_string(fab) + " vs " + std::to_string(fba) + " (cos " + std::to_string(ca) + ", " +
                  std::to_string(cb) + ")";
      }
      EXPECT_EQ(bad, 0) << "roughness " << r << " thin " << thin << ", first: " << first;
      EXPECT_GT(refl, 2500);
      if (!thin) {
        EXPECT_GT(refr, 800);  // refraction pairs with a valid microfacet (wo in front, wi behind)
      } else {
        EXPECT_EQ(refr, 0) << "a thin slab transmits only along -wo (a Dirac lobe)";
      }
    }
  }
}

TEST(dielectric, rough_white_furnace) {
  // Energy of the rough interface with the radiance scaling undone (refraction weights times
  // eta^2): at most 1 (single scattering loses the energy of inter-reflections between
  // microfacets, Heitz et al. 2016) and above a lower bound; the Monte Carlo mean of sample()
  // agrees with the quadrature of eval(). Lower bounds: the quadrature values (1.000, 0.999,
  // 0.923, 0.989, 0.970, 0.960, 0.855, 0.677 in table order) less 0.01-0.03; the loss is
  // largest inside the glass beyond the critical angle, where light bounces between
  // microfacets that totally reflect it.
  struct Case {
    double roughness, cos_o, lower;
  };
  const Case cases[] = {{0.1, 0.8, 0.99}, {0.3, 1.0, 0.97}, {0.3, 0.1, 0.90},  {0.3, -0.9, 0.96},
                        {0.3, -0.5, 0.94}, {0.7, 0.9, 0.93}, {0.7, 0.1, 0.83}, {0.7, -0.6, 0.65}};
  Pcg32 rng(308);
  uint64_t seed = 7400;
  for (const Case& c : cases) {
    auto mat = make_dielectric(c.roughness);
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c.cos_o, rng));
    std::string what = "roughness " + std::to_string(c.roughness) + " cos " + std::to_string(c.cos_o);
    FurnaceMc mc = furnace_mc(*mat, si, wo, seed++, 200000, true);
    // eta^2 of a refraction seen from wo: (eta_t / eta_o)^2.
    double eta2 = c.cos_o > 0 ? k_ior * k_ior : 1.0 / (k_ior * k_ior);
    double quad = furnace_quadrature(*mat, si, wo, eta2);
    EXPECT_LE(mc.mean, 1.01) << what;
    EXPECT_LE(mc.mean, 1.0 + 4.0 * mc.stddev_of_mean) << what;
    EXPECT_LE(quad, 1.001) << what;
    EXPECT_GT(mc.mean, c.lower) << what;
    EXPECT_NEAR(mc.mean, quad, 4.0 * mc.stddev_of_mean + 1e-3) << what;
  }
}

TEST(dielectric, thin_slab_reflectance) {
  // Smooth thin slab: R' = R + T^2 R / (1 - R^2) = 2R / (1 + R), straight transmission
  // wi = -wo with weight = transmittance and no radiance scaling (same medium on both sides).
  ParamSet p;
  p.set("thin", true);
  p.set("transmittance", std::vector<double>{0.5, 0.6, 0.7});
  auto mat = create_material("dielectric", p, no_textures(), "test");
  EXPECT_EQ(mat->flags(), uint32_t(k_bsdf_delta | k_bsdf_reflection | k_bsdf_transmission));
  Pcg32 rng(309);
  for (double c : {1.0, 0.8, 0.5, 0.2, 0.05, -0.3, -0.9}) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    double r = fresnel_ref(std::fabs(c), k_ior), t = 1 - r;
    double r_slab = r + t * t * r / (1 - r * r);
    bool ok_r, ok_t;
    BsdfSample br = sample_lobe(*mat, si, wo, 0.f, &ok_r), bt = sample_lobe(*mat, si, wo, k_one_minus_epsilon, &ok_t);
    ASSERT_TRUE(ok_r && ok_t);
    EXPECT_NEAR(br.pdf, r_slab, 2e-6) << c;
    EXPECT_NEAR(br.pdf + bt.pdf, 1.0, 1e-6);
    EXPECT_EQ(br.weight, Color(1.f));
    EXPECT_TRUE(bt.flags & k_bsdf_transmission);
    EXPECT_EQ(bt.wi, -wo);
    EXPECT_EQ(bt.weight, Color(0.5f, 0.6f, 0.7f));
    EXPECT_EQ(bt.eta, 1.f);
    if (c == 1.0) {
      EXPECT_NEAR(br.pdf, 2 * 0.04 / 1.04, 1e-6);
    }
  }
  // Rough thin slab: energy (reflection + straight transmission) <= 1, and only the masked
  // part of the glossy reflection is lost (measured 0.97, 0.93, 0.94 for the three cosines:
  // grazing microfacets reflect more and their reflections are masked more).
  auto rough = make_dielectric(0.5, true);
  for (double c : {0.9, 0.3, -0.1}) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    FurnaceMc mc = furnace_mc(*rough, si, to_f(direction_at_cos(n, c, rng)), 7500, 200000, false);
    EXPECT_LE(mc.mean, 1.0 + 4.0 * mc.stddev_of_mean) << c;
    EXPECT_LE(mc.max_weight, 1.0 + 1e-5) << c;
    EXPECT_GT(mc.mean, 0.9) << c;
  }
  // An index-matched thin slab is allowed and transmits everything.
  auto matched = make_dielectric(0.0, true, 1.0, 1.0);
  bool ok;
  BsdfSample b = sample_lobe(*matched, make_si({0, 0, 1}, {0, 0, 1}), normalize(Vec3f(0.3f, 0, 1)), 0.f, &ok);
  ASSERT_TRUE(ok);
  EXPECT_TRUE(b.flags & k_bsdf_transmission);
}

TEST(dielectric, albedo_transmittance_and_flags) {
  ParamSet p;
  p.set("roughness", 0.4);
  p.set("transmittance", std::vector<double>{0.2, 0.5, 0.9});
  auto mat = create_material("dielectric", p, no_textures(), "test");
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  EXPECT_EQ(mat->albedo(si), Color(0.2f, 0.5f, 0.9f));
  EXPECT_EQ(mat->flags(), uint32_t(k_bsdf_glossy | k_bsdf_reflection | k_bsdf_transmission));
  // The tint applies to refraction only; reflection stays white.
  Vec3f wo = normalize(Vec3f(0.2f, 0.1f, 1.f));
  Color fr = mat->eval(si, wo, normalize(Vec3f(-0.2f, -0.1f, 1.f)));
  Color ft = mat->eval(si, wo, normalize(Vec3f(-0.1f, 0.f, -1.f)));
  EXPECT_EQ(fr.x, fr.z);
  EXPECT_NEAR(ft.x / ft.z, 0.2 / 0.9, 1e-6);
  // Default: smooth glass (ior 1.5).
  EXPECT_EQ(create_material("dielectric", ParamSet{}, no_textures(), "t")->flags(),
            uint32_t(k_bsdf_delta | k_bsdf_reflection | k_bsdf_transmission));
}

TEST(dielectric, parameter_errors) {
  for (double ior : {0.5, 11.0}) {
    ParamSet p;
    p.set("ior", ior);
    std::string msg = error_of(p);
    EXPECT_NE(msg.find("'ior'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("[1, 10]"), std::string::npos) << msg;
    EXPECT_NE(msg.find("material 9"), std::string::npos) << msg;
  }
  ParamSet ext;
  ext.set("exterior_ior", 0.9);
  EXPECT_NE(error_of(ext).find("'exterior_ior'"), std::string::npos);
  ParamSet matched;
  matched.set("ior", 1.33);
  matched.set("exterior_ior", 1.33);
  EXPECT_NE(error_of(matched).find("must differ"), std::string::npos);
  for (double r : {-0.5, 1.01}) {
    ParamSet p;
    p.set("roughness", r);
    std::string msg = error_of(p);
    EXPECT_NE(msg.find("'roughness'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("[0, 1]"), std::string::npos) << msg;
  }
  ParamSet tr;
  tr.set("transmittance", 1.2);
  EXPECT_NE(error_of(tr).find("'transmittance'"), std::string::npos);
  ParamSet typo;
  typo.set("exterior_iro", 1.2);
  std::string msg = error_of(typo);
  EXPECT_NE(msg.find("did you mean 'exterior_ior'"), std::string::npos) << msg;
  ParamSet wrong;
  wrong.set("thin", std::string("yes"));
  EXPECT_THROW(create_material("dielectric", wrong, no_textures(), "t"), Error);
  // An air bubble in water (interior index below the exterior one) is fine.
  EXPECT_NO_THROW(make_dielectric(0.2, false, 1.0, 1.33));
}
