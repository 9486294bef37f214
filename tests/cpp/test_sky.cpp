// Light "sky" (light/sky.cpp): Preetham et al. 1999 daylight with the sun disc.
//
// The model's zenith formulas are re-implemented here in double precision from the paper
// (appendix A.2); directions follow the documented convention: the sun is at
// (cos(el) sin(az), sin(el), -cos(el) cos(az)), y up.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "chi2.h"
#include "dome_checks.h"
#include "core/error.h"
#include "core/params.h"
#include "core/rng.h"
#include "light/light.h"

using namespace sg;
using namespace sgtest;

namespace {

constexpr double k_sun_half_angle_deg = 0.265;

struct SkyParams {
  double elevation = 45.0, azimuth = 0.0, turbidity = 3.0;
  bool sun = true;
  Color albedo = Color(0.2f);
};

std::shared_ptr<Light> make_sky(const SkyParams& s) {
  ParamSet p;
  p.set("elevation", s.elevation);
  p.set("azimuth", s.azimuth);
  p.set("turbidity", s.turbidity);
  p.set("sun", s.sun);
  p.set("ground_albedo", std::vector<double>{s.albedo.x, s.albedo.y, s.albedo.z});
  return create_light("sky", p, "light 0");
}


/// Preetham appendix A.2 zenith luminance (kcd/m^2).
double preetham_zenith_luminance(double t, double elevation_deg) {
  double theta_s = k_pi_d / 2.0 - deg(elevation_deg);
  double chi = (4.0 / 9.0 - t / 120.0) * (k_pi_d - 2.0 * theta_s);
  return (4.0453 * t - 4.9710) * std::tan(chi) - 0.2155 * t + 2.4192;
}
/// Preetham appendix A.2 zenith chromaticities.
void preetham_zenith_xy(double t, double elevation_deg, double* x, double* y) {
  double ts = k_pi_d / 2.0 - deg(elevation_deg), t2 = ts * ts, t3 = t2 * ts;
  *x = t * t * (0.00166 * t3 - 0.00375 * t2 + 0.00209 * ts) +
       t * (-0.02903 * t3 + 0.06377 * t2 - 0.03202 * ts + 0.00394) +
       (0.11693 * t3 - 0.21196 * t2 + 0.06052 * ts + 0.25886);
  *y = t * t * (0.00275 * t3 - 0.00610 * t2 + 0.00317 * ts) +
       t * (-0.04214 * t3 + 0.08970 * t2 - 0.04153 * ts + 0.00516) +
       (0.15346 * t3 - 0.26756 * t2 + 0.06670 * ts + 0.26688);
}
/// Preetham appendix A.2 Perez coefficients (A..E) of Y, x and y for turbidity t.
void preetham_perez(double t, int channel, double k[5]) {
  static const double m[3][5][2] = {
      {{0.1787, -1.4630}, {-0.3554, 0.4275}, {-0.0227, 5.3251}, {0.1206, -2.5771}, {-0.0670, 0.3703}},
      {{-0.0193, -0.2592}, {-0.0665, 0.0008}, {-0.0004, 0.2125}, {-0.0641, -0.8989}, {-0.0033, 0.0452}},
      {{-0.0167, -0.2608}, {-0.0950, 0.0092}, {-0.0079, 0.2102}, {-0.0441, -1.6537}, {-0.0109, 0.0529}}};
  for (int i = 0; i < 5; ++i) k[i] = m[channel][i][0] * t + m[channel][i][1];
}
/// Perez et al.'s F(theta, gamma) from the cosine of theta and the angle gamma.
double perez_f(const double k[5], double cos_theta, double gamma) {
  return (1.0 + k[0] * std::exp(k[1] / cos_theta)) *
         (1.0 + k[2] * std::exp(k[3] * gamma) + k[4] * std::cos(gamma) * std::cos(gamma));
}
/// The sky's Y (kcd/m^2), x, y in unit direction d above the horizon: zenith value x
/// F(theta, gamma) / F(0, theta_s), Preetham sec. 3 and appendix A.2, all in double.
DVec3 preetham_xyY(double t, double elevation_deg, double azimuth_deg, const DVec3& d) {
  const double el = deg(elevation_deg), az = deg(azimuth_deg), theta_s = k_pi_d / 2.0 - el;
  const DVec3 s{std::cos(el) * std::sin(az), std::sin(el), -std::cos(el) * std::cos(az)};
  const double gamma = std::acos(std::clamp(ddot(d, s), -1.0, 1.0));
  double zenith[3] = {preetham_zenith_luminance(t, elevation_deg), 0, 0};
  preetham_zenith_xy(t, elevation_deg, &zenith[1], &zenith[2]);
  double v[3];
  for (int c = 0; c < 3; ++c) {
    double k[5];
    preetham_perez(t, c, k);
    v[c] = zenith[c] * perez_f(k, d.y, gamma) / perez_f(k, 1.0, theta_s);
  }
  return {v[0], v[1], v[2]};
}
/// Linear sRGB -> CIE XYZ (IEC 61966-2-1, D65).
DVec3 rgb_to_xyz(const Color& c) {
  return {0.4124564 * c.x + 0.3575761 * c.y + 0.1804375 * c.z, 0.2126729 * c.x + 0.7151522 * c.y + 0.0721750 * c.z,
          0.0193339 * c.x + 0.1191920 * c.y + 0.9503041 * c.z};
}

/// Sun irradiance on a surface facing it: disc radiance x solid angle of the disc.
DVec3 sun_normal_irradiance(const Light& with_sun, const Light& without_sun, const DVec3& sun_dir) {
  Color l = with_sun.le(to_f(sun_dir)) - without_sun.le(to_f(sun_dir));
  double omega = 2.0 * k_pi_d * (1.0 - std::cos(deg(k_sun_half_angle_deg)));
  return {l.x * omega, l.y * omega, l.z * omega};
}

}  // namespace

// At the zenith the Perez ratio is 1, so the sky's luminance there is Preetham's zenith
// luminance Y_z (kcd/m^2, here / 683 lm/W) and its chromaticity (x_z, y_z).
TEST(sky, zenith_matches_preetham_formulas) {
  for (double t : {2.0, 3.0, 6.0, 10.0})
    for (double el : {5.0, 20.0, 45.0, 70.0, 89.0}) {
      SkyParams s;
      s.turbidity = t;
      s.elevation = el;
      s.sun = false;
      auto sky = make_sky(s);
      DVec3 xyz = rgb_to_xyz(sky->le(Vec3f(0.f, 1.f, 0.f)));
      double y_kcd = xyz.y * 683.0 / 1000.0;
      EXPECT_NEAR(y_kcd / preetham_zenith_luminance(t, el), 1.0, 1e-4) << "T " << t << ", elevation " << el;
      double x_z, y_z;
      preetham_zenith_xy(t, el, &x_z, &y_z);
      double sum = xyz.x + xyz.y + xyz.z;
      EXPECT_NEAR(xyz.x / sum, x_z, 1e-4) << "T " << t << ", elevation " << el;
      EXPECT_NEAR(xyz.y / sum, y_z, 1e-4) << "T " << t << ", elevation " << el;
    }
  // A clear sky's zenith is blue.
  SkyParams s;
  s.turbidity = 2.0;
  Color z = make_sky(s)->le(Vec3f(0.f, 1.f, 0.f));
  EXPECT_GT(z.z, 1.5f * z.x);
}

// Circumsolar brightening: for a clear sky, directions near the sun are brighter than the
// same elevation on the other side of the sky, and brightness falls with the angle to the sun.
// The sky's radiance over the whole upper hemisphere (its luminance and chromaticity) against the
// model evaluated in double from the paper: the renderer evaluates it in float, with fast_atan2
// for the angle to the sun; 2e-5 relative bounds what float rounding may do (the largest errors
// seen are printed), far below the model's own few percent.
TEST(sky, radiance_matches_preetham_model_in_double) {
  Pcg32 rng(11);
  double worst_y = 0.0, worst_xy = 0.0;
  for (double t : {2.0, 3.0, 6.0, 10.0})
    for (double el : {3.0, 20.0, 45.0, 80.0}) {
      SkyParams sp;
      sp.turbidity = t;
      sp.elevation = el;
      sp.azimuth = 30.0 * el;
      sp.sun = false;
      auto sky = make_sky(sp);
      const double to_kcd = 683.0 / 1000.0;  // radiance units -> kcd/m^2 (luminance / 683, strength 1)
      for (int i = 0; i < 4000; ++i) {
        // Uniform over the upper hemisphere, down to 1e-4 above the horizon.
        double cos_t = std::max(1e-4, double(rng.next_float())), phi = 2.0 * k_pi_d * rng.next_float();
        double sin_t = std::sqrt(1.0 - cos_t * cos_t);
        DVec3 d{sin_t * std::sin(phi), cos_t, -sin_t * std::cos(phi)};
        const DVec3 ref = preetham_xyY(t, el, sp.azimuth, d);
        const DVec3 xyz = rgb_to_xyz(sky->le(to_f(d)));
        const double sum = xyz.x + xyz.y + xyz.z;
        ASSERT_NEAR(xyz.y * to_kcd / ref.x, 1.0, 2e-5) << "T " << t << ", elevation " << el << ", direction " << i;
        ASSERT_NEAR(xyz.x / sum, ref.y, 2e-5) << "T " << t << ", elevation " << el << ", direction " << i;
        ASSERT_NEAR(xyz.y / sum, ref.z, 2e-5) << "T " << t << ", elevation " << el << ", direction " << i;
        worst_y = std::max(worst_y, std::fabs(xyz.y * to_kcd / ref.x - 1.0));
        worst_xy = std::max({worst_xy, std::fabs(xyz.x / sum - ref.y), std::fabs(xyz.y / sum - ref.z)});
      }
    }
  std::printf("sky vs double model: max relative luminance error %.3g, max chromaticity error %.3g\n", worst_y,
              worst_xy);
}

TEST(sky, brighter_near_sun_than_opposite) {
  for (double t : {2.0, 3.0})
    for (double el : {15.0, 40.0}) {
      SkyParams s;
      s.turbidity = t;
      s.elevation = el;
      s.azimuth = 70.0;
      auto sky = make_sky(s);
      double prev = k_inf;
      for (double d : {2.0, 5.0, 10.0, 20.0, 45.0, 90.0}) {
        double l = luminance(sky->le(to_f(direction(el, 70.0 + d))));
        EXPECT_LT(l, prev) << "T " << t << ", elevation " << el << ", " << d << " degrees from the sun";
        prev = l;
      }
      double near = luminance(sky->le(to_f(direction(el, 75.0))));
      double opposite = luminance(sky->le(to_f(direction(el, 250.0))));
      EXPECT_GT(near, 3.0 * opposite) << "T " << t << ", elevation " << el;
    }
}

// The sun disc lies where elevation and azimuth say, with a 0.53 degree diameter, and its
// samples point there; azimuth 0 is -z, 90 is +x.
TEST(sky, sun_direction_matches_elevation_and_azimuth) {
  struct Case {
    double el, az;
    DVec3 landmark;  // the direction by the documented compass convention
  };
  const Case cases[] = {{3.0, 0.0, {0, 0, -1}}, {3.0, 90.0, {1, 0, 0}}, {3.0, 180.0, {0, 0, 1}},
                        {3.0, 270.0, {-1, 0, 0}}, {35.0, 123.0, {}}, {89.5, 300.0, {0, 1, 0}}};
  for (const Case& c : cases) {
    SkyParams s;
    s.elevation = c.el;
    s.azimuth = c.az;
    s.turbidity = 2.0;
    auto sky = make_sky(s);
    s.sun = false;
    auto no_sun = make_sky(s);
    DVec3 d = direction(c.el, c.az);
    if (c.landmark.x != 0 || c.landmark.y != 0 || c.landmark.z != 0) {
      EXPECT_GT(ddot(d, dnormalize(c.landmark)), std::cos(deg(3.5))) << "elevation " << c.el << ", azimuth " << c.az;
    }
    double sky_l = luminance(no_sun->le(to_f(d)));
    EXPECT_GT(luminance(sky->le(to_f(d))), 100.0 * sky_l) << "no sun at elevation " << c.el << ", azimuth " << c.az;
    // Disc edge: 0.25 degrees from the centre is inside, 0.28 outside (in four directions).
    DFrame f(d);
    for (double phi : {0.0, 1.6, 3.2, 4.8}) {
      auto at = [&](double a) {
        return to_f(f.to_world(std::sin(deg(a)) * std::cos(phi), std::sin(deg(a)) * std::sin(phi), std::cos(deg(a))));
      };
      EXPECT_GT(luminance(sky->le(at(0.25))), 100.0 * sky_l);
      EXPECT_EQ(sky->le(at(0.28)), no_sun->le(at(0.28)));
    }
    // Samples with the sun's radiance point at the disc.
    Pcg32 rng(801);
    int on_sun = 0, off = 0;
    for (int i = 0; i < 20000; ++i) {
      LightSample ls;
      if (!sky->sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls)) continue;
      if (luminance(ls.li) < 100.0 * sky_l) continue;
      ++on_sun;
      off += ddot(to_d(ls.wi), d) < std::cos(deg(0.3));
    }
    EXPECT_GT(on_sun, 1000);
    EXPECT_EQ(off, 0);
  }
}

// Sky sampling (without sun) against pdf_le(), binned in equirectangular (u, v) on a 64 x 32
// grid (4 x 4 table pixels per bin, where the density in (u, v) is piecewise constant).
TEST(sky, sample_direction_chi2) {
  SkyParams s;
  s.elevation = 25.0;
  s.azimuth = 200.0;
  s.sun = false;
  auto sky = make_sky(s);
  Grid2D g{64, 32, 0.0, 1.0, 0.0, 1.0};
  const int n = 1000000;
  Pcg32 rng(802);
  std::vector<double> obs(g.size(), 0.0);
  int failed = 0;
  for (int i = 0; i < n; ++i) {
    LightSample ls;
    if (!sky->sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls)) {
      ++failed;
      continue;
    }
    obs[equirect_cell(g, ls.wi)] += 1.0;
  }
  EXPECT_EQ(failed, 0);
  // Midpoint rule with two nodes per table pixel and axis, none on a pixel edge.
  std::vector<double> exp = equirect_expected_counts(*sky, g, n);
  EXPECT_NEAR(sum(exp) / n, 1.0, 1e-3) << "pdf_le does not integrate to 1";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
}

// With the sun, a sample is a one-sample mixture of disc and table: le()/pdf_le() report
// exactly the sample's values, and the fraction of samples within 0.3 degrees of the sun
// matches the integral of pdf_le over that cone (2-cell chi-square).
TEST(sky, sun_and_sky_mixture_is_consistent) {
  SkyParams s;
  s.elevation = 50.0;
  s.azimuth = 30.0;
  auto sky = make_sky(s);
  const DVec3 sun = direction(s.elevation, s.azimuth);
  const double cone = deg(0.3);
  const int n = 1000000;
  Pcg32 rng(803);
  int inside = 0, bad_le = 0, bad_pdf = 0, failed = 0;
  for (int i = 0; i < n; ++i) {
    LightSample ls;
    if (!sky->sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls)) {
      ++failed;
      continue;
    }
    bad_le += sky->le(ls.wi) != ls.li;
    bad_pdf += sky->pdf_le(ls.wi) != ls.pdf;
    inside += std::atan2(std::sqrt(ddot(dcross(to_d(ls.wi), sun), dcross(to_d(ls.wi), sun))), ddot(to_d(ls.wi), sun)) <=
              cone;
  }
  EXPECT_EQ(failed, 0);
  EXPECT_EQ(bad_le, 0);
  EXPECT_EQ(bad_pdf, 0);
  // Integral of pdf_le over the cone in (tau = theta / cone, phi): adaptive Simpson in tau
  // (the disc edge is a jump) inside a 64-node midpoint rule in phi.
  DFrame frame(sun);
  double p_cone = 0.0;
  for (int j = 0; j < 64; ++j) {
    double phi = 2.0 * k_pi_d * (j + 0.5) / 64;
    p_cone += integrate_1d(
        [&](double tau) {
          return double(sky->pdf_le(to_f(cone_dir(frame, cone, tau, phi)))) * cone_jacobian(cone, tau);
        },
        0.0, 1.0, 1e-9, 22, 4);
  }
  p_cone *= 2.0 * k_pi_d / 64;
  EXPECT_GT(p_cone, 0.1);
  EXPECT_LT(p_cone, 0.9);
  Chi2Result r = chi2_test({double(inside), double(n - inside)}, {n * p_cone, n * (1.0 - p_cone)});
  EXPECT_TRUE(r.ok) << "inside the cone: " << inside << " of " << n << ", expected " << n * p_cone << "; "
                    << r.message;
}

// Light sampling is unbiased: its horizontal irradiance equals quadrature of the sky plus
// the disc's radiance x solid angle x sin(elevation); it grows with the sun's elevation; the
// ground below the horizon has radiance albedo x E_h / pi.
TEST(sky, horizontal_irradiance_and_ground) {
  const Color albedo(0.1f, 0.2f, 0.3f);
  double prev = 0.0;
  for (double el : {5.0, 20.0, 45.0, 70.0, 90.0}) {
    SkyParams s;
    s.elevation = el;
    s.azimuth = 40.0;
    s.albedo = albedo;
    auto sky = make_sky(s);
    s.sun = false;
    auto no_sun = make_sky(s);
    DVec3 e_sky = quadrature_horizontal_irradiance(*no_sun);
    DVec3 e_sun = sun_normal_irradiance(*sky, *no_sun, direction(el, 40.0));
    double sin_el = std::sin(deg(el));
    Color e_mc = to_f(mc_irradiance(*sky, {0, 1, 0}, 400000, 804));
    double expected[3] = {e_sky.x + e_sun.x * sin_el, e_sky.y + e_sun.y * sin_el, e_sky.z + e_sun.z * sin_el};
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(e_mc[k] / expected[k], 1.0, 1e-2) << "elevation " << el << ", channel " << k;
    EXPECT_GT(luminance(e_mc), 1.05 * prev) << "elevation " << el;
    prev = luminance(e_mc);
    Color ground = sky->le(to_f(dnormalize({0.3, -1.0, 0.2})));
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(ground[k] / (albedo[k] * expected[k] / k_pi_d), 1.0, 2e-3) << "elevation " << el << ", channel " << k;
  }
  // A black ground is never sampled.
  SkyParams s;
  s.albedo = Color(0.f);
  auto sky = make_sky(s);
  EXPECT_EQ(sky->le(Vec3f(0.f, -1.f, 0.f)), Color(0.f));
  Pcg32 rng(805);
  int below = 0;
  for (int i = 0; i < 100000; ++i) {
    LightSample ls;
    if (sky->sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls)) below += ls.wi.y < 0.f;
  }
  EXPECT_EQ(below, 0);
}

// The sun's radiance follows the atmosphere: about 100 klx of direct normal illuminance at
// the zenith on a clear day (T = 2), less with haze, and redder towards the horizon.
TEST(sky, sun_radiance_is_physical) {
  auto normal_illuminance = [](double el, double t, Color* rgb) {
    SkyParams s;
    s.elevation = el;
    s.turbidity = t;
    auto sky = make_sky(s);
    s.sun = false;
    auto no_sun = make_sky(s);
    DVec3 e = sun_normal_irradiance(*sky, *no_sun, direction(el, 0.0));
    *rgb = to_f(e);
    return 683.0 * luminance(*rgb);
  };
  Color zenith_rgb, low_rgb, hazy_rgb;
  double e_clear = normal_illuminance(90.0, 2.0, &zenith_rgb);
  EXPECT_GT(e_clear, 85e3);
  EXPECT_LT(e_clear, 130e3);
  EXPECT_LT(normal_illuminance(90.0, 6.0, &hazy_rgb), 0.8 * e_clear);
  EXPECT_LT(normal_illuminance(10.0, 2.0, &low_rgb), 0.5 * e_clear);
  EXPECT_GT(low_rgb.x / low_rgb.z, 1.5 * zenith_rgb.x / zenith_rgb.z) << "the low sun is not redder";
}

TEST(sky, power_and_visibility) {
  SkyParams s;
  s.sun = false;
  s.albedo = Color(0.f);  // so that the sun does not change the ground's radiance
  auto sky = make_sky(s);
  EXPECT_TRUE(sky->is_infinite());
  EXPECT_FALSE(sky->is_delta());
  EXPECT_TRUE(sky->visible_to_camera());
  Bounds3 b;
  b.expand(Vec3f(-1.f, -1.f, -1.f));
  b.expand(Vec3f(1.f, 1.f, 1.f));  // radius sqrt(3)
  sky->preprocess(b);
  // pi r^2 x 4 pi x mean luminance (by quadrature over the sphere; the sampling table is
  // a pixel-centre approximation of it).
  const double mean = sphere_mean_luminance(*sky);
  EXPECT_NEAR(sky->power() / (k_pi_d * 3.0 * 4.0 * k_pi_d * mean), 1.0, 1e-2);
  // The sun adds its irradiance x pi r^2.
  s.sun = true;
  auto with_sun = make_sky(s);
  with_sun->preprocess(b);
  DVec3 e_sun = sun_normal_irradiance(*with_sun, *sky, direction(s.elevation, s.azimuth));
  EXPECT_NEAR((with_sun->power() - sky->power()) / (k_pi_d * 3.0 * luminance(to_f(e_sun))), 1.0, 1e-3);
  ParamSet hidden;
  hidden.set("visible", false);
  EXPECT_FALSE(create_light("sky", hidden, "l")->visible_to_camera());
}

TEST(sky, parameter_errors) {
  auto message = [](const std::string& key, ParamSet::Value v) {
    ParamSet p;
    p.set(key, v);
    try {
      create_light("sky", p, "light 4");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string m = message("elevation", 95.0);
  EXPECT_NE(m.find("'elevation'"), std::string::npos) << m;
  EXPECT_NE(m.find("[0, 90]"), std::string::npos) << m;
  m = message("elevation", -1.0);
  EXPECT_NE(m.find("'elevation'"), std::string::npos) << m;
  m = message("turbidity", 1.0);
  EXPECT_NE(m.find("'turbidity'"), std::string::npos) << m;
  EXPECT_NE(m.find("[1.7, 10]"), std::string::npos) << m;
  m = message("turbidity", 12.0);
  EXPECT_NE(m.find("[1.7, 10]"), std::string::npos) << m;
  m = message("ground_albedo", 1.5);
  EXPECT_NE(m.find("'ground_albedo'"), std::string::npos) << m;
  EXPECT_NE(m.find("[0, 1]"), std::string::npos) << m;
  m = message("strength", -2.0);
  EXPECT_NE(m.find("'strength'"), std::string::npos) << m;
  m = message("turbidty", 3.0);
  EXPECT_NE(m.find("did you mean 'turbidity'"), std::string::npos) << m;
  m = message("azimuth", double(NAN));
  EXPECT_NE(m.find("'azimuth'"), std::string::npos) << m;
}

// The renderer samples a sky with a sun as two lights (Light::parts): its dome (a dome light,
// sampled by the table) and its sun (not a dome): their radiances add up to the sky's, each
// part's samples report their own pdf, and the powers add up to the sky's. Without a sun the
// sky is its own one part.
TEST(sky, parts_are_the_dome_and_the_sun) {
  SkyParams s;
  s.elevation = 35.0;
  s.azimuth = 120.0;
  auto sky = make_sky(s);
  Bounds3 b;
  b.expand(Vec3f(-3.f, 0.f, -3.f));
  b.expand(Vec3f(3.f, 2.f, 3.f));
  sky->preprocess(b);
  std::vector<const Light*> parts = sky->parts();
  ASSERT_EQ(parts.size(), 2u);
  const Light* dome = parts[0];
  const Light* sun = parts[1];
  EXPECT_TRUE(dome->is_dome());
  EXPECT_FALSE(sun->is_dome());
  EXPECT_TRUE(dome->is_infinite() && sun->is_infinite());
  EXPECT_NEAR(dome->power() + sun->power(), sky->power(), 1e-4 * sky->power());
  Pcg32 rng(611);
  for (int i = 0; i < 20000; ++i) {
    Vec3f d = to_f(dnormalize({rng.next_float() - 0.5, rng.next_float() - 0.5, rng.next_float() - 0.5}));
    if (i % 2) d = normalize(to_f(direction(35.0, 120.0)) + 0.003f * d);  // at and around the disc
    Color sum = dome->le(d) + sun->le(d);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(sum[k], sky->le(d)[k], 1e-5f * std::max(1.f, sky->le(d)[k]));
    for (const Light* part : parts) {
      LightSample ls;
      if (!part->sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls)) continue;
      EXPECT_EQ(ls.pdf, part->pdf_le(ls.wi));
      EXPECT_EQ(ls.li, part->le(ls.wi));
    }
  }
  s.sun = false;
  auto no_sun = make_sky(s);
  ASSERT_EQ(no_sun->parts().size(), 1u);
  EXPECT_EQ(no_sun->parts()[0], no_sun.get());
}
