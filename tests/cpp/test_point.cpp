// Light "point" (light/point.cpp), created through sg::create_light.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/params.h"
#include "core/rng.h"
#include "light/light.h"

using namespace sg;

namespace {

std::shared_ptr<Light> make_point(const Vec3f& pos, const Color& intensity, double strength = 1.0) {
  ParamSet p;
  p.set("position", std::vector<double>{pos.x, pos.y, pos.z});
  p.set("intensity", std::vector<double>{intensity.x, intensity.y, intensity.z});
  p.set("strength", strength);
  return create_light("point", p, "light 0");
}

}  // namespace

TEST(point, inverse_square_law_and_delta_record) {
  const Vec3f pos(1.5f, -2.f, 3.25f);
  auto light = make_point(pos, Color(1.f, 2.f, 4.f), 3.0);
  EXPECT_TRUE(light->is_delta());
  EXPECT_FALSE(light->is_infinite());
  Pcg32 rng(401);
  for (int i = 0; i < 10000; ++i) {
    // Reference points at distances from 1e-2 to 1e3.
    double r = std::pow(10.0, -2.0 + 5.0 * rng.next_float());
    double z = 1.0 - 2.0 * rng.next_float(), phi = 6.283185307179586 * rng.next_float();
    double s = std::sqrt(1.0 - z * z);
    Vec3f x(float(pos.x + r * s * std::cos(phi)), float(pos.y + r * s * std::sin(phi)), float(pos.z + r * z));
    double dx = double(pos.x) - x.x, dy = double(pos.y) - x.y, dz = double(pos.z) - x.z;
    double d2 = dx * dx + dy * dy + dz * dz, d = std::sqrt(d2);
    LightSample ls;
    ASSERT_TRUE(light->sample({x, Vec3f(0.f)}, rng.next_2d(), &ls));
    EXPECT_TRUE(ls.delta);
    EXPECT_FALSE(ls.infinite);
    EXPECT_EQ(ls.pdf, 1.f);
    EXPECT_EQ(ls.p_light, pos);
    // li = I / d^2 (I = intensity * strength), up to float rounding.
    const double I[3] = {3.0, 6.0, 12.0};
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(ls.li[k] / (I[k] / d2), 1.0, 1e-5) << "distance " << d;
    EXPECT_NEAR(ls.wi.x, dx / d, 1e-6);
    EXPECT_NEAR(ls.wi.y, dy / d, 1e-6);
    EXPECT_NEAR(ls.wi.z, dz / d, 1e-6);
  }
  // At the light position there is no direction.
  LightSample ls;
  EXPECT_FALSE(light->sample({pos, Vec3f(0.f)}, Vec2f(0.5f, 0.5f), &ls));
  // Power = 4 pi * luminance(I).
  EXPECT_NEAR(light->power(), 4.0 * 3.14159265358979 * 3.0 * luminance(Color(1.f, 2.f, 4.f)), 1e-4);
  EXPECT_TRUE(is_black(light->le(Vec3f(0, 0, 1))));
  EXPECT_EQ(light->pdf_le(Vec3f(0, 0, 1)), 0.f);
}

TEST(point, sample_does_not_depend_on_u) {
  auto light = make_point(Vec3f(0.f, 0.f, 2.f), Color(1.f));
  LightSample a, b;
  ASSERT_TRUE(light->sample({Vec3f(0.f), Vec3f(0.f)}, Vec2f(0.1f, 0.9f), &a));
  ASSERT_TRUE(light->sample({Vec3f(0.f), Vec3f(0.f)}, Vec2f(0.7f, 0.2f), &b));
  EXPECT_EQ(a.wi, b.wi);
  EXPECT_EQ(a.li, b.li);
  EXPECT_EQ(a.li, Color(0.25f));  // exact: 1 / 2^2
  EXPECT_EQ(a.wi, Vec3f(0.f, 0.f, 1.f));
}

TEST(point, parameter_errors) {
  ParamSet typo;
  typo.set("intensty", 1.0);
  try {
    create_light("point", typo, "light 4");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    std::string msg = e.what();
    EXPECT_NE(msg.find("did you mean 'intensity'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("light 4"), std::string::npos) << msg;
  }
  ParamSet negative;
  negative.set("intensity", -1.0);
  EXPECT_THROW(create_light("point", negative, "l"), Error);
  ParamSet bad_pos;
  bad_pos.set("position", std::vector<double>{1.0, 2.0});
  EXPECT_THROW(create_light("point", bad_pos, "l"), Error);
  try {
    create_light("pont", ParamSet{}, "l");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'point'"), std::string::npos) << e.what();
  }
}
