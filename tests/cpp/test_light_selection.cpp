// Light selection (api/scene.cpp, integrator/render_scene.h): next-event estimation picks a
// light at a shading point by the flux density it brings there (RenderScene::pick_light:
// power / 4 pi d^2 for lights with a place, power per scene disc for the others); beyond
// k_max_weighed_lights, by power alone (RenderScene::group_pick). Lights come in two groups,
// each sampled at every vertex: domes (whole-sky lights) and all others. Checked: picks in
// proportion within each group (chi-square), pmf consistent with the choice, near lights
// preferred, the groups' members.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

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

/// Picks `n` lights through group g's power distribution and compares the counts with the
/// expected proportions (chi-square); `power` lists the group's lights' powers in order.
void expect_proportional_picks(const RenderScene& rs, int g, const std::vector<double>& power, uint64_t seed) {
  ASSERT_EQ(rs.group_lights[g].size(), power.size());
  double total = 0.0;
  for (double p : power) total += p;
  for (size_t i = 0; i < power.size(); ++i) {
    EXPECT_NEAR(rs.group_pick[g].pmf(i), power[i] / total, 1e-6 + 1e-5 * power[i] / total) << "light " << i;
    EXPECT_NEAR(rs.group_pmf(rs.group_lights[g][i]), power[i] / total, 1e-6 + 1e-5 * power[i] / total);
  }
  const int n = 1000000;
  Pcg32 rng(seed);
  std::vector<double> obs(power.size(), 0.0), exp(power.size());
  for (int i = 0; i < n; ++i) obs[rs.group_pick[g].sample(rng.next_float())] += 1.0;
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
  ASSERT_EQ(rs.group_lights[0], (std::vector<uint32_t>{strong, weak}));
  expect_proportional_picks(rs, 0, {rs.lights[strong]->power(), rs.lights[weak]->power()}, 901);
}

// Power estimates of all light kinds are on one scale: a light's share of its group's picks is
// its power, and lights that deliver the same flux to the scene get the same estimate. The
// domes ("environment", the sky's dome) form one group, the rest (the sky's sun too) the other.
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
  // point, spot, sun, environment, then the sky's parts: its dome and its sun.
  ASSERT_EQ(rs.lights.size(), 6u);
  EXPECT_EQ(rs.group_lights[0], (std::vector<uint32_t>{0, 1, 2, 5}));
  EXPECT_EQ(rs.group_lights[1], (std::vector<uint32_t>{3, 4}));
  EXPECT_EQ(rs.infinite_lights, (std::vector<uint32_t>{2, 3, 4, 5}));
  for (int g = 0; g < 2; ++g) {
    std::vector<double> power;
    for (uint32_t li : rs.group_lights[g]) {
      EXPECT_GT(rs.lights[li]->power(), 0.f);
      power.push_back(rs.lights[li]->power());
    }
    expect_proportional_picks(rs, g, power, 902 + 100 * g);
  }
  // The scene's bounding sphere has radius 2 sqrt(2): pi r^2 x irradiance for the sun,
  // pi r^2 x 4 pi L for a uniform environment; a point light radiates 4 pi I.
  double r2 = 8.0;
  EXPECT_NEAR(rs.lights[2]->power() / (k_pi_d * r2 * 20.0), 1.0, 1e-5);
  EXPECT_NEAR(rs.lights[3]->power() / (k_pi_d * r2 * 4.0 * k_pi_d * 0.5), 1.0, 1e-5);
  EXPECT_NEAR(rs.lights[0]->power() / (4.0 * k_pi_d * 5.0), 1.0, 1e-5);
}

namespace {

/// pick_light of group g at p against the flux-density weights (chi-square), and light_pmf
/// against the pmf pick_light returns.
void expect_weighted_picks_in_group(const RenderScene& rs, int g, const Vec3f& p, uint64_t seed) {
  const std::vector<uint32_t>& members = rs.group_lights[g];
  const size_t n_l = members.size();
  if (n_l == 1) {  // the group's one light, always
    float pmf;
    EXPECT_EQ(rs.pick_light(g, p, 0.5f, &pmf), members[0]);
    EXPECT_EQ(pmf, 1.f);
    EXPECT_EQ(rs.light_pmf(p, members[0]), 1.f);
    return;
  }
  std::vector<double> w(n_l);
  double total = 0.0;
  for (size_t i = 0; i < n_l; ++i) {
    const auto& lw = rs.light_weights[members[i]];
    Vec3f d = p - lw.centre;
    double d2 = dot(d, d);
    w[i] = lw.local ? lw.power / (4.0 * k_pi_d * std::max(d2, double(lw.radius2))) : lw.power;
    if (lw.directional) w[i] = lw.directional->selection_intensity(p) / std::max(d2, double(lw.radius2));
    else if (lw.oriented && d2 > lw.radius2) {
      // The emission angle's lower bound: the angle to the cone's axis less its half-angle and
      // the sphere's angular radius.
      double theta = std::acos(std::clamp(double(dot(lw.axis, d)) / std::sqrt(d2), -1.0, 1.0)) - lw.cone_angle -
                     std::asin(std::min(1.0, std::sqrt(double(lw.radius2) / d2)));
      w[i] *= theta <= 0.0 ? 1.0 : (theta >= 0.5 * k_pi_d ? 0.0 : std::cos(theta));
    }
    total += w[i];
  }
  double sum = 0.0;
  for (size_t i = 0; i < n_l; ++i) {
    EXPECT_NEAR(rs.light_pmf(p, members[i]), w[i] / total, 1e-6) << "light " << members[i];
    sum += rs.light_pmf(p, members[i]);
  }
  EXPECT_NEAR(sum, 1.0, 1e-5);
  const int n = 400000;
  Pcg32 rng(seed);
  std::vector<double> obs(n_l, 0.0), exp(n_l);
  for (int k = 0; k < n; ++k) {
    float pmf;
    size_t li = rs.pick_light(g, p, rng.next_float(), &pmf);
    size_t i = size_t(std::find(members.begin(), members.end(), uint32_t(li)) - members.begin());
    ASSERT_LT(i, n_l);
    EXPECT_FLOAT_EQ(pmf, rs.light_pmf(p, uint32_t(li)));
    obs[i] += 1.0;
  }
  for (size_t i = 0; i < n_l; ++i) exp[i] = n * w[i] / total;
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
}

/// expect_weighted_picks_in_group in each light group.
void expect_weighted_picks(const RenderScene& rs, const Vec3f& p, uint64_t seed) {
  for (int g = 0; g < RenderScene::k_light_groups; ++g)
    if (!rs.group_lights[g].empty()) expect_weighted_picks_in_group(rs, g, p, seed + 1000 * uint64_t(g));
}

}  // namespace

// A small lamp next to a sun: by power alone the lamp is (almost) never chosen; weighed by
// its flux density at the shading point it is chosen near it and rarely far from it.
TEST(light_selection, lights_are_weighed_by_their_flux_density_at_the_shading_point) {
  Scene s;
  TriangleMesh big = ground_quad();
  for (Vec3f& v : big.positions) v = Vec3f(v.x * 100.f, v.y, v.z * 100.f);  // a 400 m ground
  s.add_instance(s.add_mesh(big), Transform());
  ParamSet point;
  point.set("position", std::vector<double>{0.0, 0.5, 0.0});
  point.set("intensity", 2.0);
  ParamSet sun;  // as much light as a sky of radiance 0.05 (E = 4 pi L over the sphere)
  sun.set("direction", std::vector<double>{0.3, 1.0, 0.2});
  sun.set("irradiance", 4.0 * k_pi_d * 0.05);
  uint32_t lamp = s.add_light("point", point);
  uint32_t sky = s.add_light("sun", sun);
  s.commit();
  const RenderScene& rs = s.render_scene();
  ASSERT_TRUE(rs.light_weights[lamp].local);
  ASSERT_FALSE(rs.light_weights[sky].local);
  ASSERT_EQ(rs.group_lights[0].size(), 2u);  // one group: neither is a dome
  // By power the lamp gets a vanishing share; at 0.5 m from it, most picks.
  EXPECT_LT(rs.group_pmf(lamp), 1e-3);
  float near = rs.light_pmf(Vec3f(0.f, 0.f, 0.f), lamp), far = rs.light_pmf(Vec3f(30.f, 0.f, 0.f), lamp);
  EXPECT_GT(near, 0.5f);
  EXPECT_LT(far, 0.01f);
  expect_weighted_picks(rs, Vec3f(0.f, 0.f, 0.f), 903);
  expect_weighted_picks(rs, Vec3f(3.f, 0.f, 1.f), 904);
}

TEST(light_selection, weighed_picks_of_every_light_kind_are_consistent) {
  Scene s;
  s.add_instance(s.add_mesh(ground_quad()), Transform());
  ParamSet point;
  point.set("position", std::vector<double>{1.0, 2.0, 0.0});
  point.set("intensity", 5.0);
  ParamSet sun;
  sun.set("direction", std::vector<double>{0.3, 1.0, 0.2});
  sun.set("irradiance", 20.0);
  ParamSet env;
  env.set("radiance", 0.5);
  ParamSet lamp;
  lamp.set("radiance", 40.0);
  s.add_light("point", point);
  s.add_light("spot", spot(10.0));
  s.add_light("sun", sun);
  s.add_light("environment", env);
  TriangleMesh q = ground_quad();
  for (Vec3f& v : q.positions) v = Vec3f(v.x * 0.05f, 1.0f, v.z * 0.05f + 1.f);
  std::swap(q.indices[1], q.indices[2]);
  std::swap(q.indices[4], q.indices[5]);  // facing down
  uint32_t mid = s.add_material("emissive", lamp);
  s.add_instance(s.add_mesh(q), Transform(), 0, std::nullopt, mid);
  s.commit();
  const RenderScene& rs = s.render_scene();
  ASSERT_EQ(rs.lights.size(), 5u);
  int local = 0;
  for (const auto& lw : rs.light_weights) local += lw.local;
  EXPECT_EQ(local, 3);  // point, spot, the emissive quad
  uint32_t qi = 0;  // the quad's area light (area lights come first)
  while (qi < rs.lights.size() && !dynamic_cast<const AreaLight*>(rs.lights[qi])) ++qi;
  ASSERT_LT(qi, rs.lights.size());
  const auto& quad = rs.light_weights[qi];
  ASSERT_TRUE(quad.oriented);  // one-sided, facing down
  EXPECT_NEAR(quad.axis.y, -1.f, 1e-5f);
  EXPECT_NEAR(quad.cone_angle, 0.f, 1e-3f);
  // Above the quad it sends nothing: never picked there.
  EXPECT_EQ(rs.light_pmf(Vec3f(0.f, 3.f, 1.f), qi), 0.f);
  EXPECT_GT(rs.light_pmf(Vec3f(0.f, 0.f, 1.f), qi), 0.f);
  expect_weighted_picks(rs, Vec3f(0.f, 0.f, 0.f), 905);
  expect_weighted_picks(rs, Vec3f(0.1f, 0.9f, 1.f), 906);
  expect_weighted_picks(rs, Vec3f(0.f, 3.f, 1.f), 907);
}

// Delta lights whose intensity varies with direction (spot, headlamp) are weighed by the
// intensity they send towards the shading point / d^2 -- their exact unoccluded irradiance
// there: nothing outside a spot's cone or behind a headlamp, and in a headlamp's beam the
// headlamp rather than a street lamp's spot whose flux is larger.
TEST(light_selection, beams_are_weighed_by_their_intensity_towards_the_point) {
  Scene s;
  TriangleMesh big = ground_quad();
  for (Vec3f& v : big.positions) v = Vec3f(v.x * 20.f, v.y, v.z * 20.f);
  s.add_instance(s.add_mesh(big), Transform());
  ParamSet street = spot(0.15);  // 5000 cd at strength 0.02, 8 m up, 70-degree cone
  street.set("position", std::vector<double>{0.0, 8.0, -6.0});
  street.set("cone_angle", 70.0);
  street.set("falloff_start", 50.0);
  ParamSet head;
  head.set("position", std::vector<double>{-10.0, 0.65, 0.0});
  head.set("direction", std::vector<double>{1.0, 0.0, 0.0});
  head.set("intensity", 0.44);  // 15 kcd at strength 0.02
  uint32_t spot_i = s.add_light("spot", street);
  uint32_t head_i = s.add_light("headlamp", head);
  s.commit();
  const RenderScene& rs = s.render_scene();
  ASSERT_EQ(rs.light_weights[spot_i].directional, rs.lights[spot_i]);
  ASSERT_EQ(rs.light_weights[head_i].directional, rs.lights[head_i]);
  // A point on the road 12 m ahead of the headlamp, 8.5 m from under the street lamp.
  Vec3f p(2.f, 0.f, 0.f);
  LightSampleContext ctx{p, Vec3f(0.f)};
  LightSample a, b;
  ASSERT_TRUE(rs.lights[spot_i]->sample(ctx, Vec2f(0.5f, 0.5f), &a));
  ASSERT_TRUE(rs.lights[head_i]->sample(ctx, Vec2f(0.5f, 0.5f), &b));
  float share = luminance(b.li) / (luminance(a.li) + luminance(b.li));
  EXPECT_NEAR(rs.light_pmf(p, head_i), share, 1e-4f);
  EXPECT_GT(share, 0.5f);  // by flux the headlamp would get a few percent
  // Behind the headlamp and outside the spot's cone: never picked there.
  EXPECT_EQ(rs.light_pmf(Vec3f(-15.f, 0.f, 0.f), head_i), 0.f);
  EXPECT_EQ(rs.light_pmf(Vec3f(0.f, 0.f, 25.f), spot_i), 0.f);
  expect_weighted_picks(rs, p, 908);
  expect_weighted_picks(rs, Vec3f(-3.f, 0.f, 2.f), 909);
}
