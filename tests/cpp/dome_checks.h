// Checks shared by the tests of the dome lights (sky, twilight): directions by elevation and
// azimuth, irradiance by light sampling and by quadrature of le(), the sphere's mean luminance.
#pragma once

#include <cmath>
#include <algorithm>
#include <cstdint>
#include <vector>

#include "chi2.h"
#include "core/rng.h"
#include "light/light.h"

namespace sgtest {

inline sg::Vec3f to_f(const DVec3& v) { return sg::Vec3f(float(v.x), float(v.y), float(v.z)); }
inline DVec3 to_d(const sg::Vec3f& v) { return {v.x, v.y, v.z}; }
inline double deg(double d) { return d * k_pi_d / 180.0; }

/// The unit direction at an elevation and a compass azimuth (clockwise from north = -z).
inline DVec3 direction(double elevation_deg, double azimuth_deg) {
  double e = deg(elevation_deg), a = deg(azimuth_deg);
  return {std::cos(e) * std::sin(a), std::sin(e), -std::cos(e) * std::cos(a)};
}

/// Irradiance on a surface with normal n at the origin from `samples` light samples.
inline DVec3 mc_irradiance(const sg::Light& l, const DVec3& n, int samples, uint64_t seed) {
  sg::Pcg32 rng(seed);
  DVec3 e{0, 0, 0};
  for (int i = 0; i < samples; ++i) {
    sg::LightSample ls;
    if (!l.sample({sg::Vec3f(0.f), sg::Vec3f(0.f)}, rng.next_2d(), &ls)) continue;
    double c = ddot(n, to_d(ls.wi));
    if (c <= 0.0) continue;
    double w = c / double(ls.pdf) / samples;
    e.x += ls.li.x * w, e.y += ls.li.y * w, e.z += ls.li.z * w;
  }
  return e;
}

/// Horizontal irradiance of le() above the horizon by quadrature (midpoint rule in cos theta and
/// phi, nz x 2 nz cells).
inline DVec3 quadrature_horizontal_irradiance(const sg::Light& l, int nz = 200) {
  const int nphi = 2 * nz;
  DVec3 e{0, 0, 0};
  for (int i = 0; i < nz; ++i)
    for (int j = 0; j < nphi; ++j) {
      double z = (i + 0.5) / nz, phi = 2.0 * k_pi_d * (j + 0.5) / nphi, r = std::sqrt(1.0 - z * z);
      sg::Color c = l.le(to_f({r * std::cos(phi), z, r * std::sin(phi)}));
      e.x += c.x * z, e.y += c.y * z, e.z += c.z * z;
    }
  double w = 2.0 * k_pi_d / (double(nz) * nphi);
  return {e.x * w, e.y * w, e.z * w};
}

/// The direction at equirectangular coordinates (u, v) in [0, 1]^2 (light/equirect.h's mapping).
inline DVec3 equirect_dir(double u, double v) {
  double th = k_pi_d * v, ph = 2.0 * k_pi_d * u;
  return DVec3{std::sin(th) * std::sin(ph), std::cos(th), -std::sin(th) * std::cos(ph)};
}

/// The cell of grid g (over equirectangular (u, v)) that the unit direction w falls in.
inline size_t equirect_cell(const Grid2D& g, const sg::Vec3f& w) {
  double u = wrap_phi(std::atan2(double(w.x), -double(w.z))) / (2.0 * k_pi_d);
  double v = std::acos(std::max(-1.0, std::min(1.0, double(w.y)))) / k_pi_d;
  return size_t(g.cell(u, v));
}

/// Expected counts of n samples per cell of g from the light's pdf_le (a solid-angle density):
/// the midpoint rule with 8 x 8 nodes per cell (none on a cell edge), d omega = 2 pi^2 sin(pi v)
/// du dv.
inline std::vector<double> equirect_expected_counts(const sg::Light& l, const Grid2D& g, int n) {
  std::vector<double> exp(g.size());
  for (int iy = 0; iy < g.ny; ++iy)
    for (int ix = 0; ix < g.nx; ++ix) {
      double acc = 0.0;
      for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b) {
          double u = g.cx0(ix) + (g.cx1(ix) - g.cx0(ix)) * (a + 0.5) / 8;
          double v = g.cy0(iy) + (g.cy1(iy) - g.cy0(iy)) * (b + 0.5) / 8;
          acc += double(l.pdf_le(to_f(equirect_dir(u, v)))) * 2.0 * k_pi_d * k_pi_d * std::sin(k_pi_d * v);
        }
      exp[size_t(iy) * g.nx + ix] = n * acc / 64.0 * (g.cx1(ix) - g.cx0(ix)) * (g.cy1(iy) - g.cy0(iy));
    }
  return exp;
}

/// The mean luminance of le() over the sphere of directions (midpoint rule in z and phi).
inline double sphere_mean_luminance(const sg::Light& l) {
  const int nz = 200, nphi = 400;
  double mean = 0.0;
  for (int i = 0; i < nz; ++i)
    for (int j = 0; j < nphi; ++j) {
      double z = -1.0 + 2.0 * (i + 0.5) / nz, phi = 2.0 * k_pi_d * (j + 0.5) / nphi, r = std::sqrt(1.0 - z * z);
      mean += sg::luminance(l.le(to_f({r * std::cos(phi), z, r * std::sin(phi)})));
    }
  return mean / (double(nz) * nphi);
}

}  // namespace sgtest
