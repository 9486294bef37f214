// Light "headlamp" (light/headlamp.cpp): a vehicle headlamp's low or high beam, a point light
// with an intensity pattern around the forward direction.
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
double deg(double d) { return d * k_pi_d / 180.0; }

const DVec3 k_pos{1.0, 0.65, -2.0};

std::shared_ptr<Light> make_lamp(const std::string& beam, const DVec3& forward = {1, 0, 0}, double intensity = 2.0) {
  ParamSet p;
  p.set("position", std::vector<double>{k_pos.x, k_pos.y, k_pos.z});
  p.set("direction", std::vector<double>{forward.x, forward.y, forward.z});
  p.set("intensity", std::vector<double>{intensity, intensity, intensity});
  p.set("beam", beam);
  return create_light("headlamp", p, "light 0");
}

/// The lamp's direction at H degrees to the right of forward +x (right = +z for up +y) and V up.
DVec3 lamp_dir(double h, double v) {
  return {std::cos(deg(v)) * std::cos(deg(h)), std::sin(deg(v)), std::cos(deg(v)) * std::sin(deg(h))};
}

/// Intensity (luminance, W/sr) the lamp sends along the unit direction w: from the sample at a
/// point at distance r along w, li x r^2.
double intensity(const Light& l, const DVec3& w, double r = 3.0) {
  DVec3 p{k_pos.x + r * w.x, k_pos.y + r * w.y, k_pos.z + r * w.z};
  LightSample ls;
  if (!l.sample({to_f(p), Vec3f(0.f)}, Vec2f(0.5f, 0.5f), &ls)) return 0.0;
  return luminance(ls.li) * r * r;
}

}  // namespace

// A sample from a point in the beam is the inverse-square law: li = I(w) / d^2 along the
// direction to the lamp, a delta light (pdf 1) at the lamp's position; nothing behind it.
TEST(headlamp, sample_is_the_inverse_square_law) {
  auto lamp = make_lamp("low");
  EXPECT_TRUE(lamp->is_delta());
  EXPECT_FALSE(lamp->is_infinite());
  const DVec3 w = lamp_dir(3.0, -2.0);
  double i1 = intensity(*lamp, w, 1.0);
  for (double r : {2.0, 5.0, 20.0, 60.0}) {
    DVec3 p{k_pos.x + r * w.x, k_pos.y + r * w.y, k_pos.z + r * w.z};
    LightSample ls;
    ASSERT_TRUE(lamp->sample({to_f(p), Vec3f(0.f)}, Vec2f(0.3f, 0.8f), &ls));
    EXPECT_TRUE(ls.delta);
    EXPECT_EQ(ls.pdf, 1.f);
    EXPECT_NEAR(luminance(ls.li) * r * r / i1, 1.0, 1e-4) << r;
    EXPECT_NEAR(ls.wi.x, -w.x, 1e-5);
    EXPECT_NEAR(ls.wi.y, -w.y, 1e-5);
    EXPECT_NEAR(ls.p_light.x, k_pos.x, 1e-6);
  }
  EXPECT_EQ(intensity(*lamp, lamp_dir(180.0, 0.0)), 0.0);
  EXPECT_EQ(intensity(*lamp, lamp_dir(95.0, -3.0)), 0.0);
}

// The low beam: its maximum (the intensity parameter) just below the cut-off, 1% above it
// (ECE R112's glare points), bright at 50V (0.86 degrees down on the axis), a third or more at
// 25L / 25R (9 degrees aside, 1.72 down), symmetric, and falling towards the road just in front.
// The high beam peaks on the axis. Turning the lamp turns the pattern.
TEST(headlamp, beam_patterns) {
  auto low = make_lamp("low");
  double peak = 0.0;
  for (double h = -30.0; h <= 30.0; h += 0.5)
    for (double v = -15.0; v <= 5.0; v += 0.1) peak = std::max(peak, intensity(*low, lamp_dir(h, v)));
  EXPECT_NEAR(peak / 2.0, 1.0, 1e-3);
  EXPECT_NEAR(intensity(*low, lamp_dir(0.0, -1.2)) / 2.0, 1.0, 1e-3);
  EXPECT_GT(intensity(*low, lamp_dir(0.0, -0.86)) / 2.0, 0.9);
  for (double h : {-3.43, 0.0, 3.43, 20.0}) EXPECT_LT(intensity(*low, lamp_dir(h, 0.57)) / 2.0, 0.0101) << h;
  for (double h : {-9.0, 9.0}) {
    double r = intensity(*low, lamp_dir(h, -1.72)) / 2.0;
    EXPECT_GT(r, 0.3);
    EXPECT_LT(r, 0.6);
  }
  EXPECT_NEAR(intensity(*low, lamp_dir(-12.0, -3.0)), intensity(*low, lamp_dir(12.0, -3.0)), 1e-6);
  EXPECT_LT(intensity(*low, lamp_dir(0.0, -10.0)) / 2.0, 0.1);
  auto high = make_lamp("high");
  EXPECT_NEAR(intensity(*high, lamp_dir(0.0, 0.0)) / 2.0, 1.0, 1e-4);
  EXPECT_GT(intensity(*high, lamp_dir(0.0, 1.0)) / 2.0, 0.9);
  EXPECT_LT(intensity(*high, lamp_dir(0.0, 6.0)) / 2.0, 0.2);
  auto turned = make_lamp("low", {0, 0, -1});  // forward -z: right is +x... (-z) x (+y) = +x
  EXPECT_NEAR(intensity(*turned, {std::sin(deg(4.0)) * std::cos(deg(-2.0)), std::sin(deg(-2.0)),
                                  -std::cos(deg(4.0)) * std::cos(deg(-2.0))}),
              intensity(*low, lamp_dir(4.0, -2.0)), 1e-5);
}

// power() (for light selection) is 4 pi I_max, the flux of an isotropic lamp of the peak
// intensity (pbrt-v4's bounds of spot lights): no direction gets more than power / 4 pi, and
// the peak gets exactly that. The beam itself holds a few percent of it: its solid-angle
// integral (Monte Carlo over uniform directions, 2M samples) lies in 0.02-0.1 sr for a low
// beam (a 15 kcd lamp: 300-1500 lm, real low beams send 500-1000 lm onto the road).
TEST(headlamp, power_bounds_the_intensity) {
  for (const char* beam : {"low", "high"}) {
    auto lamp = make_lamp(beam, {0.3, -0.05, 1.0}, 1.5);
    EXPECT_NEAR(lamp->power() / (4.0 * k_pi_d * 1.5), 1.0, 1e-6) << beam;
    DVec3 f = dnormalize({0.3, -0.05, 1.0});
    DFrame frame(f);
    Pcg32 rng(911);
    const int n = 1000000;
    const double cos_cap = 0.5;  // most of the beam is within 60 degrees of the axis
    double cap = 0.0, rest = 0.0, top = 0.0;
    for (int i = 0; i < n; ++i) {
      Vec2f u = rng.next_2d();
      double z = 1.0 - u.x * (1.0 - cos_cap), phi = 2.0 * k_pi_d * u.y;
      double c = intensity(*lamp, sphere_dir(frame, z, phi));
      cap += c;
      top = std::max(top, c);
      double z2 = cos_cap - (rng.next_float()) * (1.0 + cos_cap), phi2 = 2.0 * k_pi_d * rng.next_float();
      rest += intensity(*lamp, sphere_dir(frame, z2, phi2));
    }
    double solid_angle = (cap / n * 2.0 * k_pi_d * (1.0 - cos_cap) + rest / n * 2.0 * k_pi_d * (1.0 + cos_cap)) / 1.5;
    EXPECT_LE(top, lamp->power() / (4.0 * k_pi_d) * (1.0 + 1e-5)) << beam;
    EXPECT_GT(solid_angle, 0.02) << beam;
    EXPECT_LT(solid_angle, 0.1) << beam;
  }
}

// For light selection it has a place (the lamp) and lights the half-space in front only.
TEST(headlamp, bounds_and_errors) {
  auto lamp = make_lamp("low", {0, 0, 2});
  Vec3f c, axis;
  float r, half;
  ASSERT_TRUE(lamp->bounding_sphere(&c, &r));
  EXPECT_EQ(r, 0.f);
  EXPECT_NEAR(c.x, k_pos.x, 1e-6);
  ASSERT_TRUE(lamp->normal_cone(&axis, &half));
  EXPECT_NEAR(axis.z, 1.f, 1e-6);
  EXPECT_NEAR(half, 0.5f * k_pi, 1e-6);
  auto message = [](const std::string& key, ParamSet::Value v) {
    ParamSet p;
    p.set(key, v);
    try {
      create_light("headlamp", p, "light 3");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string m = message("up", std::vector<double>{0, 0, 5});
  EXPECT_NE(m.find("'up'"), std::string::npos) << m;
  m = message("beam", std::string("medium"));
  EXPECT_NE(m.find("'beam'"), std::string::npos) << m;
  m = message("intensity", -1.0);
  EXPECT_NE(m.find("'intensity'"), std::string::npos) << m;
}
