// Light "environment" (light/environment.cpp): constant radiance from every direction,
// sampled uniformly over the sphere, or by the cosine around the shading point's normal.
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

const Color k_radiance(0.5f, 1.f, 2.f);

std::shared_ptr<Light> make_env() {
  ParamSet p;
  p.set("radiance", std::vector<double>{0.25, 0.5, 1.0});
  p.set("strength", 2.0);
  return create_light("environment", p, "light 1");
}

}  // namespace

TEST(environment, uniform_pdf_and_constant_radiance) {
  auto env = make_env();
  EXPECT_TRUE(env->is_infinite());
  EXPECT_FALSE(env->is_delta());
  const float uniform = float(1.0 / (4.0 * k_pi_d));
  Pcg32 rng(601);
  for (int i = 0; i < 10000; ++i) {
    LightSample ls;
    ASSERT_TRUE(env->sample({to_f({rng.next_float() * 10.0, -3.0, 1.0}), Vec3f(0.f)}, rng.next_2d(), &ls));
    EXPECT_NEAR(ls.pdf, uniform, 1e-9);
    EXPECT_EQ(ls.pdf, env->pdf_le(ls.wi));
    EXPECT_EQ(ls.li, k_radiance);
    EXPECT_EQ(env->le(ls.wi), ls.li);
    EXPECT_TRUE(ls.infinite);
    EXPECT_FALSE(ls.delta);
    EXPECT_NEAR(length(ls.wi), 1.f, 1e-5f);
    Vec3f d = to_f(dnormalize({rng.next_float() - 0.5, rng.next_float() - 0.5, rng.next_float() - 0.5}));
    EXPECT_NEAR(env->pdf_le(d), uniform, 1e-9);
    EXPECT_EQ(env->le(d), k_radiance);
  }
}

// Sampled directions against pdf_le(), in (cos theta, phi) cells around a tilted axis.
TEST(environment, sample_direction_chi2) {
  auto env = make_env();
  DFrame frame(dnormalize({0.2, 0.7, -0.4}));
  Grid2D g{32, 64, -1.0, 1.0, 0.0, 2.0 * k_pi_d};
  const int n = 1000000;
  Pcg32 rng(602);
  std::vector<double> obs(g.size(), 0.0);
  for (int i = 0; i < n; ++i) {
    LightSample ls;
    ASSERT_TRUE(env->sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls));
    double z, phi;
    sphere_coords(frame, to_d(ls.wi), &z, &phi);
    obs[size_t(g.cell(z, phi))] += 1.0;
  }
  auto exp = expected_counts(
      g, [&](double z, double phi) { return double(env->pdf_le(to_f(sphere_dir(frame, z, phi)))); }, n);
  EXPECT_NEAR(sum(exp) / n, 1.0, 1e-5) << "pdf_le does not integrate to 1";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
}

// With a normal in the context: directions cosine-distributed around it (chi-square against
// pdf_li in cells around the normal), each sample's pdf equal to pdf_li, pdf_li a density
// (integrates to 1), zero below the normal's horizon; the sky is a dome light.
TEST(environment, cosine_sampling_around_the_normal_chi2) {
  auto env = make_env();
  EXPECT_TRUE(env->is_dome());
  const DVec3 n = dnormalize({0.2, 0.7, -0.4});
  LightSampleContext ctx{Vec3f(1.f, 2.f, 3.f), Vec3f(0.f), to_f(n)};
  DFrame frame(n);
  Grid2D g{32, 64, -1.0, 1.0, 0.0, 2.0 * k_pi_d};
  const int samples = 1000000;
  Pcg32 rng(604);
  std::vector<double> obs(g.size(), 0.0);
  int bad_pdf = 0;
  for (int i = 0; i < samples; ++i) {
    LightSample ls;
    if (!env->sample(ctx, rng.next_2d(), &ls)) continue;
    bad_pdf += ls.pdf != env->pdf_li(ctx, ls.wi);
    EXPECT_GT(ddot(n, to_d(ls.wi)), 0.0);
    double z, phi;
    sphere_coords(frame, to_d(ls.wi), &z, &phi);
    obs[size_t(g.cell(z, phi))] += 1.0;
  }
  EXPECT_EQ(bad_pdf, 0);
  auto exp = expected_counts(
      g, [&](double z, double phi) { return double(env->pdf_li(ctx, to_f(sphere_dir(frame, z, phi)))); }, samples);
  EXPECT_NEAR(sum(exp) / samples, 1.0, 1e-4) << "pdf_li does not integrate to 1";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
  EXPECT_EQ(env->pdf_li(ctx, -to_f(n)), 0.f);
  // Without a normal: the uniform sphere, as pdf_le.
  LightSampleContext bare{Vec3f(0.f), Vec3f(0.f)};
  EXPECT_EQ(env->pdf_li(bare, -to_f(n)), env->pdf_le(-to_f(n)));
}

// Energy: with the cosine strategy every sample of the irradiance on a plane facing the normal
// is exactly pi L (zero variance), the estimate the renderer gets from a constant sky.
TEST(environment, cosine_sampling_gives_irradiance_without_variance) {
  auto env = make_env();
  const DVec3 n = dnormalize({1, -2, 0.5});
  LightSampleContext ctx{Vec3f(0.f), Vec3f(0.f), to_f(n)};
  Pcg32 rng(605);
  int used = 0;
  for (int i = 0; i < 100000; ++i) {
    LightSample ls;
    if (!env->sample(ctx, rng.next_2d(), &ls)) continue;
    ++used;
    double c = ddot(n, to_d(ls.wi));
    for (int k = 0; k < 3; ++k) ASSERT_NEAR(double(ls.li[k]) * c / double(ls.pdf) / (k_pi_d * k_radiance[k]), 1.0, 2e-5);
  }
  EXPECT_GT(used, 99990);
}

TEST(environment, irradiance_on_a_plane_is_pi_l) {
  auto env = make_env();
  for (const DVec3& n : {DVec3{0, 0, 1}, dnormalize({1, -2, 0.5})}) {
    Pcg32 rng(603);
    const int samples = 1000000;
    double e[3] = {0, 0, 0};
    for (int i = 0; i < samples; ++i) {
      LightSample ls;
      ASSERT_TRUE(env->sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls));
      double c = ddot(n, to_d(ls.wi));
      if (c <= 0.0) continue;
      for (int k = 0; k < 3; ++k) e[k] += double(ls.li[k]) * c / double(ls.pdf);
    }
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(e[k] / samples / (k_pi_d * k_radiance[k]), 1.0, 5e-3) << "channel " << k;
  }
}

TEST(environment, power_uses_scene_radius) {
  auto env = make_env();
  Bounds3 b;
  b.expand(Vec3f(0.f, 0.f, 0.f));
  b.expand(Vec3f(0.f, 0.f, 4.f));  // radius 2
  env->preprocess(b);
  EXPECT_NEAR(env->power() / (4.0 * k_pi_d * k_pi_d * 4.0 * luminance(k_radiance)), 1.0, 1e-5);
}

TEST(environment, parameter_errors) {
  ParamSet negative;
  negative.set("radiance", std::vector<double>{1.0, -0.1, 1.0});
  EXPECT_THROW(create_light("environment", negative, "l"), Error);
  ParamSet typo;
  typo.set("radiance", 1.0);
  typo.set("strenght", 2.0);
  try {
    create_light("environment", typo, "light 9");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'strength'"), std::string::npos) << e.what();
  }
}
