// Light selection (api/scene.cpp: RenderScene::light_pick): next-event estimation picks a
// light with probability proportional to its power() estimate. A scene with a strong and
// a weak light (and lights of every kind) must pick them in proportion.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>

#include "api/scene.h"
#include "chi2.h"
#include "core/params.h"
#include "core/rng.h"
#include "io/image_io.h"

using namespace sg;
using namespace sgtest;

namespace {

TriangleMesh ground_quad() {
  TriangleMesh m;
  m.name = "ground";
  m.positions = {{-2, 0, -2}, {2, 0, -2}, {2, 0, 2}, {-2, 0, 2}};
  m.indices = {0, 2, 1, 0, 3, 2};
  return m;
}

ParamSet spot(double intensity) {
  ParamSet p;
  p.set("position", std::vector<double>{0.0, 3.0, 0.0});
  p.set("intensity", intensity);
  p.set("cone_angle", 40.0);
  p.set("falloff_start", 30.0);
  return p;
}

/// Picks `n` lights through the scene's distribution and compares the counts with the
/// expected proportions (chi-square).
void expect_proportional_picks(const RenderScene& rs, const std::vector<double>& power, uint64_t seed) {
  ASSERT_EQ(rs.lights.size(), power.size());
  double total = 0.0;
  for (double p : power) total += p;
  for (size_t i = 0; i < power.size(); ++i)
    EXPECT_NEAR(rs.light_pick.pmf(i), power[i] / total, 1e-6 + 1e-5 * power[i] / total) << "light " << i;
  const int n = 1000000;
  Pcg32 rng(seed);
  std::vector<double> obs(power.size(), 0.0), exp(power.size());
  for (int i = 0; i < n; ++i) obs[rs.light_pick.sample(rng.next_float())] += 1.0;
  for (size_t i = 0; i < power.size(); ++i) exp[i] = n * power[i] / total;
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
}

}  // namespace

TEST(light_selection, strong_and_weak_lights_are_picked_in_proportion) {
  Scene s;
  s.add_instance(s.add_mesh(ground_quad()), Transform());
  uint32_t strong = s.add_light("spot", spot(100.0));
  uint32_t weak = s.add_light("spot", spot(1.0));
  s.commit();
  const RenderScene& rs = s.render_scene();
  // Same cone: powers in the ratio of the intensities.
  EXPECT_NEAR(rs.lights[strong]->power() / rs.lights[weak]->power(), 100.0, 1e-3);
  expect_proportional_picks(rs, {rs.lights[strong]->power(), rs.lights[weak]->power()}, 901);
}

// Power estimates of all light kinds are on one scale: a light's share of the picks is its
// power, and lights that deliver the same flux to the scene get the same estimate.
TEST(light_selection, all_light_kinds_share_one_scale) {
  Scene s;
  s.add_instance(s.add_mesh(ground_quad()), Transform());
  ParamSet point;
  point.set("position", std::vector<double>{0.0, 2.0, 0.0});
  point.set("intensity", 5.0);
  ParamSet sun;
  sun.set("direction", std::vector<double>{0.3, 1.0, 0.2});
  sun.set("irradiance", 20.0);
  ParamSet env;
  env.set("radiance", 0.5);
  ParamSet sky;
  sky.set("elevation", 40.0);
  sky.set("strength", 0.05);
  s.add_light("point", point);
  s.add_light("spot", spot(10.0));
  s.add_light("sun", sun);
  s.add_light("environment", env);
  s.add_light("sky", sky);
  s.commit();
  const RenderScene& rs = s.render_scene();
  std::vector<double> power;
  for (const Light* l : rs.lights) {
    EXPECT_GT(l->power(), 0.f);
    power.push_back(l->power());
  }
  expect_proportional_picks(rs, power, 902);
  // The scene's bounding sphere has radius 2 sqrt(2): pi r^2 x irradiance for the sun,
  // pi r^2 x 4 pi L for a uniform environment; a point light radiates 4 pi I.
  double r2 = 8.0;
  EXPECT_NEAR(rs.lights[2]->power() / (k_pi_d * r2 * 20.0), 1.0, 1e-5);
  EXPECT_NEAR(rs.lights[3]->power() / (k_pi_d * r2 * 4.0 * k_pi_d * 0.5), 1.0, 1e-5);
  EXPECT_NEAR(rs.lights[0]->power() / (4.0 * k_pi_d * 5.0), 1.0, 1e-5);
}
