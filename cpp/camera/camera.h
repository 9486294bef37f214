// Pinhole camera in the OpenCV convention.
//
// Camera space: x right, y down, z forward (the viewing direction). A camera-space
// point (X, Y, Z) projects to continuous image coordinates
//   u = fx * X / Z + cx,   v = fy * Y / Z + cy,
// and lands in pixel (floor(u), floor(v)). Pixel (i, j) covers [i, i+1) x [j, j+1); its
// centre is at (i + 0.5, j + 0.5). `world_from_camera` maps camera space to world space
// (its last column is the camera position).
//
// Lens distortion: OpenCV's model (Brown-Conrady; cv::projectPoints) with k1, k2, p1, p2, k3.
// The normalized point (x, y) = (X/Z, Y/Z) is distorted to
//   x' = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
//   y' = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y,   r^2 = x^2 + y^2,
// and u = fx x' + cx, v = fy y' + cy. Camera rays go through the distorted lens (each image
// position is undistorted), so every output, labels included, is rendered in the photo's own
// geometry: no resampling.
#pragma once

#include <cstdint>
#include <string>

#include "core/math.h"
#include "core/params.h"

namespace sg {

struct PinholeCamera {
  float fx = 1.f, fy = 1.f, cx = 0.f, cy = 0.f;
  float k1 = 0.f, k2 = 0.f, p1 = 0.f, p2 = 0.f, k3 = 0.f;  ///< OpenCV distortion coefficients
  uint32_t width = 0, height = 0;

  bool distorted() const { return k1 != 0.f || k2 != 0.f || p1 != 0.f || p2 != 0.f || k3 != 0.f; }
  /// The distortion of a normalized point (x, y) (see above).
  Vec2f distort(const Vec2f& xy) const;
  /// Its inverse: the normalized point that distorts to `xy_distorted` (Newton's method;
  /// converges inside the image for coefficients validate() accepts). Returns false when
  /// it did not converge.
  bool undistort(const Vec2f& xy_distorted, Vec2f* xy) const;
  Transform world_from_camera;

  /// Throws sg::Error when the intrinsics are unusable (zero/negative/non-finite focal
  /// length, empty image, non-finite distortion, or a distortion that folds the image back
  /// on itself before its corners: outer pixels would then have no ray).
  void validate() const;

  /// Camera ray through continuous image position (u, v); the direction is unit length.
  /// `z_per_t` receives the camera-space z of the unit direction (depth = t * z_per_t).
  Ray generate_ray(float u, float v, float* z_per_t = nullptr) const;

  /// Projects a world point (through the lens distortion); returns false when it is behind
  /// the camera.
  bool project(const Vec3f& p_world, float* u, float* v) const;

  Vec3f position() const { return world_from_camera.apply_point(Vec3f(0.f)); }

  /// Intrinsics from a vertical field of view (degrees), principal point at the image centre.
  static PinholeCamera from_fov(float vfov_degrees, uint32_t width, uint32_t height,
                                const Transform& world_from_camera);
  /// `world_from_camera` for a camera at `eye` looking at `target`; `up` is the world
  /// up vector (image y points along -up).
  static Transform look_at(const Vec3f& eye, const Vec3f& target, const Vec3f& up);
  /// The camera of plugin "pinhole" (camera/camera.cpp declares its parameters: width,
  /// height, fov_y or fx, fy, cx, cy, world_from_camera). Throws sg::Error naming `context`.
  static PinholeCamera from_params(const ParamSet& params, const std::string& context = "camera");
};

}  // namespace sg
