// Medium "homogeneous" (medium/homogeneous.cpp) and the Henyey-Greenstein phase function it
// scatters with (medium/medium.h): the phase function is a density (integrates to 1), its
// samples follow it (chi-square, g in {-0.7, 0, 0.3, 0.9}) and their pdf is its value;
// transmittance is Beer-Lambert over the part of a ray inside the layer; free-flight
// distances follow sigma_t exp(-sigma_t s) inside the layer (chi-square) and pass with
// probability T.
#include <gtest/gtest.h>

#include <cmath>

#include "chi2.h"
#include "core/error.h"
#include "core/params.h"
#include "core/rng.h"
#include "medium/medium.h"

using namespace sg;
using namespace sgtest;

namespace {

Vec3f to_f(const DVec3& v) { return Vec3f(float(v.x), float(v.y), float(v.z)); }
DVec3 to_d(const Vec3f& v) { return {v.x, v.y, v.z}; }
/// A medium's random stream whose first number is u (a multiple of 2^-24).
MediumRng stream_from(float u) { return MediumRng((uint64_t(uint32_t(u * 0x1p24f)) << 8) << 32); }
MediumRng stream_from(Pcg32& rng) { return MediumRng((uint64_t(rng.next_u32()) << 32) | rng.next_u32()); }

std::shared_ptr<Medium> make_fog(double extinction, double top, double bottom = std::nan("")) {
  ParamSet p;
  p.set("extinction", extinction);
  p.set("top", top);
  if (!std::isnan(bottom)) p.set("bottom", bottom);
  p.set("albedo", std::vector<double>{0.9, 0.8, 0.7});
  p.set("g", 0.5);
  return create_medium("homogeneous", p, "medium");
}

}  // namespace

class HenyeyGreensteinTest : public ::testing::TestWithParam<float> {};

TEST_P(HenyeyGreensteinTest, integrates_to_one_and_pdf_is_the_value) {
  const float g = GetParam();
  // Integral over the sphere of p(cos) = 2 pi * integral over cos in [-1, 1].
  const int n = 200000;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    double c = -1.0 + 2.0 * (i + 0.5) / n;
    sum += HenyeyGreenstein::eval(g, float(c)) * 2.0 / n;
  }
  EXPECT_NEAR(sum * 2.0 * k_pi_d, 1.0, 2e-3) << "g " << g;
  HenyeyGreenstein hg{g};
  Pcg32 rng(1201);
  const Vec3f wo = normalize(Vec3f(0.3f, -0.5f, 0.8f));
  for (int i = 0; i < 1000; ++i) {
    float pdf;
    Vec3f wi = hg.sample(wo, rng.next_2d(), &pdf);
    EXPECT_NEAR(length(wi), 1.f, 1e-5f);
    EXPECT_NEAR(pdf, hg.eval(wo, wi), 1e-3f * pdf + 1e-6f);
  }
  // Forward scattering for g > 0: the mean of dot(wi, -wo) is g (the asymmetry parameter).
  double mean = 0.0;
  const int m = 200000;
  for (int i = 0; i < m; ++i) {
    float pdf;
    mean += dot(hg.sample(wo, rng.next_2d(), &pdf), -wo);
  }
  EXPECT_NEAR(mean / m, g, 0.01) << "g " << g;
}

TEST_P(HenyeyGreensteinTest, sample_chi2) {
  const float g = GetParam();
  HenyeyGreenstein hg{g};
  const Vec3f wo = normalize(Vec3f(-0.2f, 0.9f, 0.4f));
  DFrame frame(to_d(wo));
  Grid2D grid{40, 32, -1.0, 1.0, 0.0, 2.0 * k_pi_d};
  const int n = 1000000;
  Pcg32 rng(1202);
  std::vector<double> obs(grid.size(), 0.0);
  for (int i = 0; i < n; ++i) {
    float pdf;
    Vec3f wi = hg.sample(wo, rng.next_2d(), &pdf);
    double z, phi;
    sphere_coords(frame, to_d(wi), &z, &phi);
    obs[size_t(grid.cell(z, phi))] += 1.0;
  }
  // The phase function depends on cos theta alone: each cell's probability is the integral
  // of eval over its cos range (fine midpoint rule: g = 0.9 peaks sharply at cos = -1) times
  // its share of the azimuth. (2D adaptive quadrature of that peak takes minutes.)
  std::vector<double> exp(grid.size());
  for (int ix = 0; ix < grid.nx; ++ix) {
    const int steps = 4000;
    double p = 0.0;
    for (int k = 0; k < steps; ++k) {
      double c = grid.cx0(ix) + (grid.cx1(ix) - grid.cx0(ix)) * (k + 0.5) / steps;
      p += HenyeyGreenstein::eval(g, float(c)) * (grid.cx1(ix) - grid.cx0(ix)) / steps;
    }
    for (int iy = 0; iy < grid.ny; ++iy) exp[size_t(iy) * grid.nx + ix] = n * p * (grid.cy1(iy) - grid.cy0(iy));
  }
  // The azimuth: the sampled directions' value matches eval around the frame too.
  for (int k = 0; k < 100; ++k) {
    DVec3 d = sphere_dir(frame, -1.0 + 2.0 * (k + 0.5) / 100.0, 0.37 * k);
    EXPECT_NEAR(hg.eval(wo, to_f(d)), HenyeyGreenstein::eval(g, float(-1.0 + 2.0 * (k + 0.5) / 100.0)), 1e-3);
  }
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << "g " << g << ": " << r.message;
}

INSTANTIATE_TEST_SUITE_P(homogeneous, HenyeyGreensteinTest, ::testing::Values(-0.7f, 0.f, 0.3f, 0.9f));

TEST(homogeneous, transmittance_is_beer_lambert_inside_the_layer) {
  auto fog = make_fog(0.05, 10.0, -2.0);
  // Horizontal ray at y = 1: inside over its whole length.
  EXPECT_NEAR(fog->transmittance({0, 1, 0}, {1, 0, 0}, 20.f), std::exp(-0.05 * 20.0), 1e-6);
  // Non-unit direction: t in units of |d|.
  EXPECT_NEAR(fog->transmittance({0, 1, 0}, {2, 0, 0}, 10.f), std::exp(-0.05 * 20.0), 1e-6);
  // Straight up from y = 1 to infinity: 9 m inside.
  EXPECT_NEAR(fog->transmittance({0, 1, 0}, {0, 1, 0}, k_inf), std::exp(-0.05 * 9.0), 1e-6);
  // From above the layer down through it, to y = -5: 12 m of the 20 inside.
  EXPECT_NEAR(fog->transmittance({0, 15, 0}, {0, -1, 0}, 20.f), std::exp(-0.05 * 12.0), 1e-6);
  // Slanted: the inside length scales by 1 / sin(elevation).
  Vec3f d = normalize(Vec3f(1, 1, 0));
  EXPECT_NEAR(fog->transmittance({0, 0, 0}, d, k_inf), std::exp(-0.05 * 10.0 * std::sqrt(2.0)), 1e-5);
  // Entirely above: 1; horizontal forever inside: 0.
  EXPECT_EQ(fog->transmittance({0, 11, 0}, {1, 0, 0}, k_inf), 1.f);
  EXPECT_EQ(fog->transmittance({0, 1, 0}, {1, 0, 0}, k_inf), 0.f);
  EXPECT_EQ(fog->albedo(), Color(0.9f, 0.8f, 0.7f));
  EXPECT_EQ(fog->phase().g, 0.5f);
}

TEST(homogeneous, free_flight_distances_chi2_and_pass_probability) {
  // From y = 12 down at 30 degrees below the horizon through the layer [-2, 10] to t_max 30:
  // inside from t = 4 (y 10) to t = 28 (y -2), 24 m; the flight's distance inside is
  // exponential (rate 0.08) and it passes with probability exp(-0.08 * 24).
  const double sigma = 0.08;
  auto fog = make_fog(sigma, 10.0, -2.0);
  const Vec3f o(0, 12, 0), d = normalize(Vec3f(std::sqrt(3.f), -1.f, 0.f));
  const double t0 = 4.0, t1 = 28.0;
  const int n = 400000, bins = 48;
  Pcg32 rng(1203);
  std::vector<double> obs(bins + 1, 0.0);
  for (int i = 0; i < n; ++i) {
    float t;
    MediumRng stream = stream_from(rng);
    if (fog->sample_distance(o, d, 30.f, stream, &t)) {
      ASSERT_GE(t, t0 - 1e-4);
      ASSERT_LT(t, t1 + 1e-4);
      obs[std::min(bins - 1, int((t - t0) / (t1 - t0) * bins))] += 1.0;
    } else {
      obs[bins] += 1.0;
    }
  }
  std::vector<double> exp(bins + 1);
  for (int b = 0; b < bins; ++b) {
    double a = (t1 - t0) * b / bins, c = (t1 - t0) * (b + 1) / bins;
    exp[b] = n * (std::exp(-sigma * a) - std::exp(-sigma * c));
  }
  exp[bins] = n * std::exp(-sigma * (t1 - t0));
  EXPECT_NEAR(exp[bins] / n, fog->transmittance(o, d, 30.f), 1e-5) << "pass probability = T";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
}

TEST(homogeneous, visibility_is_koschmieder_and_bad_parameters_are_errors) {
  ParamSet p;
  p.set("visibility", 100.0);
  auto fog = create_medium("homogeneous", p, "medium");
  // Contrast 2% at the visibility distance: T(V) = exp(-3.912) = 0.02.
  EXPECT_NEAR(fog->transmittance({0, 1, 0}, {1, 0, 0}, 100.f), 0.02, 1e-4);
  ParamSet both = p;
  both.set("extinction", 0.1);
  EXPECT_THROW(create_medium("homogeneous", both, "medium"), Error);
  EXPECT_THROW(create_medium("homogeneous", ParamSet(), "medium"), Error);
  ParamSet bad = p;
  bad.set("g", 1.0);
  EXPECT_THROW(create_medium("homogeneous", bad, "medium"), Error);
  ParamSet upside = p;
  upside.set("top", 1.0);
  upside.set("bottom", 2.0);
  try {
    create_medium("homogeneous", upside, "medium");
    FAIL() << "bottom above top accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bottom"), std::string::npos) << e.what();
  }
}

TEST(homogeneous, points_in_a_segment_chi2_and_scatter_probability) {
  // The free-flight density conditioned on scattering within the segment (decoupled next-event
  // estimation): truncated exponential over the 24 m inside the layer; p_scatter = 1 - T.
  const double sigma = 0.08;
  auto fog = make_fog(sigma, 10.0, -2.0);
  const Vec3f o(0, 12, 0), d = normalize(Vec3f(std::sqrt(3.f), -1.f, 0.f));
  const double t0 = 4.0, t1 = 28.0, p = 1.0 - std::exp(-sigma * (t1 - t0));
  const int n = 400000, bins = 48;
  Pcg32 rng(1204);
  std::vector<double> obs(bins, 0.0);
  for (int i = 0; i < n; ++i) {
    float t, ps;
    MediumRng stream = stream_from(rng);
    ASSERT_TRUE(fog->sample_in_segment(o, d, 30.f, stream, &t, &ps));
    ASSERT_NEAR(ps, p, 1e-5);
    ASSERT_GE(t, t0 - 1e-4);
    ASSERT_LE(t, t1 + 1e-4);
    obs[std::min(bins - 1, int((t - t0) / (t1 - t0) * bins))] += 1.0;
  }
  std::vector<double> exp(bins);
  for (int b = 0; b < bins; ++b) {
    double a = (t1 - t0) * b / bins, c = (t1 - t0) * (b + 1) / bins;
    exp[b] = n * (std::exp(-sigma * a) - std::exp(-sigma * c)) / p;
  }
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
  // A segment above the layer crosses no medium; an infinite one inside scatters for sure.
  float t, ps;
  MediumRng half = stream_from(0.5f), half2 = stream_from(0.5f);
  EXPECT_FALSE(fog->sample_in_segment({0, 11, 0}, {1, 0, 0}, k_inf, half, &t, &ps));
  ASSERT_TRUE(fog->sample_in_segment({0, 1, 0}, {1, 0, 0}, k_inf, half2, &t, &ps));
  EXPECT_EQ(ps, 1.f);
  EXPECT_NEAR(t, std::log(2.0) / sigma, 1e-3);
}
