#include "core/math.h"

#include <Eigen/Dense>
#include <string>

#include "core/error.h"

namespace sg {

Transform Transform::from_row_major(const float* v, const char* what) {
  Transform t;
  for (int i = 0; i < 16; ++i) {
    if (!std::isfinite(v[i])) throw Error(std::string(what) + ": matrix has a non-finite entry");
    t.m[i] = v[i];
  }
  if (v[12] != 0.f || v[13] != 0.f || v[14] != 0.f || v[15] != 1.f)
    throw Error(std::string(what) + ": last row must be (0, 0, 0, 1) (affine transforms only)");
  Eigen::Matrix4d a;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) a(r, c) = v[r * 4 + c];
  double det = a.topLeftCorner<3, 3>().determinant();
  double scale = a.topLeftCorner<3, 3>().cwiseAbs().maxCoeff();
  if (!(std::fabs(det) > 1e-12 * scale * scale * scale) || scale == 0.0)
    throw Error(std::string(what) + ": matrix is singular (determinant " + std::to_string(det) + ")");
  Eigen::Matrix4d inv = a.inverse();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) t.m_inv[r * 4 + c] = static_cast<float>(inv(r, c));
  return t;
}

Transform Transform::translate(const Vec3f& d) {
  float v[16] = {1, 0, 0, d.x, 0, 1, 0, d.y, 0, 0, 1, d.z, 0, 0, 0, 1};
  return from_row_major(v);
}

Transform Transform::scale(const Vec3f& s) {
  float v[16] = {s.x, 0, 0, 0, 0, s.y, 0, 0, 0, 0, s.z, 0, 0, 0, 0, 1};
  return from_row_major(v);
}

Transform Transform::operator*(const Transform& o) const {
  Eigen::Matrix4d a, b;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      a(r, c) = m[r * 4 + c];
      b(r, c) = o.m[r * 4 + c];
    }
  Eigen::Matrix4d p = a * b;
  float v[16];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) v[r * 4 + c] = static_cast<float>(p(r, c));
  v[12] = v[13] = v[14] = 0.f;
  v[15] = 1.f;
  return from_row_major(v);
}

bool Transform::swaps_handedness() const {
  double det = double(m[0]) * (double(m[5]) * m[10] - double(m[6]) * m[9]) -
               double(m[1]) * (double(m[4]) * m[10] - double(m[6]) * m[8]) +
               double(m[2]) * (double(m[4]) * m[9] - double(m[5]) * m[8]);
  return det < 0.0;
}

}  // namespace sg
