// Internal (not a plugin): equirectangular (latitude-longitude) maps of the sphere of
// directions, shared by the lights "envmap" and "sky": the direction <-> image mapping and
// importance sampling of a piecewise-constant (nearest-pixel) map.
//
// Orientation, in map space (y up), the convention of Mitsuba 3's "envmap" emitter:
//   v = 0 (top row) is +y, v = 1 (bottom row) is -y; theta = pi v is the angle from +y.
//   u = 0 (left edge) is -z, u = 1/4 is +x, u = 1/2 (image centre) is +z, u = 3/4 is -x;
//   phi = 2 pi u, and the direction is (sin theta sin phi, cos theta, -sin theta cos phi).
// Seen from inside, the image is not mirrored: a camera at the origin looking along +z with
// +y up sees the image centre, and the image's right half (u > 1/2, towards -x) on its right.
// In compass terms (north = -z, east = +x in a right-handed y-up world) u = azimuth / 360,
// the azimuth measured clockwise from north when seen from above; "sky" uses the same azimuth.
#pragma once

#include <cmath>
#include <vector>

#include "core/math.h"
#include "core/sampling.h"

namespace sg {

/// Map-space direction of the image coordinates (u, v) in [0, 1]^2.
/// NOTE: sin and cos of phi = 2 pi u and theta = pi v from sincos_2pi (2e-7 absolute, no libm call).
inline Vec3f equirect_direction(const Vec2f& uv) {
  float sin_phi, cos_phi, sin_theta, cos_theta;
  sincos_2pi(uv.x, &sin_phi, &cos_phi);
  sincos_2pi(0.5f * uv.y, &sin_theta, &cos_theta);
  return {sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi};
}

/// Image coordinates (u, v) in [0, 1]^2 of a unit map-space direction.
/// NOTE: theta from atan2(sin, cos) rather than acos(cos): the same angle for a unit d, accurate
/// near the poles too, and both angles from fast_atan2 (no libm call).
inline Vec2f equirect_uv(const Vec3f& d) {
  float u = fast_atan2(d.x, -d.z) * k_inv_two_pi;
  if (u < 0.f) u += 1.f;
  float v = fast_atan2(std::sqrt(d.x * d.x + d.z * d.z), d.y) * k_inv_pi;
  return {u, v};
}

/// Importance sampling of a width x height map of non-negative weights (row-major, top
/// row first) read with nearest-pixel lookup, i.e. a piecewise-constant function of (u, v).
class EquirectSampler {
 public:
  EquirectSampler() = default;
  EquirectSampler(const std::vector<float>& values, int width, int height) : m_width(width), m_height(height) {
    // NOTE: sampling density proportional to value x sin(theta) over (u, v), pbrt-v3
    // sec. 14.2.4 ("Infinite Area Lights"): the sin(theta) factor of the Jacobian
    // d(omega) = 2 pi^2 sin(theta) du dv keeps the stretched polar rows from being
    // oversampled. sin(theta) is taken at the row centre.
    std::vector<float> w(values.size());
    double mean = 0.0;
    for (int y = 0; y < height; ++y) {
      double theta0 = M_PI * y / height, theta1 = M_PI * (y + 1) / height;
      float sin_c = float(std::sin(0.5 * (theta0 + theta1)));
      // Solid angle of one pixel of this row: (2 pi / width) (cos theta0 - cos theta1).
      double pixel_solid_angle = 2.0 * M_PI / width * (std::cos(theta0) - std::cos(theta1));
      for (int x = 0; x < width; ++x) {
        size_t i = size_t(y) * width + x;
        w[i] = values[i] * sin_c;
        mean += double(values[i]) * pixel_solid_angle;
      }
    }
    m_mean = float(mean / (4.0 * M_PI));
    m_dist = Distribution2D(w, size_t(width), size_t(height));
  }

  /// The sampler of a width x height table of the luminance that `radiance` (a function of the
  /// map-space direction, returning a Color) has at the pixel centres.
  template <typename Radiance>
  static EquirectSampler of_radiance(int width, int height, const Radiance& radiance) {
    std::vector<float> lum(size_t(width) * height);
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        lum[size_t(y) * width + x] =
            luminance(radiance(equirect_direction(Vec2f((x + 0.5f) / width, (y + 0.5f) / height))));
    return EquirectSampler(lum, width, height);
  }

  int width() const { return m_width; }
  int height() const { return m_height; }
  /// Solid-angle average of the values over the sphere.
  float mean() const { return m_mean; }

  /// Pixel (row-major index) that nearest-pixel lookup reads for the unit direction d.
  size_t pixel(const Vec3f& d) const { return pixel(equirect_uv(d)); }
  size_t pixel(const Vec2f& uv) const {
    return Distribution2D::cell_index(uv.y, size_t(m_height)) * size_t(m_width) +
           Distribution2D::cell_index(uv.x, size_t(m_width));
  }

  /// A map-space direction distributed with density pdf(). Callers take the density (and
  /// the radiance) from the returned direction, so that they agree exactly with what
  /// pdf_le()/le() report for it.
  Vec3f sample(const Vec2f& u) const { return equirect_direction(m_dist.sample(u)); }

  /// normalize(sample(u)) and its density, equal to pdf() of that direction bit for bit: the
  /// sampled cell's density when the point lies far enough inside its cell that the direction's
  /// round trip through equirect_uv cannot leave it, else pdf() itself.
  /// NOTE: the round trip (sincos_2pi, normalize, fast_atan2) moves v by under 4e-7 and u by
  /// under (6e-7 / sin theta + 3e-7) / (2 pi) + 1e-7; the margins below are 1e-5 for v and
  /// 2e-5 / sin theta for u, more than 20 times those. Sampling then skips two atan2s and the
  /// density table's lookup (a default-scenario frame, whole process: old / new time 1.0490);
  /// tests/cpp/test_envmap.cpp checks the equality over 1.2 million samples.
  Vec3f sample_with_pdf(const Vec2f& u, float* pdf_out) const {
    float cell_pdf = 0.f;
    const Vec2f uv = m_dist.sample(u, &cell_pdf);
    const Vec3f wi = normalize(equirect_direction(uv));
    const float sin_theta = std::sqrt(wi.x * wi.x + wi.z * wi.z);
    const float fu = uv.x * float(m_width), fv = uv.y * float(m_height);
    const float du = std::min(fu - std::floor(fu), std::floor(fu) + 1.f - fu) / float(m_width);
    const float dv = std::min(fv - std::floor(fv), std::floor(fv) + 1.f - fv) / float(m_height);
    if (sin_theta > 0.f && dv > 1e-5f && du * sin_theta > 2e-5f)
      *pdf_out = solid_angle_density(cell_pdf, wi);
    else
      *pdf_out = pdf(wi);
    return wi;
  }

  /// Solid-angle density of sample() at the unit map-space direction d.
  float pdf(const Vec3f& d) const { return solid_angle_density(m_dist.pdf(equirect_uv(d)), d); }

  /// The solid-angle density at the unit direction d of the (u, v) density `cell_pdf`.
  /// NOTE: p(omega) = p(u, v) / (2 pi^2 sin theta), pbrt-v3 eq. 14.8. Out of line: with FMA
  /// contraction (GCC's default -ffp-contract=fast) sin theta inlined into two callers may round
  /// differently, and sample_with_pdf() must agree with pdf() bit for bit.
  [[gnu::noinline]] static float solid_angle_density(float cell_pdf, const Vec3f& d) {
    const float sin_theta = std::sqrt(d.x * d.x + d.z * d.z);
    if (!(sin_theta > 0.f)) return 0.f;
    return cell_pdf / (2.f * k_pi * k_pi * sin_theta);
  }

 private:
  int m_width = 0, m_height = 0;
  float m_mean = 0.f;
  Distribution2D m_dist;
};

}  // namespace sg
