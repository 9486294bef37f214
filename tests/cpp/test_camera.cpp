// Pinhole camera (camera/camera.h) in the OpenCV convention: x right, y down, z forward;
// u = fx X / Z + cx, v = fy Y / Z + cy; pixel (i, j) has its centre at (i + 0.5, j + 0.5).
#include <gtest/gtest.h>

#include <cmath>

#include "camera/camera.h"
#include "core/error.h"
#include "core/rng.h"

using namespace sg;

namespace {

struct D3 {
  double x, y, z;
};
D3 d3(const Vec3f& v) { return {v.x, v.y, v.z}; }
D3 sub(const D3& a, const D3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dot3(const D3& a, const D3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 cross3(const D3& a, const D3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double len3(const D3& a) { return std::sqrt(dot3(a, a)); }
D3 norm3(const D3& a) { return {a.x / len3(a), a.y / len3(a), a.z / len3(a)}; }

const Vec3f k_eye(3.f, -4.f, 2.f), k_target(0.5f, 1.f, 0.3f), k_up(0.f, 0.f, 1.f);

/// Asymmetric intrinsics (fx != fy, principal point off-centre) and a look_at pose.
PinholeCamera test_camera() {
  PinholeCamera c;
  c.fx = 520.f;
  c.fy = 480.f;
  c.cx = 330.7f;
  c.cy = 250.2f;
  c.width = 640;
  c.height = 480;
  c.world_from_camera = PinholeCamera::look_at(k_eye, k_target, k_up);
  return c;
}

/// Camera axes in world space from the OpenCV definition, computed in double:
/// z forward, x = z cross up (right), y = z cross x (down).
void reference_axes(D3* x, D3* y, D3* z) {
  *z = norm3(sub(d3(k_target), d3(k_eye)));
  *x = norm3(cross3(*z, d3(k_up)));
  *y = cross3(*z, *x);
}

}  // namespace

TEST(camera, project_then_generate_ray_passes_through_the_point) {
  PinholeCamera cam = test_camera();
  D3 ax, ay, az;
  reference_axes(&ax, &ay, &az);
  Pcg32 rng(701);
  int tested = 0;
  for (int i = 0; i < 20000; ++i) {
    // Random point inside the view frustum (and a bit beyond), depth 0.2 .. 200.
    double Z = 0.2 * std::pow(1000.0, rng.next_float());
    double u_ref = -50.0 + 740.0 * rng.next_float(), v_ref = -50.0 + 580.0 * rng.next_float();
    double X = (u_ref - cam.cx) / cam.fx * Z, Y = (v_ref - cam.cy) / cam.fy * Z;
    D3 pw{k_eye.x + X * ax.x + Y * ay.x + Z * az.x, k_eye.y + X * ax.y + Y * ay.y + Z * az.y,
          k_eye.z + X * ax.z + Y * ay.z + Z * az.z};
    Vec3f p(float(pw.x), float(pw.y), float(pw.z));
    float u, v;
    ASSERT_TRUE(cam.project(p, &u, &v));
    // The projection follows the pinhole formula (tolerance: float rounding of the point).
    D3 pc = sub(d3(p), d3(k_eye));
    double Xc = dot3(pc, ax), Yc = dot3(pc, ay), Zc = dot3(pc, az);
    EXPECT_NEAR(u, cam.fx * Xc / Zc + cam.cx, 2e-3);
    EXPECT_NEAR(v, cam.fy * Yc / Zc + cam.cy, 2e-3);
    // The camera ray through (u, v) passes through the point: distance from the ray
    // below 1e-4 of the distance to the camera.
    float z_per_t;
    Ray r = cam.generate_ray(u, v, &z_per_t);
    EXPECT_NEAR(length(r.d), 1.f, 1e-6f);
    D3 op = sub(d3(p), d3(r.o));
    double t = dot3(op, d3(r.d));
    ASSERT_GT(t, 0.0);
    D3 perp = sub(op, D3{r.d.x * t, r.d.y * t, r.d.z * t});
    EXPECT_LT(len3(perp), 1e-4 * len3(op)) << "point at depth " << Z;
    // Depth convention: t * z_per_t is the camera-space z.
    EXPECT_NEAR(t * z_per_t / Zc, 1.0, 1e-4);
    ++tested;
  }
  EXPECT_EQ(tested, 20000);
}

TEST(camera, principal_point_ray_is_the_optical_axis) {
  PinholeCamera cam = test_camera();
  Ray r = cam.generate_ray(cam.cx, cam.cy);
  const auto& m = cam.world_from_camera.m;
  D3 zcol = norm3({m[2], m[6], m[10]});
  EXPECT_NEAR(r.d.x, zcol.x, 1e-6);
  EXPECT_NEAR(r.d.y, zcol.y, 1e-6);
  EXPECT_NEAR(r.d.z, zcol.z, 1e-6);
  // ... and the z column is the viewing direction of look_at.
  D3 ax, ay, az;
  reference_axes(&ax, &ay, &az);
  EXPECT_NEAR(dot3(zcol, az), 1.0, 1e-6);
  EXPECT_EQ(r.o, k_eye);
  EXPECT_EQ(cam.position(), k_eye);
}

TEST(camera, pixel_centre_convention) {
  PinholeCamera cam = test_camera();
  // The ray through the centre of pixel (i, j) is generated at (i + 0.5, j + 0.5) and a
  // point on it projects back into pixel (i, j), not onto a pixel corner.
  for (int i : {0, 17, 320, 639})
    for (int j : {0, 250, 479}) {
      Ray r = cam.generate_ray(i + 0.5f, j + 0.5f);
      Vec3f p = r.o + r.d * 7.5f;
      float u, v;
      ASSERT_TRUE(cam.project(p, &u, &v));
      EXPECT_NEAR(u, i + 0.5f, 1e-3f);
      EXPECT_NEAR(v, j + 0.5f, 1e-3f);
      EXPECT_EQ(int(std::floor(u)), i);
      EXPECT_EQ(int(std::floor(v)), j);
    }
}

TEST(camera, look_at_orientation) {
  PinholeCamera cam = test_camera();
  D3 ax, ay, az;
  reference_axes(&ax, &ay, &az);
  Vec3f target = k_target;
  float u0, v0, u, v;
  ASSERT_TRUE(cam.project(target, &u0, &v0));
  EXPECT_NEAR(u0, cam.cx, 1e-3);
  EXPECT_NEAR(v0, cam.cy, 1e-3);
  // Image y points along -up: a point above the target appears higher (smaller v).
  ASSERT_TRUE(cam.project(target + k_up * 0.5f, &u, &v));
  EXPECT_LT(v, v0 - 10.f);
  EXPECT_NEAR(u, u0, 1e-2);  // up projects onto the image's vertical axis
  // Image x points right: along forward x up.
  Vec3f right(float(ax.x), float(ax.y), float(ax.z));
  ASSERT_TRUE(cam.project(target + right * 0.5f, &u, &v));
  EXPECT_GT(u, u0 + 10.f);
  EXPECT_NEAR(v, v0, 1e-2);
  // The rotation part is orthonormal and right-handed (x cross y = z).
  const auto& m = cam.world_from_camera.m;
  D3 cx{m[0], m[4], m[8]}, cy{m[1], m[5], m[9]}, cz{m[2], m[6], m[10]};
  EXPECT_NEAR(dot3(cx, cy), 0.0, 1e-6);
  EXPECT_NEAR(len3(cx), 1.0, 1e-6);
  EXPECT_NEAR(len3(cy), 1.0, 1e-6);
  D3 xy = cross3(cx, cy);
  EXPECT_NEAR(dot3(xy, cz), 1.0, 1e-6);
  EXPECT_NEAR(dot3(cy, d3(k_up)), -std::sqrt(1.0 - dot3(az, d3(k_up)) * dot3(az, d3(k_up))), 1e-6);
  // Points behind the camera do not project.
  EXPECT_FALSE(cam.project(k_eye - (target - k_eye), &u, &v));
  // Degenerate look_at.
  EXPECT_THROW(PinholeCamera::look_at(k_eye, k_eye, k_up), Error);
  EXPECT_THROW(PinholeCamera::look_at(Vec3f(0.f), Vec3f(0.f, 0.f, 5.f), Vec3f(0.f, 0.f, 1.f)), Error);
}

TEST(camera, from_fov_intrinsics) {
  for (float vfov : {10.f, 45.f, 90.f, 150.f}) {
    PinholeCamera c = PinholeCamera::from_fov(vfov, 640, 360, Transform());
    double f = 0.5 * 360.0 / std::tan(0.5 * vfov * 3.14159265358979323846 / 180.0);
    EXPECT_NEAR(c.fy / f, 1.0, 1e-6) << vfov;
    EXPECT_EQ(c.fx, c.fy);
    EXPECT_EQ(c.cx, 320.f);
    EXPECT_EQ(c.cy, 180.f);
    EXPECT_EQ(c.width, 640u);
    EXPECT_EQ(c.height, 360u);
    // The top edge of the image is half the vertical field of view above the axis.
    Ray top = c.generate_ray(c.cx, 0.f);
    double angle = std::acos(double(top.d.z)) * 180.0 / 3.14159265358979323846;
    EXPECT_NEAR(angle, 0.5 * vfov, 1e-3) << vfov;
    EXPECT_LT(top.d.y, 0.f) << "image top must be camera -y";
  }
  EXPECT_THROW(PinholeCamera::from_fov(0.f, 64, 64, Transform()), Error);
  EXPECT_THROW(PinholeCamera::from_fov(180.f, 64, 64, Transform()), Error);
}

TEST(camera, validate) {
  PinholeCamera c = test_camera();
  EXPECT_NO_THROW(c.validate());
  c.fx = 0.f;
  EXPECT_THROW(c.validate(), Error);
  c = test_camera();
  c.fy = -1.f;
  EXPECT_THROW(c.validate(), Error);
  c = test_camera();
  c.cx = std::numeric_limits<float>::infinity();
  EXPECT_THROW(c.validate(), Error);
  c = test_camera();
  c.height = 0;
  EXPECT_THROW(c.validate(), Error);
}

namespace {

/// OpenCV's distortion evaluated independently in double (cv::projectPoints' formula).
void opencv_distort(double k1, double k2, double p1, double p2, double k3, double x, double y, double* xd, double* yd) {
  double r2 = x * x + y * y;
  double radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
  *xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
  *yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
}

}  // namespace

// Barrel (a wide-angle dashcam's) and pincushion distortion with tangential terms.
TEST(camera, distortion_is_opencvs_and_rays_invert_it) {
  const float coeffs[2][5] = {{-0.28f, 0.09f, 0.0012f, -0.0008f, -0.012f}, {0.12f, 0.02f, -0.001f, 0.0015f, 0.f}};
  for (const auto& k : coeffs) {
    PinholeCamera c = test_camera();
    c.k1 = k[0], c.k2 = k[1], c.p1 = k[2], c.p2 = k[3], c.k3 = k[4];
    ASSERT_NO_THROW(c.validate());
    Pcg32 rng(7);
    double worst_px = 0.0, worst_inverse = 0.0;
    for (int i = 0; i < 2000; ++i) {
      // A pixel anywhere in the image, corners included.
      float u = rng.next_float() * float(c.width), v = rng.next_float() * float(c.height);
      Ray r = c.generate_ray(u, v);
      // The ray's normalized point distorts to the pixel (OpenCV's formula, in double).
      Vec3f pc = c.world_from_camera.apply_inverse_vector(r.d);
      double xd, yd;
      opencv_distort(c.k1, c.k2, c.p1, c.p2, c.k3, pc.x / pc.z, pc.y / pc.z, &xd, &yd);
      worst_px = std::max(worst_px, std::hypot(c.fx * xd + c.cx - u, c.fy * yd + c.cy - v));
      // project() inverts generate_ray.
      float pu, pv;
      ASSERT_TRUE(c.project(r.o + r.d * 3.f, &pu, &pv));
      worst_px = std::max(worst_px, double(std::hypot(pu - u, pv - v)));
      // undistort(distort(p)) == p.
      Vec2f p((u - c.cx) / c.fx * 0.9f, (v - c.cy) / c.fy * 0.9f), back;
      ASSERT_TRUE(c.undistort(c.distort(p), &back));
      worst_inverse = std::max(worst_inverse, double(std::hypot(back.x - p.x, back.y - p.y)));
    }
    EXPECT_LT(worst_px, 2e-3) << "pixels";
    EXPECT_LT(worst_inverse, 1e-5) << "normalized units";
  }
}

TEST(camera, distortion_that_folds_the_image_is_refused) {
  PinholeCamera c = test_camera();
  c.k1 = -0.9f;  // r (1 - 0.9 r^2) turns back at r = 0.61, inside the image's corners (r_d ~ 0.8)
  try {
    c.validate();
    FAIL() << "accepted a folding distortion";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("folds the image back"), std::string::npos) << e.what();
  }
  c.k1 = std::nanf("");
  EXPECT_THROW(c.validate(), Error);
}
