// Small value types used in the render loop: Vec2f, Vec3f, Frame, Transform.
// Eigen is used outside the hot loop (matrix inversion); these are plain structs
// so that the integrator compiles to tight scalar code.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace sg {

constexpr float k_pi = 3.14159265358979323846f;
constexpr float k_inv_pi = 0.31830988618379067154f;
constexpr float k_inv_two_pi = 0.15915494309189533577f;
constexpr float k_inv_four_pi = 0.07957747154594766788f;
constexpr float k_inf = std::numeric_limits<float>::infinity();
/// Largest float strictly below 1: upper bound for canonical samples in [0, 1).
constexpr float k_one_minus_epsilon = 0x1.fffffep-1f;

struct Vec2f {
  float x = 0.f, y = 0.f;
  Vec2f() = default;
  constexpr Vec2f(float x_, float y_) : x(x_), y(y_) {}
  Vec2f operator+(const Vec2f& o) const { return {x + o.x, y + o.y}; }
  Vec2f operator-(const Vec2f& o) const { return {x - o.x, y - o.y}; }
  Vec2f operator*(float s) const { return {x * s, y * s}; }
};

struct Vec3f {
  float x = 0.f, y = 0.f, z = 0.f;
  Vec3f() = default;
  constexpr Vec3f(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  constexpr explicit Vec3f(float s) : x(s), y(s), z(s) {}
  float operator[](int i) const { return (&x)[i]; }
  float& operator[](int i) { return (&x)[i]; }
  Vec3f operator+(const Vec3f& o) const { return {x + o.x, y + o.y, z + o.z}; }
  Vec3f operator-(const Vec3f& o) const { return {x - o.x, y - o.y, z - o.z}; }
  Vec3f operator*(const Vec3f& o) const { return {x * o.x, y * o.y, z * o.z}; }
  Vec3f operator/(const Vec3f& o) const { return {x / o.x, y / o.y, z / o.z}; }
  Vec3f operator*(float s) const { return {x * s, y * s, z * s}; }
  Vec3f operator/(float s) const { float r = 1.f / s; return {x * r, y * r, z * r}; }
  Vec3f operator-() const { return {-x, -y, -z}; }
  Vec3f& operator+=(const Vec3f& o) { x += o.x; y += o.y; z += o.z; return *this; }
  Vec3f& operator*=(const Vec3f& o) { x *= o.x; y *= o.y; z *= o.z; return *this; }
  Vec3f& operator*=(float s) { x *= s; y *= s; z *= s; return *this; }
  bool operator==(const Vec3f& o) const { return x == o.x && y == o.y && z == o.z; }
  bool operator!=(const Vec3f& o) const { return !(*this == o); }
};

inline Vec3f operator*(float s, const Vec3f& v) { return v * s; }
inline float dot(const Vec3f& a, const Vec3f& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3f cross(const Vec3f& a, const Vec3f& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length_squared(const Vec3f& v) { return dot(v, v); }
inline float length(const Vec3f& v) { return std::sqrt(dot(v, v)); }
inline Vec3f normalize(const Vec3f& v) { return v / length(v); }
inline float max_component(const Vec3f& v) { return std::max(v.x, std::max(v.y, v.z)); }
inline Vec3f vmin(const Vec3f& a, const Vec3f& b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3f vmax(const Vec3f& a, const Vec3f& b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
inline Vec3f vabs(const Vec3f& v) { return {std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}; }
inline bool is_finite(const Vec3f& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
inline bool is_black(const Vec3f& v) { return v.x == 0.f && v.y == 0.f && v.z == 0.f; }
/// Rec. 709 luminance of a linear RGB triple.
inline float luminance(const Vec3f& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }
inline Vec3f face_forward(const Vec3f& n, const Vec3f& v) { return dot(n, v) < 0.f ? -n : n; }

using Color = Vec3f;

/// Orthonormal basis around a unit normal.
/// NOTE: branchless construction of Duff et al., "Building an Orthonormal Basis,
/// Revisited", JCGT 6(1), 2017, Listing 3.
struct Frame {
  Vec3f s, t, n;
  Frame() = default;
  explicit Frame(const Vec3f& normal) : n(normal) {
    float sign = std::copysign(1.f, n.z);
    float a = -1.f / (sign + n.z);
    float b = n.x * n.y * a;
    s = Vec3f(1.f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    t = Vec3f(b, sign + n.y * n.y * a, -n.y);
  }
  Vec3f to_local(const Vec3f& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  Vec3f to_world(const Vec3f& v) const { return s * v.x + t * v.y + n * v.z; }
};

/// Affine 4x4 transform stored row-major; the last row is (0, 0, 0, 1).
/// The inverse is computed once (with Eigen, in math.cpp) and cached.
/// An axis-aligned box (empty: lo > hi).
struct Bounds3 {
  Vec3f lo{k_inf, k_inf, k_inf}, hi{-k_inf, -k_inf, -k_inf};
  void expand(const Vec3f& p) { lo = vmin(lo, p); hi = vmax(hi, p); }
  bool empty() const { return lo.x > hi.x; }
  Vec3f center() const { return (lo + hi) * 0.5f; }
  float radius() const { return empty() ? 0.f : 0.5f * length(hi - lo); }
};

struct Transform {
  std::array<float, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  std::array<float, 16> m_inv{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

  Transform() = default;
  /// Builds from 16 row-major values. Throws sg::Error when the matrix is not a finite,
  /// invertible affine transform.
  static Transform from_row_major(const float* values16, const char* what = "transform");
  static Transform translate(const Vec3f& t);
  static Transform scale(const Vec3f& s);

  Vec3f apply_point(const Vec3f& p) const {
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
            m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
  }
  Vec3f apply_vector(const Vec3f& v) const {
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
            m[8] * v.x + m[9] * v.y + m[10] * v.z};
  }
  /// Normals transform with the inverse transpose.
  Vec3f apply_normal(const Vec3f& n) const {
    return {m_inv[0] * n.x + m_inv[4] * n.y + m_inv[8] * n.z,
            m_inv[1] * n.x + m_inv[5] * n.y + m_inv[9] * n.z,
            m_inv[2] * n.x + m_inv[6] * n.y + m_inv[10] * n.z};
  }
  Vec3f apply_inverse_point(const Vec3f& p) const {
    return {m_inv[0] * p.x + m_inv[1] * p.y + m_inv[2] * p.z + m_inv[3],
            m_inv[4] * p.x + m_inv[5] * p.y + m_inv[6] * p.z + m_inv[7],
            m_inv[8] * p.x + m_inv[9] * p.y + m_inv[10] * p.z + m_inv[11]};
  }
  Vec3f apply_inverse_vector(const Vec3f& v) const {
    return {m_inv[0] * v.x + m_inv[1] * v.y + m_inv[2] * v.z, m_inv[4] * v.x + m_inv[5] * v.y + m_inv[6] * v.z,
            m_inv[8] * v.x + m_inv[9] * v.y + m_inv[10] * v.z};
  }
  Transform operator*(const Transform& o) const;
  /// True when the 3x3 part has a negative determinant (mirroring flips winding).
  bool swaps_handedness() const;
  bool operator==(const Transform& o) const { return m == o.m; }
};

/// Ray with origin, direction and a [0, t_max) interval.
struct Ray {
  Vec3f o, d;
  float t_max = k_inf;
};

}  // namespace sg
