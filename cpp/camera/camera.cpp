#include "camera/camera.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace sg {

void PinholeCamera::validate() const {
  auto bad = [](float f) { return !std::isfinite(f) || !(f > 0.f); };
  if (bad(fx) || bad(fy))
    throw Error("camera: focal lengths fx, fy must be positive and finite (got fx=" + std::to_string(fx) +
                ", fy=" + std::to_string(fy) + ")");
  if (!std::isfinite(cx) || !std::isfinite(cy)) throw Error("camera: principal point (cx, cy) must be finite");
  if (width == 0 || height == 0) throw Error("camera: width and height must be positive");
  if (width > 65536 || height > 65536) throw Error("camera: width and height must be at most 65536");
  for (float k : {k1, k2, p1, p2, k3})
    if (!std::isfinite(k)) throw Error("camera: distortion coefficients k1, k2, p1, p2, k3 must be finite");
  if (!distorted()) return;
  // The radial factor must grow monotonically out to the image's farthest corner: where
  // d(r (1 + k1 r^2 + k2 r^4 + k3 r^6))/dr <= 0 the lens folds the image back on itself.
  double rd_max = 0.0;
  for (float u : {0.f, float(width)})
    for (float v : {0.f, float(height)})
      rd_max = std::max(rd_max, std::hypot(double(u - cx) / fx, double(v - cy) / fy));
  const double tangential = std::fabs(double(p1)) + std::fabs(double(p2));
  const double step = 1e-3;
  for (double r = 0.0;; r += step) {
    double r2 = r * r;
    double slope = 1.0 + 3.0 * k1 * r2 + 5.0 * k2 * r2 * r2 + 7.0 * k3 * r2 * r2 * r2;
    double rd = r * (1.0 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2);
    if (slope <= 0.0)
      throw Error("camera: the lens distortion (k1=" + std::to_string(k1) + ", k2=" + std::to_string(k2) +
                  ", k3=" + std::to_string(k3) + ") folds the image back at " +
                  std::to_string(int(std::lround(rd * std::max(fx, fy)))) +
                  " px from the principal point, inside the image: its outer pixels have no ray");
    if (rd > rd_max * (1.0 + 4.0 * tangential) + 1e-6 || r > 100.0) break;
  }
}

Vec2f PinholeCamera::distort(const Vec2f& xy) const {
  const float x = xy.x, y = xy.y, r2 = x * x + y * y;
  const float radial = 1.f + r2 * (k1 + r2 * (k2 + r2 * k3));
  return Vec2f(x * radial + 2.f * p1 * x * y + p2 * (r2 + 2.f * x * x),
               y * radial + p1 * (r2 + 2.f * y * y) + 2.f * p2 * x * y);
}

bool PinholeCamera::undistort(const Vec2f& xy_distorted, Vec2f* xy) const {
  // NOTE: Newton's method on D(p) - p_d = 0 with the analytic Jacobian of the Brown-Conrady
  // model (OpenCV's cv::undistortPoints iterates a fixed point 5 times instead, which is not
  // accurate for strong distortion), in double precision, from the distorted point.
  const double xd = xy_distorted.x, yd = xy_distorted.y;
  double x = xd, y = yd;
  for (int it = 0; it < 30; ++it) {
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * double(k3)));
    const double dradial = k1 + r2 * (2.0 * k2 + 3.0 * double(k3) * r2);  // d radial / d r^2
    const double fx_ = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - xd;
    const double fy_ = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - yd;
    if (std::fabs(fx_) < 1e-12 && std::fabs(fy_) < 1e-12) break;
    const double j00 = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
    const double j01 = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
    const double j10 = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
    const double j11 = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
    const double det = j00 * j11 - j01 * j10;
    if (!(std::fabs(det) > 1e-300)) return false;
    x -= (j11 * fx_ - j01 * fy_) / det;
    y -= (j00 * fy_ - j10 * fx_) / det;
    if (!std::isfinite(x) || !std::isfinite(y)) return false;
  }
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * double(k3)));
  const double ex = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - xd;
  const double ey = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - yd;
  *xy = Vec2f(float(x), float(y));
  return std::fabs(ex) < 1e-6 && std::fabs(ey) < 1e-6;
}

Ray PinholeCamera::generate_ray(float u, float v, float* z_per_t) const {
  Vec3f d_cam((u - cx) / fx, (v - cy) / fy, 1.f);
  if (distorted()) {
    Vec2f xy;
    // validate() guarantees convergence inside the image; outside it the last iterate is used.
    undistort(Vec2f(d_cam.x, d_cam.y), &xy);
    d_cam = Vec3f(xy.x, xy.y, 1.f);
  }
  // z per unit distance along the ray: the z of the unit camera-space direction.
  if (z_per_t) *z_per_t = 1.f / length(d_cam);
  Ray r;
  const auto& m = world_from_camera.m;
  r.o = Vec3f(m[3], m[7], m[11]);  // the camera-space origin in world space
  r.d = normalize(world_from_camera.apply_vector(d_cam));
  r.t_max = k_inf;
  return r;
}

bool PinholeCamera::project(const Vec3f& p_world, float* u, float* v) const {
  Vec3f pc = world_from_camera.apply_inverse_point(p_world);
  if (!(pc.z > 0.f)) return false;
  Vec2f xy(pc.x / pc.z, pc.y / pc.z);
  if (distorted()) xy = distort(xy);
  *u = fx * xy.x + cx;
  *v = fy * xy.y + cy;
  return true;
}

PinholeCamera PinholeCamera::from_fov(float vfov_degrees, uint32_t width, uint32_t height,
                                      const Transform& world_from_camera) {
  if (!(vfov_degrees > 0.f && vfov_degrees < 180.f))
    throw Error("camera: vertical field of view must lie in (0, 180) degrees, got " + std::to_string(vfov_degrees));
  PinholeCamera c;
  float f = 0.5f * float(height) / std::tan(0.5f * vfov_degrees * k_pi / 180.f);
  c.fx = c.fy = f;
  c.cx = 0.5f * float(width);
  c.cy = 0.5f * float(height);
  c.width = width;
  c.height = height;
  c.world_from_camera = world_from_camera;
  c.validate();
  return c;
}

Transform PinholeCamera::look_at(const Vec3f& eye, const Vec3f& target, const Vec3f& up) {
  Vec3f z = target - eye;
  if (!(length(z) > 0.f)) throw Error("look_at: eye and target coincide");
  z = normalize(z);
  Vec3f x = cross(z, up);  // right = forward x up  (y is down)
  if (!(length(x) > 1e-6f)) throw Error("look_at: up vector is parallel to the viewing direction");
  x = normalize(x);
  Vec3f y = cross(z, x);  // down
  float m[16] = {x.x, y.x, z.x, eye.x, x.y, y.y, z.y, eye.y, x.z, y.z, z.z, eye.z, 0, 0, 0, 1};
  return Transform::from_row_major(m, "look_at");
}

}  // namespace sg
