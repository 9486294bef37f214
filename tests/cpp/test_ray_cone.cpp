// Ray cones for texture level of detail (integrator/ray_cone.h): camera spread angle,
// triangle LOD term, footprint and bounce spread against closed-form values.
#include <gtest/gtest.h>

#include <cmath>

#include "integrator/ray_cone.h"

using namespace sg;

namespace {

TriangleMesh quad(float half, bool with_uvs) {
  TriangleMesh m;
  m.positions = {{-half, -half, 0}, {half, -half, 0}, {half, half, 0}, {-half, half, 0}};
  if (with_uvs) m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

}  // namespace

TEST(ray_cone, camera_spread_is_the_angle_of_one_pixel) {
  // eq. (30): gamma = atan(2 tan(fov/2) / H).
  const float fov = 50.f;
  PinholeCamera cam = PinholeCamera::from_fov(fov, 320, 240, Transform());
  float expected = std::atan(2.f * std::tan(0.5f * fov * k_pi / 180.f) / 240.f);
  EXPECT_NEAR(pixel_spread_angle(cam), expected, 1e-7f);
  cam.fx = 100.f;  // the wider of the two pixel angles
  cam.fy = 400.f;
  EXPECT_NEAR(pixel_spread_angle(cam), std::atan(0.01f), 1e-7f);
}

TEST(ray_cone, triangle_lod_term_is_sqrt_of_uv_over_world_area) {
  TriangleMesh m = quad(1.f, true);  // world 2 x 2 for uv 1 x 1
  InstanceRecord inst;
  inst.mesh = &m;
  EXPECT_NEAR(uv_per_world_length(inst, 0), 0.5f, 1e-6f);
  EXPECT_NEAR(uv_per_world_length(inst, 1), 0.5f, 1e-6f);
  inst.world_from_object = Transform::scale(Vec3f(3.f, 3.f, 1.f));  // the instance transform counts
  EXPECT_NEAR(uv_per_world_length(inst, 0), 0.5f / 3.f, 1e-6f);
  inst.world_from_object = Transform::scale(Vec3f(4.f, 1.f, 1.f));  // anisotropic: sqrt of the area ratio
  EXPECT_NEAR(uv_per_world_length(inst, 0), 0.25f, 1e-6f);

  TriangleMesh no_uv = quad(1.f, false);  // barycentric uvs: area 1/2 over world area 2
  inst.mesh = &no_uv;
  inst.world_from_object = Transform();
  EXPECT_NEAR(uv_per_world_length(inst, 0), std::sqrt(0.25f), 1e-6f);

  TriangleMesh flat_uv = quad(1.f, true);
  flat_uv.uvs = {{0, 0}, {1, 0}, {2, 0}, {3, 0}};  // degenerate uv mapping: point samples
  inst.mesh = &flat_uv;
  EXPECT_EQ(uv_per_world_length(inst, 0), 0.f);
}

TEST(ray_cone, footprint_grows_with_one_over_cos) {
  Vec3f n(0, 0, 1);
  EXPECT_NEAR(ray_cone_uv_footprint(0.02f, n, Vec3f(0, 0, -1), 0.5f), 0.01f, 1e-8f);
  float c = 0.25f;
  Vec3f d(std::sqrt(1 - c * c), 0, -c);
  EXPECT_NEAR(ray_cone_uv_footprint(0.02f, n, d, 0.5f), 0.01f / c, 1e-7f);
  EXPECT_TRUE(std::isinf(ray_cone_uv_footprint(0.02f, n, Vec3f(1, 0, 0), 0.5f)));
  EXPECT_EQ(ray_cone_uv_footprint(0.f, n, d, 0.5f), 0.f);
  EXPECT_EQ(ray_cone_uv_footprint(0.02f, n, d, 0.f), 0.f);
}

TEST(ray_cone, bounce_spread) {
  BsdfSample bs;
  bs.flags = k_bsdf_delta | k_bsdf_reflection;
  bs.pdf = 1.f;
  EXPECT_EQ(bsdf_spread_angle(bs), 0.f);  // flat mirrors keep the cone
  bs.flags = k_bsdf_diffuse | k_bsdf_reflection;
  bs.pdf = k_inv_pi;  // Lambertian at normal incidence: clamped wide cone
  EXPECT_NEAR(bsdf_spread_angle(bs), k_pi / 8.f, 1e-7f);
  bs.flags = k_bsdf_glossy | k_bsdf_reflection;
  bs.pdf = 1e4f;  // a sharp lobe: solid angle 1/pdf, full cone angle 2/sqrt(pi pdf)
  EXPECT_NEAR(bsdf_spread_angle(bs), 2.f / std::sqrt(k_pi * 1e4f), 1e-7f);
  EXPECT_NEAR(camera_sample_spread_scale(1), 1.f, 0.f);
  EXPECT_NEAR(camera_sample_spread_scale(16), 0.25f, 1e-7f);
  EXPECT_NEAR(camera_sample_spread_scale(4096), 0.125f, 0.f);
}

TEST(ray_cone, footprint_ellipse_in_uv_space) {
  TriangleMesh m = quad(1.f, true);  // z = 0 plane, uv = (x + 1) / 2, (y + 1) / 2
  InstanceRecord inst;
  inst.mesh = &m;
  Vec3f n(0, 0, 1);
  const float w = 0.02f, c = 0.25f;
  Vec3f d(0, std::sqrt(1 - c * c), -c);  // slanted along +y
  Vec2f a, b;
  ASSERT_TRUE(ray_cone_uv_ellipse(inst, 0, n, d, w, &a, &b));
  // Major axis w / cos along the projected direction (uv v), minor w across (uv u); 1 m = 0.5 uv.
  EXPECT_NEAR(a.x, 0.f, 1e-7f);
  EXPECT_NEAR(std::fabs(a.y), 0.5f * w / c, 1e-6f);
  EXPECT_NEAR(std::fabs(b.x), 0.5f * w, 1e-7f);
  EXPECT_NEAR(b.y, 0.f, 1e-7f);
  // Its longer axis is the isotropic footprint of eq. (34) for a uniform uv mapping.
  EXPECT_NEAR(std::fabs(a.y), ray_cone_uv_footprint(w, n, d, uv_per_world_length(inst, 0)), 1e-6f);

  // A stretched uv mapping (u compressed 4x by the instance) stretches the ellipse in u only.
  inst.world_from_object = Transform::scale(Vec3f(4.f, 1.f, 1.f));
  ASSERT_TRUE(ray_cone_uv_ellipse(inst, 1, n, d, w, &a, &b));
  EXPECT_NEAR(std::fabs(b.x), 0.5f * w / 4.f, 1e-7f);
  EXPECT_NEAR(std::fabs(a.y), 0.5f * w / c, 1e-6f);

  // set_ray_cone_footprint fills all three fields; head-on the ellipse is a circle.
  inst.world_from_object = Transform();
  SurfaceInteraction si;
  si.ng = n;
  set_ray_cone_footprint(&si, inst, 0, Vec3f(0, 0, -1), w);
  EXPECT_NEAR(si.uv_footprint, 0.5f * w, 1e-7f);
  EXPECT_NEAR(std::hypot(si.uv_axis_a.x, si.uv_axis_a.y), 0.5f * w, 1e-7f);
  EXPECT_NEAR(std::hypot(si.uv_axis_b.x, si.uv_axis_b.y), 0.5f * w, 1e-7f);
  EXPECT_NEAR(si.uv_axis_a.x * si.uv_axis_b.x + si.uv_axis_a.y * si.uv_axis_b.y, 0.f, 1e-9f);
  // Exactly grazing: no ellipse, infinite isotropic footprint (the texture average).
  set_ray_cone_footprint(&si, inst, 0, Vec3f(1, 0, 0), w);
  EXPECT_TRUE(std::isinf(si.uv_footprint));
  EXPECT_EQ(si.uv_axis_a.x, 0.f);
  EXPECT_EQ(si.uv_axis_a.y, 0.f);
}
