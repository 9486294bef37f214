// The "facing" texture plugin: dot(shading normal, axis), shaped (snow on up-facing surfaces).
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/params.h"
#include "core/rng.h"
#include "texture/texture.h"

using namespace sg;

namespace {

std::shared_ptr<Texture> make(ParamSet p = {}) { return create_texture("facing", p, "test"); }

TexturePoint at(const Vec3f& n_world, const Vec3f& n_object = Vec3f(0.f, 0.f, 1.f)) {
  TexturePoint q;
  q.n_world = normalize(n_world);
  q.n_object = normalize(n_object);
  return q;
}

Vec3f random_direction(Pcg32& rng) {
  float z = 1.f - 2.f * rng.next_float(), phi = 2.f * float(M_PI) * rng.next_float();
  float r = std::sqrt(std::max(0.f, 1.f - z * z));
  return Vec3f(r * std::cos(phi), r * std::sin(phi), z);
}

}  // namespace

// Default: up (+y) in world space, the cosine [-1, 1] mapped to [0, 1].
TEST(facing, default_is_the_up_cosine_mapped_to_unit_interval) {
  auto t = make();
  EXPECT_TRUE(t->needs_position());
  EXPECT_FALSE(t->is_constant());
  EXPECT_FLOAT_EQ(t->eval_point(at({0, 1, 0})).x, 1.f);
  EXPECT_FLOAT_EQ(t->eval_point(at({0, -1, 0})).x, 0.f);
  EXPECT_NEAR(t->eval_point(at({1, 0, 0})).x, 0.5f, 1e-6f);
  EXPECT_NEAR(t->eval_point(at({0, 0, -1})).x, 0.5f, 1e-6f);
  Pcg32 rng(1);
  for (int i = 0; i < 1000; ++i) {
    Vec3f n = random_direction(rng);
    Color c = t->eval_point(at(n));
    ASSERT_NEAR(c.x, 0.5f * (n.y + 1.f), 1e-5f);
    ASSERT_EQ(c.x, c.y);
    ASSERT_EQ(c.x, c.z);
  }
  // Uniform directions: the cosine is uniform in [-1, 1], the mean value 1/2.
  EXPECT_NEAR(t->average().x, 0.5f, 1e-4f);
}

// Snow's mask: 0 on faces steeper than 55 degrees, 1 on faces flatter than 35, smooth between.
TEST(facing, remapped_slope_band) {
  ParamSet p;
  const double c55 = std::cos(55.0 * M_PI / 180.0), c35 = std::cos(35.0 * M_PI / 180.0);
  p.set("remap", std::vector<double>{c55, c35});
  p.set("smooth", true);
  auto t = make(p);
  auto slope = [](double deg) {
    double a = deg * M_PI / 180.0;
    return Vec3f(float(std::sin(a)), float(std::cos(a)), 0.f);
  };
  EXPECT_FLOAT_EQ(t->eval_point(at(slope(0))).x, 1.f);
  EXPECT_FLOAT_EQ(t->eval_point(at(slope(30))).x, 1.f);
  EXPECT_FLOAT_EQ(t->eval_point(at(slope(60))).x, 0.f);
  EXPECT_FLOAT_EQ(t->eval_point(at(slope(90))).x, 0.f);
  EXPECT_FLOAT_EQ(t->eval_point(at(slope(180))).x, 0.f);
  float mid = t->eval_point(at(slope(45))).x;
  double u = (std::cos(45.0 * M_PI / 180.0) - c55) / (c35 - c55);
  EXPECT_NEAR(mid, u * u * (3 - 2 * u), 1e-5);
  // Monotone in the slope.
  float prev = 2.f;
  for (int d = 0; d <= 180; ++d) {
    float v = t->eval_point(at(slope(d))).x;
    ASSERT_LE(v, prev + 1e-6f) << d;
    prev = v;
  }
  // invert: the down-facing complement.
  p.set("invert", true);
  EXPECT_FLOAT_EQ(make(p)->eval_point(at(slope(0))).x, 0.f);
}

// Any axis (normalized), in world or object space.
TEST(facing, axis_and_space) {
  ParamSet p;
  p.set("axis", std::vector<double>{0.0, 0.0, -3.0});
  p.set("remap", std::vector<double>{0.0, 1.0});
  auto w = make(p);
  EXPECT_FLOAT_EQ(w->eval_point(at({0, 0, -1}, {0, 1, 0})).x, 1.f);
  EXPECT_FLOAT_EQ(w->eval_point(at({0, 0, 1}, {0, 0, -1})).x, 0.f);
  EXPECT_NEAR(w->eval_point(at({0, 1, -1})).x, std::sqrt(0.5f), 1e-6f);
  p.set("space", std::string("object"));
  auto o = make(p);
  EXPECT_FLOAT_EQ(o->eval_point(at({0, 0, 1}, {0, 0, -1})).x, 1.f);
  EXPECT_FLOAT_EQ(o->eval_point(at({0, 0, -1}, {0, 1, 0})).x, 0.f);
  // A colour ramp: down-facing blue, up-facing white.
  ParamSet r;
  r.set("ramp_positions", std::vector<double>{0.0, 1.0});
  r.set("ramp_colors", std::vector<double>{0, 0, 1, 1, 1, 1});
  Color up = make(r)->eval_point(at({0, 1, 0})), down = make(r)->eval_point(at({0, -1, 0}));
  EXPECT_FLOAT_EQ(up.x, 1.f);
  EXPECT_FLOAT_EQ(down.x, 0.f);
  EXPECT_FLOAT_EQ(down.z, 1.f);
}

TEST(facing, errors) {
  ParamSet zero;
  zero.set("axis", std::vector<double>{0.0, 0.0, 0.0});
  EXPECT_THROW(make(zero), Error);
  ParamSet same;
  same.set("remap", std::vector<double>{0.5, 0.5});
  EXPECT_THROW(make(same), Error);
  ParamSet space;
  space.set("space", std::string("camera"));
  EXPECT_THROW(make(space), Error);
  ParamSet unknown;
  unknown.set("normal", 1.0);
  EXPECT_THROW(make(unknown), Error);
}
