// Light "spot" (light/spot.cpp): a delta point light with pbrt-v4's smoothstep falloff.
// Expectations come from an independent implementation of the documented intensity
// I(theta) = I_axis * smoothstep(cos(cone_angle), cos(falloff_start), cos(theta)).
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
double deg(double d) { return d * k_pi_d / 180.0; }

const DVec3 k_pos{1.0, 3.0, -0.5};
const DVec3 k_axis = dnormalize({0.2, -1.0, 0.3});
const Color k_intensity(40.f, 30.f, 20.f);

std::shared_ptr<Light> make_spot(double cone, double start, const DVec3& axis = k_axis) {
  ParamSet p;
  p.set("position", std::vector<double>{k_pos.x, k_pos.y, k_pos.z});
  p.set("direction", std::vector<double>{axis.x * 2.0, axis.y * 2.0, axis.z * 2.0});  // need not be unit
  p.set("intensity", std::vector<double>{k_intensity.x / 2.0, k_intensity.y / 2.0, k_intensity.z / 2.0});
  p.set("strength", 2.0);
  p.set("cone_angle", cone);
  p.set("falloff_start", start);
  return create_light("spot", p, "light 0");
}

double expected_falloff(double theta_deg, double cone, double start) {
  double c = std::cos(deg(theta_deg)), ce = std::cos(deg(cone)), cs = std::cos(deg(start));
  if (cs <= ce) return c >= ce ? 1.0 : 0.0;
  double t = std::min(1.0, std::max(0.0, (c - ce) / (cs - ce)));
  return t * t * (3.0 - 2.0 * t);
}

}  // namespace

// Irradiance at receivers placed at angle theta from the axis and distance d, on surfaces
// with various normals: E = I(theta) cos / d^2 inside the cone, and no sample outside.
TEST(spot, irradiance_inside_and_outside_the_cone) {
  const double cone = 30.0, start = 20.0;
  auto spot = make_spot(cone, start);
  EXPECT_TRUE(spot->is_delta());
  EXPECT_FALSE(spot->is_infinite());
  DFrame f(k_axis);
  for (double theta : {0.0, 10.0, 19.9, 20.5, 22.0, 25.0, 28.0, 29.9, 30.5, 45.0, 120.0})
    for (double d : {0.5, 2.0, 7.0})
      for (double phi : {0.3, 2.5}) {
        DVec3 dir = f.to_world(std::sin(deg(theta)) * std::cos(phi), std::sin(deg(theta)) * std::sin(phi),
                               std::cos(deg(theta)));
        DVec3 p{k_pos.x + d * dir.x, k_pos.y + d * dir.y, k_pos.z + d * dir.z};
        DVec3 n = dnormalize({-dir.x + 0.3, -dir.y, -dir.z + 0.1});  // faces the light, tilted
        LightSample ls;
        bool ok = spot->sample({to_f(p), Vec3f(0.f)}, Vec2f(0.5f, 0.5f), &ls);
        double s = expected_falloff(theta, cone, start);
        std::string where = "theta " + std::to_string(theta) + ", d " + std::to_string(d);
        if (s == 0.0) {
          EXPECT_FALSE(ok) << where;
          continue;
        }
        ASSERT_TRUE(ok) << where;
        EXPECT_TRUE(ls.delta);
        EXPECT_EQ(ls.pdf, 1.f);
        EXPECT_NEAR(ddot(to_d(ls.wi), DVec3{-dir.x, -dir.y, -dir.z}), 1.0, 1e-6) << where;
        EXPECT_NEAR(ls.p_light.x, k_pos.x, 1e-6);
        EXPECT_NEAR(ls.p_light.y, k_pos.y, 1e-6);
        EXPECT_NEAR(ls.p_light.z, k_pos.z, 1e-6);
        double cos_n = ddot(n, to_d(ls.wi));
        for (int k = 0; k < 3; ++k) {
          double e = double(ls.li[k]) * cos_n / ls.pdf;
          double unattenuated = k_intensity[k] * cos_n / (d * d);
          // Relative to the unattenuated value: near the cone's edge the smoothstep works on
          // a difference of float cosines (a few ulps of 0.87 against 1e-3).
          EXPECT_NEAR(e / unattenuated, s, 1e-5 + 1e-4 * s) << where << ", channel " << k;
        }
      }
}

// Hard edge when the falloff starts where the cone ends; a 180 degree cone is a point light.
TEST(spot, hard_edge_and_full_sphere) {
  auto hard = make_spot(25.0, 25.0);
  DFrame f(k_axis);
  auto at = [&](double theta) {
    DVec3 d = f.to_world(std::sin(deg(theta)), 0.0, std::cos(deg(theta)));
    return to_f({k_pos.x + 2 * d.x, k_pos.y + 2 * d.y, k_pos.z + 2 * d.z});
  };
  LightSample ls;
  ASSERT_TRUE(hard->sample({at(24.9), Vec3f(0.f)}, Vec2f(0.f, 0.f), &ls));
  EXPECT_NEAR(ls.li.x, k_intensity.x / 4.0, 1e-4);
  EXPECT_FALSE(hard->sample({at(25.1), Vec3f(0.f)}, Vec2f(0.f, 0.f), &ls));
  auto sphere = make_spot(180.0, 180.0);
  ParamSet p;
  p.set("position", std::vector<double>{k_pos.x, k_pos.y, k_pos.z});
  p.set("intensity", std::vector<double>{k_intensity.x, k_intensity.y, k_intensity.z});
  auto point = create_light("point", p, "light 1");
  EXPECT_NEAR(sphere->power() / point->power(), 1.0, 1e-6);
  for (double theta : {0.0, 90.0, 179.0}) {
    LightSample a, b;
    ASSERT_TRUE(sphere->sample({at(theta), Vec3f(0.f)}, Vec2f(0.f, 0.f), &a));
    ASSERT_TRUE(point->sample({at(theta), Vec3f(0.f)}, Vec2f(0.f, 0.f), &b));
    EXPECT_NEAR(a.li.x / b.li.x, 1.0, 1e-6);
  }
}

// power() = I 2 pi (1 - (cos start + cos end) / 2) equals the emitted intensity integrated
// over the sphere (measured through sample() at unit distance, by quadrature in cos theta).
TEST(spot, power_is_the_integrated_intensity) {
  const std::pair<double, double> cases[] = {{30.0, 25.0}, {60.0, 10.0}, {120.0, 90.0}, {5.0, 0.0}};
  for (auto [cone, start] : cases) {
    auto spot = make_spot(cone, start);
    double formula = luminance(k_intensity) * 2.0 * k_pi_d * (1.0 - 0.5 * (std::cos(deg(start)) + std::cos(deg(cone))));
    EXPECT_NEAR(spot->power() / formula, 1.0, 1e-5) << cone << ", " << start;
    DFrame f(k_axis);
    const int n = 20000;
    double integral = 0.0;
    for (int i = 0; i < n; ++i) {
      double z = -1.0 + 2.0 * (i + 0.5) / n;  // cos(theta); the intensity is rotationally symmetric
      DVec3 d = f.to_world(std::sqrt(1.0 - z * z), 0.0, z);
      LightSample ls;
      if (spot->sample({to_f({k_pos.x + d.x, k_pos.y + d.y, k_pos.z + d.z}), Vec3f(0.f)}, Vec2f(0.f, 0.f), &ls))
        integral += luminance(ls.li);  // intensity at unit distance
    }
    integral *= 2.0 * k_pi_d * 2.0 / n;
    EXPECT_NEAR(integral / spot->power(), 1.0, 1e-3) << cone << ", " << start;
  }
}

TEST(spot, parameter_errors) {
  auto message = [](const std::string& key, ParamSet::Value v) {
    ParamSet p;
    p.set(key, v);
    try {
      create_light("spot", p, "light 5");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string m = message("cone_angle", 0.0);
  EXPECT_NE(m.find("'cone_angle'"), std::string::npos) << m;
  EXPECT_NE(m.find("(0, 180]"), std::string::npos) << m;
  m = message("cone_angle", 190.0);
  EXPECT_NE(m.find("(0, 180]"), std::string::npos) << m;
  m = message("falloff_start", 40.0);  // beyond the default cone of 30 degrees
  EXPECT_NE(m.find("'falloff_start'"), std::string::npos) << m;
  EXPECT_NE(m.find("[0, cone_angle]"), std::string::npos) << m;
  m = message("falloff_start", -1.0);
  EXPECT_NE(m.find("'falloff_start'"), std::string::npos) << m;
  m = message("intensity", -1.0);
  EXPECT_NE(m.find("'intensity'"), std::string::npos) << m;
  m = message("direction", std::vector<double>{0.0, 0.0, 0.0});
  EXPECT_NE(m.find("'direction'"), std::string::npos) << m;
  m = message("cone_angel", 10.0);
  EXPECT_NE(m.find("did you mean 'cone_angle'"), std::string::npos) << m;
  // A narrow cone with the default falloff start: the start is clamped to the cone.
  EXPECT_EQ(message("cone_angle", 10.0), "no error");
}
