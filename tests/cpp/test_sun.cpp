// Light "sun" (light/sun.cpp), created through sg::create_light: a distant disc of
// angular diameter 0.53 degrees (half-angle 0.265 degrees), or a delta directional light.
#include <gtest/gtest.h>

#include <cmath>

#include "chi2.h"
#include "core/error.h"
#include "core/params.h"
#include "core/rng.h"
#include "light/light.h"

using namespace sg;
using namespace sgtest;

namespace {

Vec3f to_f(const DVec3& v) { return Vec3f(float(v.x), float(v.y), float(v.z)); }
DVec3 to_d(const Vec3f& v) { return {v.x, v.y, v.z}; }

// Default sun direction; the disc tests below run for several directions.
const DVec3 k_sun_dir = dnormalize({0.3, -0.5, 0.8});
const Color k_irradiance(1000.f, 800.f, 600.f);
constexpr double k_diameter_deg = 0.53;
const double k_half = 0.5 * k_diameter_deg * k_pi_d / 180.0;

std::shared_ptr<Light> make_sun(double diameter_deg = k_diameter_deg, const DVec3& dir = k_sun_dir) {
  ParamSet p;
  p.set("direction", std::vector<double>{dir.x, dir.y, dir.z});
  p.set("irradiance", std::vector<double>{k_irradiance.x, k_irradiance.y, k_irradiance.z});
  p.set("angular_diameter", diameter_deg);
  return create_light("sun", p, "light 0");
}

/// Irradiance on a surface with unit normal n: Monte Carlo mean of li cos / pdf.
Color mc_irradiance(const Light& sun, const DVec3& n, int samples, uint64_t seed) {
  Pcg32 rng(seed);
  double e[3] = {0, 0, 0};
  for (int i = 0; i < samples; ++i) {
    LightSample ls;
    if (!sun.sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls)) continue;
    double c = ddot(n, to_d(ls.wi));
    if (c <= 0.0) continue;
    for (int k = 0; k < 3; ++k) e[k] += double(ls.li[k]) * c / double(ls.pdf);
  }
  return Color(float(e[0] / samples), float(e[1] / samples), float(e[2] / samples));
}

/// Integral of f(tau, phi) over [t0, t1] x [p0, p1]: adaptive Simpson along tau (where
/// the disc edge is a jump, made ragged at the scale of one float ulp of the cosine by
/// le()'s float dot product) inside a 16-point midpoint rule along phi (the integrands are
/// smooth and periodic in phi). Bounded depth, so the ragged edge cannot blow up the cost.
template <class F>
double integrate_tau_phi(const F& f, double t0, double t1, double p0, double p1, double eps) {
  const int m = 16;
  double s = 0.0;
  for (int j = 0; j < m; ++j) {
    double phi = p0 + (p1 - p0) * (j + 0.5) / m;
    s += integrate_1d([&](double tau) { return f(tau, phi); }, t0, t1, eps, 20, 3);
  }
  return s * (p1 - p0) / m;
}

/// Integral over the sphere of f(direction), restricted to a cone of 1.2 half-angles
/// around the sun, in the cone-local parameterization (tau = theta / half, phi).
template <class F>
double integrate_around_sun(const DVec3& sun_dir, const F& f) {
  DFrame frame(sun_dir);
  double s = 0.0;
  for (int j = 0; j < 16; ++j)  // 16 x 16 midpoint nodes in phi
    s += integrate_tau_phi(
        [&](double tau, double phi) { return f(cone_dir(frame, k_half, tau, phi)) * cone_jacobian(k_half, tau); },
        0.0, 1.2, 2.0 * k_pi_d * j / 16, 2.0 * k_pi_d * (j + 1) / 16, 1e-10);
  return s;
}

/// The disc tests run for several sun directions: float rounding of direction components
/// differs between them.
class SunDisc : public ::testing::TestWithParam<DVec3> {
 protected:
  DVec3 dir() const { return dnormalize(GetParam()); }
};

std::string dir_name(const DVec3& d) {
  return "sun direction (" + std::to_string(d.x) + ", " + std::to_string(d.y) + ", " + std::to_string(d.z) + ")";
}

}  // namespace

// Cone sampling around the sun direction against the light's own pdf_le(), binned in
// (theta / half-angle, phi); the outermost ring [1, 1.05] catches samples outside the disc.
TEST_P(SunDisc, sample_direction_chi2) {
  const DVec3 sun_dir = dir();
  auto sun = make_sun(k_diameter_deg, sun_dir);
  DFrame frame(sun_dir);
  Grid2D g{21, 32, 0.0, 1.05, 0.0, 2.0 * k_pi_d};
  const int n = 1000000;
  Pcg32 rng(501 + uint64_t(1000 * std::fabs(sun_dir.x)));
  std::vector<double> obs(g.size(), 0.0);
  int outside = 0;
  for (int i = 0; i < n; ++i) {
    LightSample ls;
    if (!sun->sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls)) continue;
    double tau, phi;
    cone_coords(frame, k_half, to_d(ls.wi), &tau, &phi);
    long c = g.cell(tau, phi);
    if (c < 0) {
      ++outside;
      continue;
    }
    obs[size_t(c)] += 1.0;
  }
  EXPECT_EQ(outside, 0) << "samples farther than 1.05 half-angles from the sun";
  std::vector<double> exp(g.size());
  for (int iy = 0; iy < g.ny; ++iy)
    for (int ix = 0; ix < g.nx; ++ix)
      exp[size_t(iy) * g.nx + ix] = n * integrate_tau_phi(
          [&](double tau, double phi) {
            return double(sun->pdf_le(to_f(cone_dir(frame, k_half, tau, phi)))) * cone_jacobian(k_half, tau);
          },
          g.cx0(ix), g.cx1(ix), g.cy0(iy), g.cy1(iy), 1e-12);
  EXPECT_NEAR(sum(exp) / n, 1.0, 1e-3) << dir_name(sun_dir);
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << dir_name(sun_dir) << ": " << r.message;
}

TEST_P(SunDisc, irradiance_equals_parameter) {
  const DVec3 sun_dir = dir();
  auto sun = make_sun(k_diameter_deg, sun_dir);
  // Facing the sun: E = irradiance (0.1%).
  Color e = mc_irradiance(*sun, sun_dir, 200000, 502);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(e[k] / k_irradiance[k], 1.0, 1e-3) << "channel " << k;
  // A surface tilted by 60 degrees receives E cos(60 deg): irradiance from a uniform disc
  // is linear in the receiver normal while the disc stays above the horizon.
  DFrame frame(sun_dir);
  DVec3 tilted = frame.to_world(std::sin(k_pi_d / 3), 0.0, std::cos(k_pi_d / 3));
  Color e60 = mc_irradiance(*sun, tilted, 200000, 503);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(e60[k] / (0.5 * k_irradiance[k]), 1.0, 1e-3) << "channel " << k;
}

// le() and pdf_le() describe the same disc that sample() samples.
TEST_P(SunDisc, le_and_pdf_le_consistent_with_sample) {
  const DVec3 sun_dir = dir();
  auto sun = make_sun(k_diameter_deg, sun_dir);
  EXPECT_TRUE(sun->is_infinite());
  EXPECT_FALSE(sun->is_delta());
  Pcg32 rng(504);
  int bad_le = 0, bad_pdf = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    LightSample ls;
    ASSERT_TRUE(sun->sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls));
    ASSERT_TRUE(ls.infinite);
    ASSERT_FALSE(ls.delta);
    bad_le += sun->le(ls.wi) != ls.li;
    bad_pdf += sun->pdf_le(ls.wi) != ls.pdf;
  }
  EXPECT_EQ(bad_le, 0) << dir_name(sun_dir) << ": sampled directions where le() differs from the sample's li (of "
                        << n << ")";
  EXPECT_EQ(bad_pdf, 0) << dir_name(sun_dir) << ": sampled directions where pdf_le() differs from the sample's pdf (of "
                        << n << ")";
  // Outside the disc there is no sun.
  DFrame frame(sun_dir);
  for (double tau : {1.01, 1.5, 10.0, 100.0, 600.0}) {
    Vec3f d = to_f(cone_dir(frame, k_half, tau, 1.0));
    EXPECT_TRUE(is_black(sun->le(d))) << "tau " << tau;
    EXPECT_EQ(sun->pdf_le(d), 0.f) << "tau " << tau;
  }
  // pdf_le is a normalized density, and the radiance seen by rays that hit the sun
  // (le, what BSDF sampling sees) produces the nominal irradiance.
  double pdf_integral =
      integrate_around_sun(sun_dir, [&](const DVec3& d) { return double(sun->pdf_le(to_f(d))); });
  EXPECT_NEAR(pdf_integral, 1.0, 1e-3) << dir_name(sun_dir) << ": pdf_le does not integrate to 1";
  double e = integrate_around_sun(sun_dir,
                                  [&](const DVec3& d) { return double(sun->le(to_f(d)).x) * ddot(d, sun_dir); });
  EXPECT_NEAR(e / k_irradiance.x, 1.0, 1e-3) << dir_name(sun_dir) << ": irradiance from le() differs from the parameter";
}

INSTANTIATE_TEST_SUITE_P(sun, SunDisc,
                         ::testing::Values(DVec3{0.3, -0.5, 0.8}, DVec3{0, 0, 1}, DVec3{1, 1, 1},
                                           DVec3{0.718, -0.041, 0.694}));

TEST(sun, delta_sun) {
  auto sun = make_sun(0.0);
  EXPECT_TRUE(sun->is_delta());
  EXPECT_TRUE(sun->is_infinite());
  LightSample ls;
  ASSERT_TRUE(sun->sample({Vec3f(1.f, 2.f, 3.f), Vec3f(0.f)}, Vec2f(0.3f, 0.6f), &ls));
  EXPECT_TRUE(ls.delta);
  EXPECT_TRUE(ls.infinite);
  EXPECT_EQ(ls.pdf, 1.f);
  EXPECT_EQ(ls.li, k_irradiance);
  EXPECT_NEAR(ls.wi.x, k_sun_dir.x, 1e-6);
  EXPECT_NEAR(ls.wi.y, k_sun_dir.y, 1e-6);
  EXPECT_NEAR(ls.wi.z, k_sun_dir.z, 1e-6);
  // A delta light cannot be hit by a ray.
  EXPECT_TRUE(is_black(sun->le(to_f(k_sun_dir))));
  EXPECT_EQ(sun->pdf_le(to_f(k_sun_dir)), 0.f);
}

TEST(sun, power_uses_scene_radius) {
  auto sun = make_sun();
  Bounds3 b;
  b.expand(Vec3f(-1.f, -2.f, -2.f));
  b.expand(Vec3f(1.f, 2.f, 2.f));  // radius 3
  sun->preprocess(b);
  EXPECT_NEAR(sun->power() / (k_pi_d * 9.0 * luminance(k_irradiance)), 1.0, 1e-5);
}

TEST(sun, parameter_errors) {
  ParamSet zero_dir;
  zero_dir.set("direction", std::vector<double>{0.0, 0.0, 0.0});
  EXPECT_THROW(create_light("sun", zero_dir, "l"), Error);
  ParamSet huge;
  huge.set("angular_diameter", 90.0);
  EXPECT_THROW(create_light("sun", huge, "l"), Error);
  ParamSet negative;
  negative.set("irradiance", -1.0);
  EXPECT_THROW(create_light("sun", negative, "l"), Error);
  ParamSet typo;
  typo.set("irradience", 5.0);
  try {
    create_light("sun", typo, "light 2");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'irradiance'"), std::string::npos) << e.what();
  }
}
