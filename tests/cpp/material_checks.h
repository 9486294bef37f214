// Test helpers shared by the material tests (test_diffuse.cpp, test_emissive.cpp):
// chi-square of sample() against pdf(), eval/pdf/sample consistency, reciprocity and
// the white furnace, all through the public Material interface.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "chi2.h"
#include "core/rng.h"
#include "material/material.h"

namespace sgtest {

inline sg::Vec3f to_f(const DVec3& v) { return sg::Vec3f(float(v.x), float(v.y), float(v.z)); }
inline DVec3 to_d(const sg::Vec3f& v) { return {v.x, v.y, v.z}; }

/// Uniformly distributed unit vector from two uniforms, in double (independent of sg warps).
inline DVec3 random_unit(sg::Pcg32& rng) {
  double z = 1.0 - 2.0 * rng.next_float(), phi = 2.0 * k_pi_d * rng.next_float();
  double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

/// Unit direction at cosine `c` from `axis`, at a random azimuth.
inline DVec3 direction_at_cos(const DVec3& axis, double c, sg::Pcg32& rng) {
  DFrame f(axis);
  double phi = 2.0 * k_pi_d * rng.next_float(), s = std::sqrt(std::max(0.0, 1.0 - c * c));
  return dnormalize(f.to_world(s * std::cos(phi), s * std::sin(phi), c));
}

/// Surface interaction with unit geometric normal `ng` and shading normal `ns`.
inline sg::SurfaceInteraction make_si(const DVec3& ng, const DVec3& ns) {
  sg::SurfaceInteraction si;
  si.p = sg::Vec3f(0.3f, -1.2f, 2.f);
  si.p_error = sg::Vec3f(0.f);
  si.ng = to_f(dnormalize(ng));
  si.ns = to_f(dnormalize(ns));
  si.uv = sg::Vec2f(0.25f, 0.75f);
  si.dpdu = sg::Frame(si.ns).s;
  return si;
}

/// A plugin context without textures or materials to refer to.
inline sg::MaterialContext no_textures() {
  sg::MaterialContext ctx;
  ctx.textures = [](uint32_t) -> std::shared_ptr<sg::Texture> { return nullptr; };
  ctx.materials = [](uint32_t) -> std::shared_ptr<sg::Material> { return nullptr; };
  return ctx;
}

inline double rel_diff(double a, double b) {
  double m = std::max(std::fabs(a), std::fabs(b));
  return m == 0.0 ? 0.0 : std::fabs(a - b) / m;
}

/// Chi-square test of the directions produced by mat.sample(si, wo) against
/// mat.pdf(si, wo, .), binned in (cos theta, phi) around the geometric normal. Samples
/// that return false are not binned: the expected counts integrate pdf() over each cell,
/// so the total expectation is N * integral(pdf) and a sampler that fails more (or less)
/// often than pdf() admits fails the test. Also checks, for every sample, that the
/// weight equals eval / pdf (rel 1e-4), that the returned pdf equals pdf() and that
/// sampled directions have non-zero eval.
inline void check_sampling(const sg::Material& mat, const sg::SurfaceInteraction& si, const sg::Vec3f& wo,
                           uint64_t seed, const std::string& what, int n_samples = 1000000) {
  DFrame frame(to_d(si.ng));
  Grid2D g{32, 64, -1.0, 1.0, 0.0, 2.0 * k_pi_d};
  sg::Pcg32 rng(seed);
  std::vector<double> obs(g.size(), 0.0);
  int n_bad_weight = 0, n_bad_pdf = 0, n_bad_dir = 0;
  std::string first_problem;
  for (int i = 0; i < n_samples; ++i) {
    float u_lobe = rng.next_float();
    sg::Vec2f u = rng.next_2d();
    sg::BsdfSample bs;
    if (!mat.sample(si, wo, u_lobe, u, &bs)) continue;
    double z, phi;
    sphere_coords(frame, to_d(bs.wi), &z, &phi);
    long c = g.cell(z, phi);
    if (c < 0 || !(std::fabs(sg::length(bs.wi) - 1.f) < 1e-5f)) {
      ++n_bad_dir;
      continue;
    }
    obs[size_t(c)] += 1.0;
    sg::Color f = mat.eval(si, wo, bs.wi);
    float pdf = mat.pdf(si, wo, bs.wi);
    // sample pdf == pdf(): both are |cos|/pi of the same direction, but sample() takes the
    // cosine from the warp's local z and pdf() from a dot product with the world direction;
    // float rounding differs by ~1e-7 absolute, hence an absolute floor of 1e-6 (pdf <= 1/pi).
    if (!(std::fabs(pdf - bs.pdf) <= 1e-4 * std::max(pdf, bs.pdf) + 1e-6)) {
      if (n_bad_pdf++ == 0)
        first_problem += " pdf mismatch: sample " + std::to_string(bs.pdf) + " vs pdf() " + std::to_string(pdf) + ";";
    }
    bool weight_ok = pdf > 0.f;
    for (int k = 0; k < 3 && weight_ok; ++k) weight_ok = rel_diff(bs.weight[k], f[k] / pdf) <= 1e-4;
    if (!weight_ok && n_bad_weight++ == 0)
      first_problem += " weight " + std::to_string(bs.weight.x) + " vs eval/pdf " + std::to_string(f.x / pdf) + ";";
  }
  // eval_pdf() (next-event estimation) equals the separate eval() and pdf() calls, on
  // sampled directions and on random ones from the whole sphere.
  int n_bad_eval_pdf = 0;
  auto check_eval_pdf = [&](const sg::Vec3f& wi) {
    float p_joint;
    sg::Color f_joint = mat.eval_pdf(si, wo, wi, &p_joint);
    sg::Color f = mat.eval(si, wo, wi);
    float p = mat.pdf(si, wo, wi);
    bool ok = rel_diff(p_joint, p) <= 1e-6;
    for (int k = 0; k < 3; ++k) ok = ok && rel_diff(f_joint[k], f[k]) <= 1e-6;
    if (!ok && n_bad_eval_pdf++ == 0)
      first_problem += " eval_pdf (" + std::to_string(f_joint.x) + ", " + std::to_string(p_joint) + ") vs eval/pdf (" +
                       std::to_string(f.x) + ", " + std::to_string(p) + ");";
  };
  for (int i = 0; i < 2000; ++i) {
    sg::BsdfSample bs;
    if (mat.sample(si, wo, rng.next_float(), rng.next_2d(), &bs)) check_eval_pdf(bs.wi);
    check_eval_pdf(to_f(random_unit(rng)));
  }
  EXPECT_EQ(n_bad_eval_pdf, 0) << what << ":" << first_problem;
  EXPECT_EQ(n_bad_dir, 0) << what << ": sampled directions not unit length";
  EXPECT_EQ(n_bad_pdf, 0) << what << ":" << first_problem;
  EXPECT_EQ(n_bad_weight, 0) << what << ":" << first_problem;
  auto exp = expected_counts(
      g,
      [&](double z, double phi) { return double(mat.pdf(si, wo, to_f(sphere_dir(frame, z, phi)))); },
      double(n_samples), 1e-9, 16);
  EXPECT_LE(sum(exp) / n_samples, 1.0 + 1e-3) << what << ": pdf integrates to more than 1";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << what << ": " << r.message;
}

/// Reciprocity of the BSDF f = eval / |cos_i| on random pairs of directions (ns == ng).
/// The reference cosines are computed in double from the float directions. eval() computes
/// its cosine as a float dot product whose absolute error is bounded by about
/// gamma(3) * sum |a_k b_k| <= 2e-7 (more or less, depending on FMA contraction), i.e. a
/// relative error of 2e-7 / |cos|. For |cos| >= 0.05 on both sides this stays below 1e-5
/// in total, and the pair is held to the 1e-5 relative tolerance; grazing pairs
/// (1e-4 <= |cos| < 0.05) are held to 1e-5 + 4e-7 / min|cos| (the float bound).
inline void check_reciprocity(const sg::Material& mat, uint64_t seed, int pairs = 10000) {
  sg::Pcg32 rng(seed);
  int nonzero = 0, bad = 0, grazing = 0;
  std::string first;
  for (int i = 0; i < pairs; ++i) {
    DVec3 n = random_unit(rng);
    sg::SurfaceInteraction si = make_si(n, n);
    sg::Vec3f a = to_f(random_unit(rng)), b = to_f(random_unit(rng));
    double ca = std::fabs(ddot(to_d(si.ns), to_d(a))), cb = std::fabs(ddot(to_d(si.ns), to_d(b)));
    if (ca < 1e-4 || cb < 1e-4) continue;
    double tol = 1e-5;
    if (std::min(ca, cb) < 0.05) {
      tol += 4e-7 / std::min(ca, cb);
      ++grazing;
    }
    sg::Color eab = mat.eval(si, a, b), eba = mat.eval(si, b, a);  // (wo, wi) = (a, b) and (b, a)
    nonzero += !sg::is_black(eab);
    for (int k = 0; k < 3; ++k) {
      double fab = eab[k] / cb, fba = eba[k] / ca;
      if (rel_diff(fab, fba) > tol) {
        if (bad++ == 0)
          first = std::to_string(fab) + " vs " + std::to_string(fba) + " (cos " + std::to_string(ca) + ", " +
                  std::to_string(cb) + ")";
        break;
      }
    }
  }
  EXPECT_EQ(bad, 0) << "non-reciprocal pairs, first: " << first;
  // About half of random pairs lie on the same side; make sure the test saw reflection,
  // including grazing pairs.
  EXPECT_GT(nonzero, pairs / 4);
  EXPECT_GT(grazing, pairs / 20);
}

/// White furnace: with albedo 1 the Monte Carlo mean of the sample weight (0 for failed
/// samples) is 1 within 1e-3 and no single weight exceeds 1.001; and the integral of
/// eval over the sphere (quadrature, independent of sample()) is 1 within 1e-3.
inline void check_white_furnace(const sg::Material& mat, const sg::SurfaceInteraction& si, const sg::Vec3f& wo,
                                uint64_t seed, const std::string& what, int n_samples = 200000) {
  sg::Pcg32 rng(seed);
  double sum_w = 0.0, max_w = 0.0;
  for (int i = 0; i < n_samples; ++i) {
    sg::BsdfSample bs;
    float u_lobe = rng.next_float();
    sg::Vec2f u = rng.next_2d();
    if (!mat.sample(si, wo, u_lobe, u, &bs)) continue;
    double w = sg::max_component(bs.weight);
    sum_w += sg::luminance(bs.weight);
    max_w = std::max(max_w, w);
  }
  EXPECT_NEAR(sum_w / n_samples, 1.0, 1e-3) << what << ": mean sample weight";
  EXPECT_LE(max_w, 1.001) << what << ": a sample weight exceeds 1 (energy gain)";
  DFrame frame(to_d(si.ng));
  double integral = integrate_2d(
      [&](double z, double phi) {
        return double(sg::luminance(mat.eval(si, wo, to_f(sphere_dir(frame, z, phi)))));
      },
      -1.0, 1.0, 0.0, 2.0 * k_pi_d, 1e-7, 16, 4);
  EXPECT_NEAR(integral, 1.0, 1e-3) << what << ": integral of eval over the sphere";
}

/// The incoming directions used by the material tests: cosines from normal incidence to
/// grazing (0.01) on the front side, and one from the back side.
inline std::vector<double> incoming_cosines() { return {1.0, 0.7, 0.3, 0.1, 0.01, -0.5}; }


/// A Dirac lobe seen by check_sampling_with_deltas: its direction, the probability that
/// sample() returns it (BsdfSample::pdf of a delta sample), its mass (weight * pdf, the
/// fraction of light it reflects or transmits, per channel) and how often it was drawn.
struct DeltaLobe {
  sg::Vec3f wi;
  double probability = 0.0;
  sg::Color mass;
  int count = 0;
};

/// check_sampling for materials with Dirac lobes (a smooth coat, glass, a mix with
/// either). Non-delta samples are checked exactly as in check_sampling (binned against
/// pdf(), weight == eval / pdf, sample pdf == pdf()). Delta samples are grouped by
/// direction (within 1e-4); within a group the reported pdf and mass must be constant
/// (rel 1e-5), and each group becomes one more chi-square cell whose expected count is
/// N * its reported probability. So the test fails if a delta lobe is drawn more or less
/// often than its pdf says, or if pdf() misdescribes the non-delta part. At most 4 delta
/// directions are expected. Returns the delta lobes for analytic checks of their masses.
/// `cell_eps` is the absolute quadrature tolerance per cell (probability units) of the
/// expected counts: 1e-9 as in check_sampling; glossy lobes evaluated in float cannot
/// converge that far (float noise of a cell's integral is ~1e-9) and then recurse to the
/// maximum depth, so their tests pass 1e-7 (an expected-count error of at most 0.1 per
/// cell at 10^6 samples, far below the Poisson noise sqrt(expected)).
inline std::vector<DeltaLobe> check_sampling_with_deltas(const sg::Material& mat, const sg::SurfaceInteraction& si,
                                                        const sg::Vec3f& wo, uint64_t seed, const std::string& what,
                                                        int n_samples = 1000000, double cell_eps = 1e-9) {
  DFrame frame(to_d(si.ng));
  Grid2D g{32, 64, -1.0, 1.0, 0.0, 2.0 * k_pi_d};
  sg::Pcg32 rng(seed);
  std::vector<double> obs(g.size(), 0.0);
  std::vector<DeltaLobe> deltas;
  int n_bad_weight = 0, n_bad_pdf = 0, n_bad_dir = 0, n_bad_delta = 0;
  std::string first_problem;
  for (int i = 0; i < n_samples; ++i) {
    float u_lobe = rng.next_float();
    sg::Vec2f u = rng.next_2d();
    sg::BsdfSample bs;
    if (!mat.sample(si, wo, u_lobe, u, &bs)) continue;
    if (!(std::fabs(sg::length(bs.wi) - 1.f) < 1e-5f)) {
      ++n_bad_dir;
      continue;
    }
    if (bs.flags & sg::k_bsdf_delta) {
      sg::Color mass = bs.weight * bs.pdf;
      DeltaLobe* lobe = nullptr;
      for (auto& d : deltas)
        if (sg::length(d.wi - bs.wi) < 1e-4f) lobe = &d;
      if (!lobe) {
        deltas.push_back({bs.wi, double(bs.pdf), mass, 0});
        lobe = &deltas.back();
      }
      ++lobe->count;
      bool same = bs.pdf > 0.f && rel_diff(bs.pdf, lobe->probability) <= 1e-5;
      for (int k = 0; k < 3; ++k) same = same && rel_diff(mass[k], lobe->mass[k]) <= 1e-5;
      if (!same && n_bad_delta++ == 0)
        first_problem += " delta lobe with varying pdf " + std::to_string(bs.pdf) + " / mass " +
                         std::to_string(mass.x) + ";";
      continue;
    }
    double z, phi;
    sphere_coords(frame, to_d(bs.wi), &z, &phi);
    long c = g.cell(z, phi);
    if (c < 0) {
      ++n_bad_dir;
      continue;
    }
    obs[size_t(c)] += 1.0;
    sg::Color f = mat.eval(si, wo, bs.wi);
    float pdf = mat.pdf(si, wo, bs.wi);
    if (!(std::fabs(pdf - bs.pdf) <= 1e-4 * std::max(pdf, bs.pdf) + 1e-6)) {
      if (n_bad_pdf++ == 0)
        first_problem += " pdf mismatch: sample " + std::to_string(bs.pdf) + " vs pdf() " + std::to_string(pdf) + ";";
    }
    bool weight_ok = pdf > 0.f;
    for (int k = 0; k < 3 && weight_ok; ++k) weight_ok = rel_diff(bs.weight[k], f[k] / pdf) <= 1e-4;
    if (!weight_ok && n_bad_weight++ == 0)
      first_problem += " weight " + std::to_string(bs.weight.x) + " vs eval/pdf " + std::to_string(f.x / pdf) + ";";
  }
  EXPECT_EQ(n_bad_dir, 0) << what << ": sampled directions not unit length";
  EXPECT_EQ(n_bad_pdf, 0) << what << ":" << first_problem;
  EXPECT_EQ(n_bad_weight, 0) << what << ":" << first_problem;
  EXPECT_EQ(n_bad_delta, 0) << what << ":" << first_problem;
  EXPECT_LE(deltas.size(), 4u) << what << ": more delta directions than expected";
  auto exp = expected_counts(
      g,
      [&](double z, double phi) { return double(mat.pdf(si, wo, to_f(sphere_dir(frame, z, phi)))); },
      double(n_samples), cell_eps, 16);
  for (const auto& d : deltas) {
    obs.push_back(double(d.count));
    exp.push_back(double(n_samples) * d.probability);
  }
  EXPECT_LE(sum(exp) / n_samples, 1.0 + 1e-3) << what << ": pdf plus delta probabilities exceed 1";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << what << ": " << r.message;
  return deltas;
}

/// Directional albedo of the non-delta lobes: the integral of luminance(eval) over the
/// sphere, as a sum of per-cell adaptive quadratures on the check_sampling grid (so that
/// narrow glossy lobes are resolved), independent of sample().
inline double eval_integral(const sg::Material& mat, const sg::SurfaceInteraction& si, const sg::Vec3f& wo,
                            double cell_eps = 1e-9) {
  DFrame frame(to_d(si.ng));
  Grid2D g{32, 64, -1.0, 1.0, 0.0, 2.0 * k_pi_d};
  return sum(expected_counts(
      g,
      [&](double z, double phi) {
        return double(sg::luminance(mat.eval(si, wo, to_f(sphere_dir(frame, z, phi)))));
      },
      1.0, cell_eps, 16));
}

}  // namespace sgtest
