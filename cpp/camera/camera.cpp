#include "camera/camera.h"

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
}

Ray PinholeCamera::generate_ray(float u, float v, float* z_per_t) const {
  Vec3f d_cam((u - cx) / fx, (v - cy) / fy, 1.f);
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
  *u = fx * pc.x / pc.z + cx;
  *v = fy * pc.y / pc.z + cy;
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
