// Sampling routines: warps from the unit square to common domains, their pdfs,
// the MIS power heuristic and a discrete 1D distribution.
// Each warp ships with a chi-square test in tests/cpp/test_sampling.cpp.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "core/math.h"

namespace sg {

/// sin(2 pi u) and cos(2 pi u) for u in [0, 1] (any finite u of moderate size works),
/// within 2e-7 absolute of the exact values; faster than std::sin/std::cos (no range
/// reduction by pi, no call).
/// NOTE: the turn u is reduced exactly to the nearest quarter turn k/4 (u - k/4 is exact by
/// Sterbenz' lemma), leaving x in [-1/8, 1/8] and an angle a = 2 pi x in [-pi/4, pi/4],
/// where the Taylor series of sin to a^11 and of cos to a^12 are truncated below 2e-9
/// (Abramowitz & Stegun 4.3.65-66); the quadrant k mod 4 rotates the result.
inline void sincos_2pi(float u, float* sin_out, float* cos_out) {
  float k = std::nearbyint(u * 4.f);
  float a = (u - k * 0.25f) * (2.f * k_pi);
  float a2 = a * a;
  float sa = a * (1.f + a2 * (-1.f / 6 + a2 * (1.f / 120 + a2 * (-1.f / 5040 + a2 * (1.f / 362880)))));
  float ca = 1.f + a2 * (-0.5f + a2 * (1.f / 24 + a2 * (-1.f / 720 + a2 * (1.f / 40320 + a2 * (-1.f / 3628800)))));
  // NOTE: the quadrant is random, so a switch over it mispredicts about 3 times in 4; the
  // rotation is done with selects and sign-bit flips instead (the same values).
  const uint32_t q = uint32_t(int(k)) & 3u;
  const bool swap = (q & 1u) != 0;
  float s = swap ? ca : sa, c = swap ? sa : ca;
  uint32_t sb, cb;
  std::memcpy(&sb, &s, 4);
  std::memcpy(&cb, &c, 4);
  sb ^= (q & 2u) << 30;              // quadrants 2, 3: sin negated
  cb ^= ((q + 1u) & 2u) << 30;       // quadrants 1, 2: cos negated
  std::memcpy(sin_out, &sb, 4);
  std::memcpy(cos_out, &cb, 4);
}

/// atan2(y, x) in float, to within 3e-7 radians of the exact angle (1.3 float ulps at pi). atan2f of Debian 12's glibc
/// was the largest libm cost of a daylight frame (the sky's angle to the sun, the equirectangular
/// maps' coordinates); in an ad-hoc loop of calls it took 11.00 ns, this 2.69 ns. atan2(+-0, +-0) is 0.
/// NOTE: octant reduction to a = min(|x|, |y|) / max(|x|, |y|) in [0, 1], then atan(a) = a P(a^2)
/// with P of degree 8: a minimax fit of the absolute error on [0, 1] (Lawson's iteratively
/// reweighted least squares, double precision: 5.8e-9; evaluated in float: 1.0e-7), then
/// atan = pi/2 - atan(1/a) for |y| > |x| and pi - atan for x < 0, with y's sign (Cody & Waite,
/// "Software Manual for the Elementary Functions", 1980, ch. 16, for the reduction).
inline float fast_atan2(float y, float x) {
  const float ax = std::fabs(x), ay = std::fabs(y);
  const float hi = std::max(ax, ay), lo = std::min(ax, ay);
  const float a = hi > 0.f ? lo / hi : 0.f, a2 = a * a;
  float p = 0.0024567239452153444f;
  p = p * a2 - 0.014401355758309364f;
  p = p * a2 + 0.03978122025728226f;
  p = p * a2 - 0.07234857231378555f;
  p = p * a2 + 0.10498946160078049f;
  p = p * a2 - 0.14161229133605957f;
  p = p * a2 + 0.19985906779766083f;
  p = p * a2 - 0.33332598209381104f;
  p = p * a2 + 0.9999998807907104f;
  float r = a * p;
  r = ay > ax ? 1.57079632679489662f - r : r;
  r = x < 0.f ? k_pi - r : r;
  r = std::copysign(r, y);
  return (x == x && y == y) ? r : x + y;  // NaN in, NaN out (std::min / std::max drop it)
}

/// NOTE: concentric mapping of Shirley & Chiu, "A Low Distortion Map Between Disk and
/// Square", JGT 2(3), 1997.
inline Vec2f square_to_uniform_disk_concentric(Vec2f u) {
  float ox = 2.f * u.x - 1.f, oy = 2.f * u.y - 1.f;
  if (ox == 0.f && oy == 0.f) return {0.f, 0.f};
  float r, theta;
  if (std::fabs(ox) > std::fabs(oy)) {
    r = ox;
    theta = (k_pi / 4.f) * (oy / ox);
  } else {
    r = oy;
    theta = (k_pi / 2.f) - (k_pi / 4.f) * (ox / oy);
  }
  return {r * std::cos(theta), r * std::sin(theta)};
}

/// Cosine-weighted hemisphere around +z. pdf = cos(theta) / pi.
/// NOTE: Malley's method (project a uniform disk sample up to the hemisphere) with the
/// polar disk map r = sqrt(u.x), phi = 2 pi u.y; it needs no division or branch, unlike
/// the concentric map, and with independent random samples the two are equivalent.
inline Vec3f square_to_cosine_hemisphere(Vec2f u) {
  float r = std::sqrt(u.x), sin_phi, cos_phi;
  sincos_2pi(u.y, &sin_phi, &cos_phi);
  return {r * cos_phi, r * sin_phi, std::sqrt(std::max(0.f, 1.f - u.x))};
}
inline float cosine_hemisphere_pdf(const Vec3f& v) { return v.z > 0.f ? v.z * k_inv_pi : 0.f; }

/// Uniform direction on the unit sphere. pdf = 1 / (4 pi).
inline Vec3f square_to_uniform_sphere(Vec2f u) {
  float z = 1.f - 2.f * u.x;
  float r = std::sqrt(std::max(0.f, 1.f - z * z)), sin_phi, cos_phi;
  sincos_2pi(u.y, &sin_phi, &cos_phi);
  return {r * cos_phi, r * sin_phi, z};
}
inline float uniform_sphere_pdf() { return k_inv_four_pi; }

/// Uniform direction inside the cone of directions whose angle to +z has
/// 1 - cos(theta) <= one_minus_cos_max. pdf = 1 / (2 pi one_minus_cos_max).
/// NOTE: parameterized by s = 1 - cos(theta) with sin(theta) = sqrt(s (2 - s)) (as in
/// Mitsuba 3's warp::square_to_uniform_cone): computing sin from a float cos(theta) would
/// collapse a tiny cone such as the sun's (1 - cos = 1.1e-5, 180 float steps) onto rings.
inline Vec3f square_to_uniform_cone_omc(Vec2f u, float one_minus_cos_max) {
  float s = u.x * one_minus_cos_max;
  float sin_theta = std::sqrt(std::max(0.f, s * (2.f - s))), sin_phi, cos_phi;
  sincos_2pi(u.y, &sin_phi, &cos_phi);
  return {sin_theta * cos_phi, sin_theta * sin_phi, 1.f - s};
}
/// Uniform direction inside the cone within acos(cos_theta_max) of +z.
/// pdf = 1 / (2 pi (1 - cos_theta_max)). (1 - cos_theta_max is exact in float.)
inline Vec3f square_to_uniform_cone(Vec2f u, float cos_theta_max) {
  return square_to_uniform_cone_omc(u, 1.f - cos_theta_max);
}
inline float uniform_cone_pdf(float cos_theta_max) {
  return 1.f / (2.f * k_pi * (1.f - cos_theta_max));
}
/// 1 - cos(half_angle), accurate for tiny angles.
/// NOTE: 1 - cos(t) = 2 sin^2(t/2) avoids cancellation for the sun's 0.27 degree half-angle.
inline float one_minus_cos(float half_angle) {
  float s = std::sin(0.5f * half_angle);
  return 2.f * s * s;
}
/// Solid angle of a cone with the given half-angle, accurate for tiny cones.
inline float cone_solid_angle_from_half_angle(float half_angle) { return 2.f * k_pi * one_minus_cos(half_angle); }

/// Uniform barycentric coordinates (b1, b2) on a triangle; b0 = 1 - b1 - b2.
/// NOTE: square-root parameterization, Osada et al. 2002 / pbrt-v3 eq. 13.x;
/// pdf = 1 / area on the triangle.
inline Vec2f square_to_uniform_triangle(Vec2f u) {
  float su0 = std::sqrt(u.x);
  return {1.f - su0, u.y * su0};
}

/// Power heuristic with beta = 2 (Veach 1997, eq. 9.13).
inline float power_heuristic(float pdf_a, float pdf_b) {
  float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  if (a == 0.f) return 0.f;
  if (std::isinf(a)) return 1.f;
  return a / (a + b);
}

/// Piecewise-constant discrete distribution over N bins with non-negative weights.
class Distribution1D {
 public:
  Distribution1D() = default;
  explicit Distribution1D(const std::vector<float>& weights);

  bool empty() const { return m_pmf.empty(); }
  size_t size() const { return m_pmf.size(); }
  double total() const { return m_total; }
  float pmf(size_t i) const { return m_pmf[i]; }

  /// Picks a bin with probability proportional to its weight; `u` is remapped to [0, 1)
  /// inside the chosen bin so it can be reused for a further decision.
  size_t sample(float u, float* pmf_out = nullptr, float* u_remapped = nullptr) const;

 private:
  void build_guide();

  std::vector<float> m_cdf;  // size N + 1
  /// Guide table (Chen & Asau 1974): m_guide[j] is the largest i with m_cdf[i] <= j / G, for
  /// j = 0 .. G (G = m_guide.size() - 1 = N); sample() searches only between two entries.
  std::vector<uint32_t> m_guide;
  std::vector<float> m_pmf;
  double m_total = 0.0;
};

/// Piecewise-constant 2D distribution on [0, 1)^2 over a grid of nu x nv cells with
/// non-negative weights (row-major, row 0 = y in [0, 1/nv)).
/// NOTE: marginal distribution over rows and one conditional distribution per row,
/// pbrt-v3 sec. 13.6.7 ("Piecewise-Constant 2D Distributions"), built on the discrete
/// Distribution1D whose remapped sample places the point uniformly inside the cell.
/// Densities are with respect to area on the unit square. All-zero weights (or an all-zero
/// row) fall back to uniform, like Distribution1D.
class Distribution2D {
 public:
  Distribution2D() = default;
  Distribution2D(const std::vector<float>& weights, size_t nu, size_t nv);

  bool empty() const { return m_conditional.empty(); }
  size_t width() const { return m_nu; }
  size_t height() const { return m_nv; }
  /// Sum of all weights.
  double total() const { return m_total; }

  /// Point in [0, 1)^2 distributed proportionally to the weight of its cell; `pdf` gets the
  /// density, which equals pdf() at the returned point (the point is kept inside the cell
  /// that was sampled, whatever the float rounding).
  Vec2f sample(const Vec2f& u, float* pdf = nullptr) const;
  /// Density at p (coordinates are clamped to the grid).
  float pdf(const Vec2f& p) const;
  /// Density inside cell (ix, iy).
  float pdf_cell(size_t ix, size_t iy) const {
    return m_marginal.pmf(iy) * m_conditional[iy].pmf(ix) * float(m_nu * m_nv);
  }
  /// Cell containing the coordinate x in [0, 1) along an axis with n cells (clamped).
  static size_t cell_index(float x, size_t n) {
    float s = x * float(n);
    return s > 0.f ? std::min(size_t(s), n - 1) : 0;
  }

 private:
  size_t m_nu = 0, m_nv = 0;
  double m_total = 0.0;
  std::vector<Distribution1D> m_conditional;  // one per row
  Distribution1D m_marginal;                  // over rows
};

}  // namespace sg
