// core/sampling.h: chi-square goodness-of-fit of every warp against its pdf, pdf
// normalization, output domains, and the discrete Distribution1D.
//
// Expected cell counts always come from integrating the *pdf function* over each cell
// (adaptive Simpson, tests/cpp/chi2.h), never from the warp itself. Significance: see
// k_chi2_alpha in chi2.h (0.01 overall, Bonferroni-corrected over the suite).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "chi2.h"
#include "core/error.h"
#include "core/rng.h"
#include "core/sampling.h"

using namespace sg;
using namespace sgtest;

namespace {

constexpr int k_samples = 1000000;

DVec3 to_d(const Vec3f& v) { return {v.x, v.y, v.z}; }
Vec3f to_f(const DVec3& v) { return Vec3f(float(v.x), float(v.y), float(v.z)); }

/// Histogram of a spherical warp in (cos theta, phi) around +z; counts samples outside
/// the expected domain in *bad.
template <class Warp, class InDomain>
std::vector<double> sphere_histogram(const Grid2D& g, Warp warp, InDomain in_domain, uint64_t seed, int* bad,
                                     std::string* first_bad) {
  DFrame frame(DVec3{0, 0, 1});
  Pcg32 rng(seed);
  std::vector<double> h(g.size(), 0.0);
  *bad = 0;
  for (int i = 0; i < k_samples; ++i) {
    Vec2f u = rng.next_2d();
    Vec3f v = warp(u);
    bool ok = std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) &&
              std::fabs(length(v) - 1.f) < 1e-5f && in_domain(v);
    double z, phi;
    sphere_coords(frame, to_d(v), &z, &phi);
    long c = g.cell(z, phi);
    if (!ok || c < 0) {
      if ((*bad)++ == 0)
        *first_bad = "u = (" + std::to_string(u.x) + ", " + std::to_string(u.y) + ") -> (" + std::to_string(v.x) +
                     ", " + std::to_string(v.y) + ", " + std::to_string(v.z) + ")";
      continue;
    }
    h[size_t(c)] += 1.0;
  }
  return h;
}

}  // namespace

// The chi-square machinery itself: known quantiles of the chi-square distribution and
// exact integrals, so that a broken helper cannot make the warp tests vacuous.
TEST(sampling, chi2_helper_reference_values) {
  // Critical values from standard tables.
  EXPECT_NEAR(chi2_sf(3.841459, 1), 0.05, 1e-6);
  EXPECT_NEAR(chi2_sf(23.209251, 10), 0.01, 1e-6);
  EXPECT_NEAR(chi2_sf(135.806723, 100), 0.01, 1e-6);
  EXPECT_NEAR(chi2_cdf(2.0, 2), 1.0 - std::exp(-1.0), 1e-12);  // dof 2 is exponential
  EXPECT_NEAR(chi2_sf(1118.95, 1000), 0.005, 2e-4);
  // A test of a fair die with a loaded face must fail, a fair histogram must pass.
  std::vector<double> expected(6, 1000.0), fair = {1010, 990, 1003, 980, 1025, 992},
                                           loaded = {1200, 960, 960, 960, 960, 960};
  EXPECT_TRUE(chi2_test(fair, expected, 0.01).ok);
  EXPECT_FALSE(chi2_test(loaded, expected, 0.01).ok);
  // Quadrature: smooth and discontinuous integrands.
  EXPECT_NEAR(integrate_1d([](double x) { return std::sin(x); }, 0.0, k_pi_d, 1e-12), 2.0, 1e-9);
  EXPECT_NEAR(integrate_2d([](double x, double y) { return x + y <= 1.0 ? 1.0 : 0.0; }, 0, 1, 0, 1, 1e-8), 0.5,
              1e-5);
}

TEST(sampling, sincos_2pi_matches_double_precision) {
  double max_err = 0.0;
  auto check = [&](float u) {
    float s, c;
    sincos_2pi(u, &s, &c);
    double a = 2.0 * 3.14159265358979323846 * double(u);
    max_err = std::max({max_err, std::fabs(s - std::sin(a)), std::fabs(c - std::cos(a))});
  };
  for (uint32_t i = 0; i <= 1u << 20; ++i) check(float(i) * 0x1p-20f);
  for (float u : {0.f, 0.125f, 0.25f, 0.375f, 0.5f, 0.625f, 0.75f, 0.875f, 0x1.fffffep-1f, 1e-30f}) check(u);
  EXPECT_LT(max_err, 2e-7);
  // Exact at the quarter turns (no spurious sign or rounding: directions along the axes stay on them).
  float s, c;
  sincos_2pi(0.25f, &s, &c);
  EXPECT_EQ(s, 1.f);
  EXPECT_EQ(c, 0.f);
  sincos_2pi(0.5f, &s, &c);
  EXPECT_EQ(c, -1.f);
}

TEST(sampling, fast_atan2_matches_double_precision) {
  double max_err = 0.0;
  auto check = [&](float y, float x) {
    const double e = std::fabs(double(fast_atan2(y, x)) - std::atan2(double(y), double(x)));
    max_err = std::max(max_err, e);
  };
  // Every octant, on circles of several radii (the reduction is scale-free), and the axes.
  for (uint32_t i = 0; i < 1u << 18; ++i) {
    const double a = 2.0 * 3.14159265358979323846 * (double(i) + 0.5) / double(1u << 18) - 3.14159265358979323846;
    for (double r : {1e-30, 1e-3, 1.0, 7e5}) check(float(r * std::sin(a)), float(r * std::cos(a)));
  }
  for (float y : {0.f, -0.f, 1.f, -1.f, 1e-38f, 3e38f})
    for (float x : {1.f, -1.f, 1e-38f, -1e-38f, 3e38f, -3e38f}) check(y, x);
  EXPECT_LT(max_err, 3e-7);  // the polynomial's 1e-7 and the rounding of pi - r (ulp(pi) = 2.4e-7)
  // Signs and quadrants as std::atan2: the negative x axis is +pi above it and -pi below.
  EXPECT_FLOAT_EQ(fast_atan2(0.f, -1.f), k_pi);
  EXPECT_FLOAT_EQ(fast_atan2(-0.f, -1.f), -k_pi);
  EXPECT_FLOAT_EQ(fast_atan2(1.f, 0.f), 0.5f * k_pi);
  EXPECT_FLOAT_EQ(fast_atan2(-1.f, 0.f), -0.5f * k_pi);
  EXPECT_EQ(fast_atan2(0.f, 0.f), 0.f);
  EXPECT_TRUE(std::isnan(fast_atan2(std::nanf(""), 1.f)));
}

TEST(sampling, cosine_hemisphere_chi2) {
  Grid2D g{32, 64, -1.0, 1.0, 0.0, 2.0 * k_pi_d};
  int bad;
  std::string first_bad;
  auto obs = sphere_histogram(g, square_to_cosine_hemisphere, [](const Vec3f& v) { return v.z >= 0.f; }, 1, &bad,
                              &first_bad);
  EXPECT_EQ(bad, 0) << "samples outside the hemisphere, first: " << first_bad;
  DFrame frame(DVec3{0, 0, 1});
  auto exp = expected_counts(g, [&](double z, double phi) {
    return double(cosine_hemisphere_pdf(to_f(sphere_dir(frame, z, phi))));
  }, k_samples);
  EXPECT_NEAR(sum(exp) / k_samples, 1.0, 1e-4) << "cosine_hemisphere_pdf does not integrate to 1";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
}

TEST(sampling, uniform_sphere_chi2) {
  Grid2D g{32, 64, -1.0, 1.0, 0.0, 2.0 * k_pi_d};
  int bad;
  std::string first_bad;
  auto obs = sphere_histogram(g, square_to_uniform_sphere, [](const Vec3f&) { return true; }, 2, &bad, &first_bad);
  EXPECT_EQ(bad, 0) << "samples off the unit sphere, first: " << first_bad;
  auto exp = expected_counts(g, [&](double, double) { return double(uniform_sphere_pdf()); }, k_samples);
  EXPECT_NEAR(sum(exp) / k_samples, 1.0, 1e-5) << "uniform_sphere_pdf does not integrate to 1";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
}

// Cones from wider than a hemisphere down to the sun (0.53 degree diameter, half-angle
// 0.265 degrees). Binned in the cone-local parameterization (theta / theta_max, phi) so
// that cells cover the cone for every size. theta_max is the exact angle of the float
// cos_theta_max the warp receives. For the sun, 1 - cos_theta_max is only ~180 float ulps
// of 1, so the warp must produce continuously distributed directions within the cone
// without deriving them from a float cos(theta) (which can take only ~180 values there).
class SamplingCone : public ::testing::TestWithParam<double> {};

TEST_P(SamplingCone, uniform_cone_chi2_and_domain) {
  const double half_angle_deg = GetParam();
  const float cos_max = float(std::cos(half_angle_deg * k_pi_d / 180.0));
  // Exact half-angle of the float cosine: 1 - c = 2 sin^2(theta / 2).
  const double theta_max = 2.0 * std::asin(std::sqrt(0.5 * (1.0 - double(cos_max))));
  DFrame frame(DVec3{0, 0, 1});
  Grid2D g{16, 32, 0.0, 1.0, 0.0, 2.0 * k_pi_d};
  Pcg32 rng(3 + uint64_t(half_angle_deg * 1000));
  std::vector<double> obs(g.size(), 0.0);
  int bad = 0;
  std::string first_bad;
  for (int i = 0; i < k_samples; ++i) {
    Vec2f u = rng.next_2d();
    Vec3f v = square_to_uniform_cone(u, cos_max);
    double tau, phi;
    cone_coords(frame, theta_max, to_d(v), &tau, &phi);
    bool ok = is_finite(v) && std::fabs(length(v) - 1.f) < 1e-5f && v.z >= cos_max;
    // The float result may overshoot the cone by rounding; a relative 1e-4 of the angle
    // (tau <= 1 + 1e-4) is accepted and clamped into the last ring.
    if (ok && tau > 1.0 && tau <= 1.0 + 1e-4) tau = 1.0;
    long c = g.cell(tau, phi);
    if (!ok || c < 0) {
      if (bad++ == 0)
        first_bad = "u = (" + std::to_string(u.x) + ", " + std::to_string(u.y) + "), tau = " + std::to_string(tau);
      continue;
    }
    obs[size_t(c)] += 1.0;
  }
  EXPECT_EQ(bad, 0) << "samples outside the cone, first: " << first_bad;
  const double pdf = double(uniform_cone_pdf(cos_max));
  auto exp = expected_counts(g, [&](double tau, double) { return pdf * cone_jacobian(theta_max, tau); }, k_samples);
  EXPECT_NEAR(sum(exp) / k_samples, 1.0, 1e-4) << "uniform_cone_pdf does not integrate to 1 over the cone";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << "half-angle " << half_angle_deg << " deg: " << r.message;
}

INSTANTIATE_TEST_SUITE_P(sampling, SamplingCone, ::testing::Values(120.0, 90.0, 60.0, 25.0, 2.5, 0.265));

TEST(sampling, cone_solid_angle_matches_double_precision) {
  for (double deg : {0.01, 0.265, 1.0, 30.0, 89.0}) {
    double a = deg * k_pi_d / 180.0;
    double ref = 2.0 * k_pi_d * (1.0 - std::cos(a));
    EXPECT_NEAR(cone_solid_angle_from_half_angle(float(a)) / ref, 1.0, 1e-5) << deg << " degrees";
  }
}

// Barycentric domain (b1, b2) in the unit square; the documented pdf is 1 / area on the
// triangle, i.e. 2 on {b1, b2 >= 0, b1 + b2 <= 1} and 0 elsewhere. The grid is 37 x 41 so
// that the diagonal b1 + b2 = 1 cuts cells generically.
TEST(sampling, uniform_triangle_chi2_and_domain) {
  auto pdf = [](double b1, double b2) { return (b1 >= 0 && b2 >= 0 && b1 + b2 <= 1.0) ? 2.0 : 0.0; };
  Grid2D g{37, 41, 0.0, 1.0, 0.0, 1.0};
  Pcg32 rng(4);
  std::vector<double> obs(g.size(), 0.0);
  int bad = 0;
  for (int i = 0; i < k_samples; ++i) {
    Vec2f b = square_to_uniform_triangle(rng.next_2d());
    bool ok = b.x >= 0.f && b.y >= 0.f && b.x + b.y <= 1.f + 1e-6f;
    long c = g.cell(b.x, b.y);
    if (!ok || c < 0) {
      ++bad;
      continue;
    }
    obs[size_t(c)] += 1.0;
  }
  EXPECT_EQ(bad, 0) << "barycentrics outside the triangle";
  auto exp = expected_counts(g, pdf, k_samples, 1e-9, 22);
  EXPECT_NEAR(sum(exp) / k_samples, 1.0, 1e-4);
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
}

TEST(sampling, disk_concentric_domain_and_uniformity) {
  // The disk warp underlies the cosine hemisphere; check its domain and area uniformity
  // in polar cells (r^2, phi), whose areas are equal.
  Grid2D g{16, 32, 0.0, 1.0, 0.0, 2.0 * k_pi_d};
  Pcg32 rng(5);
  std::vector<double> obs(g.size(), 0.0);
  int bad = 0;
  for (int i = 0; i < k_samples; ++i) {
    Vec2f d = square_to_uniform_disk_concentric(rng.next_2d());
    double r2 = double(d.x) * d.x + double(d.y) * d.y;
    long c = g.cell(std::min(r2, 1.0), wrap_phi(std::atan2(d.y, d.x)));
    if (!(r2 <= 1.0 + 1e-6) || c < 0) {
      ++bad;
      continue;
    }
    obs[size_t(c)] += 1.0;
  }
  EXPECT_EQ(bad, 0);
  // Density 1/pi on the disk; in (r^2, phi) coordinates dA = 0.5 d(r^2) d(phi).
  auto exp = expected_counts(g, [](double, double) { return 0.5 / k_pi_d; }, k_samples);
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
}

TEST(sampling, distribution1d_chi2) {
  // Irregular weights with zero entries (including first and last) and a dominant bin.
  Pcg32 wrng(6);
  std::vector<float> w(64);
  for (size_t i = 0; i < w.size(); ++i) w[i] = wrng.next_float() * wrng.next_float();
  w[0] = 0.f;
  w[5] = 0.f;
  w[6] = 0.f;
  w[40] = 30.f;
  w[63] = 0.f;
  Distribution1D dist(w);
  ASSERT_EQ(dist.size(), w.size());
  double total = 0.0;
  for (float x : w) total += x;
  EXPECT_NEAR(dist.total() / total, 1.0, 1e-6);
  std::vector<double> expected(w.size());
  for (size_t i = 0; i < w.size(); ++i) {
    expected[i] = k_samples * double(w[i]) / total;
    EXPECT_NEAR(dist.pmf(i), double(w[i]) / total, 1e-6 * double(w[i]) / total + 1e-12) << "bin " << i;
  }
  Pcg32 rng(7);
  std::vector<double> obs(w.size(), 0.0);
  // The remapped u must be uniform on [0, 1) again (it is reused for a further decision).
  Grid2D gu{50, 1, 0.0, 1.0, 0.0, 1.0};
  std::vector<double> obs_u(gu.size(), 0.0);
  int bad = 0;
  for (int i = 0; i < k_samples; ++i) {
    float u = rng.next_float(), pmf = -1.f, ur = -1.f;
    size_t k = dist.sample(u, &pmf, &ur);
    if (k >= w.size() || pmf != dist.pmf(k) || !(ur >= 0.f && ur < 1.f)) {
      ++bad;
      continue;
    }
    obs[k] += 1.0;
    if (k == 40) obs_u[size_t(gu.cell(ur, 0.5))] += 1.0;  // the dominant bin has ~40% of samples
  }
  EXPECT_EQ(bad, 0) << "invalid index, pmf or remapped u";
  Chi2Result r = chi2_test(obs, expected);
  EXPECT_TRUE(r.ok) << r.message;
  auto exp_u = expected_counts(gu, [&](double, double) { return sum(obs_u); }, 1.0);
  Chi2Result ru = chi2_test(obs_u, exp_u);
  EXPECT_TRUE(ru.ok) << "remapped u: " << ru.message;
}

TEST(sampling, distribution1d_edges) {
  Distribution1D d({0.f, 0.f, 2.f, 0.f, 1.f, 0.f});
  EXPECT_EQ(d.sample(0.f), 2u);
  EXPECT_EQ(d.sample(k_one_minus_epsilon), 4u);
  float pmf;
  EXPECT_EQ(d.sample(0.5f, &pmf), 2u);
  EXPECT_FLOAT_EQ(pmf, 2.f / 3.f);
  EXPECT_EQ(d.sample(0.7f, &pmf), 4u);
  EXPECT_FLOAT_EQ(pmf, 1.f / 3.f);
  // All-zero weights fall back to uniform selection.
  Distribution1D z({0.f, 0.f, 0.f, 0.f});
  for (size_t i = 0; i < 4; ++i) EXPECT_FLOAT_EQ(z.pmf(i), 0.25f);
  EXPECT_EQ(z.sample(0.6f), 2u);
  EXPECT_THROW(Distribution1D({1.f, -1.f}), Error);
  EXPECT_THROW(Distribution1D({1.f, std::nanf("")}), Error);
}

// The guide table narrows the search (sampling.cpp): the index, pmf and remapped u must be
// exactly those of a search over the whole table, for every kind of table and every u that
// matters: at and next to each cdf value, each guide threshold j / N, 0 and just below 1.
TEST(sampling, distribution1d_guide_equals_full_search) {
  Pcg32 rng(11);
  size_t checked = 0;
  for (size_t n : {16u, 17u, 100u, 256u, 1000u, 4097u}) {
    for (int kind = 0; kind < 5; ++kind) {
      std::vector<float> w(n);
      for (size_t i = 0; i < n; ++i) {
        float r = rng.next_float();
        switch (kind) {
          case 0: w[i] = 1.f; break;                                          // uniform
          case 1: w[i] = r * r * r * r; break;                                // skewed
          case 2: w[i] = (i % 7 == 0) ? 0.f : r; break;                       // zero bins
          case 3: w[i] = (i == n / 3) ? 1e7f : r * 1e-3f; break;              // one spike
          default: w[i] = (i < n / 2 || i + 1 == n) ? 0.f : std::exp(20.f * r); break;  // zero half
        }
      }
      Distribution1D d(w);
      // The reference: the largest i with cdf[i] <= u over the whole table, then the same
      // zero-bin skipping and remapping (recomputed here from the pmf's partial sums
      // as the class stores them: cdf via the same double sums).
      std::vector<double> cdf_d(n + 1, 0.0);
      for (size_t i = 0; i < n; ++i) cdf_d[i + 1] = cdf_d[i] + w[i];
      std::vector<float> cdf(n + 1);
      for (size_t i = 0; i <= n; ++i) cdf[i] = float(cdf_d[i] / cdf_d[n]);
      cdf[n] = 1.f;
      std::vector<float> us = {0.f, k_one_minus_epsilon};
      for (size_t i = 0; i <= n; ++i) {
        for (float c : {cdf[i], float(i) / float(n)}) {
          us.push_back(c);
          us.push_back(std::nextafter(c, 0.f));
          us.push_back(std::nextafter(c, 1.f));
        }
      }
      for (int k = 0; k < 2000; ++k) us.push_back(rng.next_float());
      for (float u : us) {
        if (!(u >= 0.f && u < 1.f)) continue;
        size_t i = size_t(std::max<ptrdiff_t>(0, (std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()) - 1));
        i = std::min(i, n - 1);
        while (d.pmf(i) == 0.f && i + 1 < n) ++i;
        while (d.pmf(i) == 0.f && i > 0) --i;
        float wd = cdf[i + 1] - cdf[i];
        float r = std::min(std::max(wd > 0.f ? (u - cdf[i]) / wd : 0.f, 0.f), k_one_minus_epsilon);
        float pmf = -1.f, ur = -1.f;
        ASSERT_EQ(d.sample(u, &pmf, &ur), i) << "n " << n << " kind " << kind << " u " << u;
        ASSERT_EQ(pmf, d.pmf(i));
        ASSERT_EQ(ur, r) << "n " << n << " kind " << kind << " u " << u;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100000u);
}

// The quadrant rotation of sincos_2pi is branch-free (selects and sign flips): the same bits
// as the switch it replaced, over a fine grid and every quadrant boundary's neighbours.
TEST(sampling, sincos_2pi_rotation_is_the_quadrant_switch) {
  auto reference = [](float u, float* s_out, float* c_out) {
    float k = std::nearbyint(u * 4.f);
    float a = (u - k * 0.25f) * (2.f * k_pi);
    float a2 = a * a;
    float sa = a * (1.f + a2 * (-1.f / 6 + a2 * (1.f / 120 + a2 * (-1.f / 5040 + a2 * (1.f / 362880)))));
    float ca = 1.f + a2 * (-0.5f + a2 * (1.f / 24 + a2 * (-1.f / 720 + a2 * (1.f / 40320 + a2 * (-1.f / 3628800)))));
    switch (int(k) & 3) {
      case 0: *s_out = sa; *c_out = ca; break;
      case 1: *s_out = ca; *c_out = -sa; break;
      case 2: *s_out = -sa; *c_out = -ca; break;
      default: *s_out = -ca; *c_out = sa; break;
    }
  };
  std::vector<float> us;
  for (uint32_t i = 0; i <= 1u << 18; ++i) us.push_back(float(i) * 0x1p-18f);
  for (float q : {0.125f, 0.375f, 0.625f, 0.875f, 0.25f, 0.5f, 0.75f, 1.f})
    for (float u = q, k = 0; k < 64; ++k, u = std::nextafter(u, 0.f)) us.push_back(u);
  for (float u : us) {
    float s, c, rs, rc;
    sincos_2pi(u, &s, &c);
    reference(u, &rs, &rc);
    ASSERT_EQ(std::memcmp(&s, &rs, 4), 0) << u;
    ASSERT_EQ(std::memcmp(&c, &rc, 4), 0) << u;
  }
}

TEST(sampling, power_heuristic) {
  EXPECT_FLOAT_EQ(power_heuristic(1.f, 1.f), 0.5f);
  EXPECT_FLOAT_EQ(power_heuristic(3.f, 1.f), 0.9f);
  EXPECT_FLOAT_EQ(power_heuristic(3.f, 1.f) + power_heuristic(1.f, 3.f), 1.f);
  EXPECT_EQ(power_heuristic(0.f, 1.f), 0.f);
  EXPECT_EQ(power_heuristic(k_inf, 1.f), 1.f);
}

// Distribution2D: sampled points against pdf() on a grid twice as fine as the cells
// (so the uniformity inside each cell is tested too), with a zero cell and a zero row.
TEST(sampling, distribution2d_chi2) {
  const size_t nu = 7, nv = 5;
  std::vector<float> w(nu * nv);
  for (size_t i = 0; i < w.size(); ++i) w[i] = float(1 + (i * 7919) % 13);
  w[3] = 0.f;                                    // a zero cell
  for (size_t x = 0; x < nu; ++x) w[2 * nu + x] = 0.f;  // a zero row
  w[4 * nu + 6] = 60.f;                          // a dominant cell
  Distribution2D dist(w, nu, nv);
  ASSERT_EQ(dist.width(), nu);
  ASSERT_EQ(dist.height(), nv);
  double total = 0.0;
  for (float x : w) total += x;
  EXPECT_NEAR(dist.total() / total, 1.0, 1e-6);
  // pdf_cell = weight / total * (number of cells): a density on the unit square.
  for (size_t y = 0; y < nv; ++y)
    for (size_t x = 0; x < nu; ++x)
      EXPECT_NEAR(dist.pdf_cell(x, y), w[y * nu + x] / total * double(nu * nv), 1e-5) << x << ", " << y;
  Grid2D g{int(2 * nu), int(2 * nv), 0.0, 1.0, 0.0, 1.0};
  Pcg32 rng(11);
  std::vector<double> obs(g.size(), 0.0);
  int bad = 0;
  for (int i = 0; i < k_samples; ++i) {
    float pdf = -1.f;
    Vec2f p = dist.sample(rng.next_2d(), &pdf);
    if (!(p.x >= 0.f && p.x < 1.f && p.y >= 0.f && p.y < 1.f) || pdf != dist.pdf(p) || !(pdf > 0.f)) {
      ++bad;
      continue;
    }
    obs[size_t(g.cell(p.x, p.y))] += 1.0;
  }
  EXPECT_EQ(bad, 0) << "samples outside [0, 1)^2, or whose pdf differs from pdf() at the point";
  auto exp = expected_counts(g, [&](double x, double y) { return double(dist.pdf(Vec2f(float(x), float(y)))); },
                             k_samples);
  EXPECT_NEAR(sum(exp) / k_samples, 1.0, 1e-4) << "pdf does not integrate to 1";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
}

// Large grids with sizes that are not powers of two: rounding of (i + r) / n must never
// move a sample into a neighbouring cell (pdf(sample) is exactly the sampled cell's pdf).
TEST(sampling, distribution2d_points_stay_in_their_cell) {
  const size_t nu = 4099, nv = 2047;
  std::vector<float> w(nu * nv);
  Pcg32 fill(12);
  for (float& x : w) x = fill.next_float() < 0.5f ? 0.f : fill.next_float();
  Distribution2D dist(w, nu, nv);
  Pcg32 rng(13);
  int bad = 0;
  for (int i = 0; i < 200000; ++i) {
    // Include u close to 1, where the remapped sample is close to the cell's far edge.
    Vec2f u = i % 2 ? rng.next_2d() : Vec2f(k_one_minus_epsilon - rng.next_float() * 1e-6f, rng.next_float());
    float pdf;
    Vec2f p = dist.sample(u, &pdf);
    bad += !(pdf > 0.f) || pdf != dist.pdf(p) || !(p.x < 1.f && p.y < 1.f);
  }
  EXPECT_EQ(bad, 0);
  // All-zero weights fall back to uniform.
  Distribution2D z(std::vector<float>(6, 0.f), 3, 2);
  EXPECT_FLOAT_EQ(z.pdf(Vec2f(0.9f, 0.1f)), 1.f);
  EXPECT_THROW(Distribution2D(std::vector<float>(5, 1.f), 3, 2), Error);
}
