// Test helpers for the heterogeneous media (medium/tracking.h): small instances of each plugin and a
// brute-force optical depth (a fine midpoint quadrature in double precision, independent of the
// media's own quadrature and tracking).
#pragma once

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/params.h"
#include "core/rng.h"
#include "medium/medium.h"
#include "medium/tracking.h"

namespace sgtest {

/// A ground fog 300 m around the origin, visibility 150 m on the ground, 4 m scale height.
inline std::shared_ptr<sg::Medium> small_ground_fog(double coverage = 0.6) {
  sg::ParamSet p;
  p.set("visibility", 150.0);
  p.set("scale_height", 4.0);
  p.set("extent", 300.0);
  p.set("feature_size", 40.0);
  p.set("feature_height", 6.0);
  p.set("coverage", coverage);
  p.set("seed", int64_t(3));
  p.set("majorant_cells", std::vector<double>{32, 8, 32});
  return sg::create_medium("ground_fog", p, "medium");
}

/// A cloud layer 100..200 m, 400 m around the origin, visibility 60 m inside.
inline std::shared_ptr<sg::Medium> small_clouds() {
  sg::ParamSet p;
  p.set("visibility", 60.0);
  p.set("bottom", 100.0);
  p.set("top", 200.0);
  p.set("extent", 400.0);
  p.set("feature_size", 80.0);
  p.set("feature_height", 60.0);
  p.set("coverage", 0.5);
  p.set("seed", int64_t(5));
  p.set("majorant_cells", std::vector<double>{32, 8, 32});
  return sg::create_medium("clouds", p, "medium");
}

/// A 12 x 10 x 8 grid over [-5, 5] x [0, 6] x [-4, 4] of random values, a quarter of them 0 and a
/// block of zeros (empty space), visibility 4 m at density 1.
inline std::shared_ptr<sg::Medium> small_grid() {
  sg::ParamSet p;
  std::vector<double> v(12 * 10 * 8);
  sg::Pcg32 rng(77);
  for (size_t k = 0; k < v.size(); ++k) {
    const size_t x = k % 12, y = (k / 12) % 10;
    v[k] = (rng.next_float() < 0.25f || (x < 4 && y < 4)) ? 0.0 : 1.5 * rng.next_float();
  }
  p.set("data", v);
  p.set("resolution", std::vector<double>{12, 10, 8});
  p.set("bounds_min", std::vector<double>{-5, 0, -4});
  p.set("bounds_max", std::vector<double>{5, 6, 4});
  p.set("visibility", 4.0);
  p.set("majorant_cells", std::vector<double>{4, 3, 3});
  return sg::create_medium("grid", p, "medium");
}

inline const sg::TrackedMedium& tracked(const sg::Medium& m) { return dynamic_cast<const sg::TrackedMedium&>(m); }

/// Optical depth of the ray o + t d over [0, t_max) (t in units of |d|) by `steps` midpoint steps
/// over the part inside the medium's box, in double precision.
inline double brute_optical_depth(const sg::TrackedMedium& m, const sg::Vec3f& o, const sg::Vec3f& d, double t_max,
                                  int steps = 20000) {
  const sg::Box3& box = m.majorants().box();
  double lo = 0.0, hi = t_max;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.f) {
      if (o[a] < box.lo[a] || o[a] > box.hi[a]) return 0.0;
      continue;
    }
    double ta = (double(box.lo[a]) - o[a]) / d[a], tb = (double(box.hi[a]) - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    lo = std::max(lo, ta);
    hi = std::min(hi, tb);
  }
  if (!(lo < hi)) return 0.0;
  const double h = (hi - lo) / steps, len = std::sqrt(double(sg::dot(d, d)));
  double sum = 0.0;
  for (int i = 0; i < steps; ++i) {
    const double t = lo + (i + 0.5) * h;
    sum += m.density(o + d * float(t));
  }
  return m.sigma() * sum * h * len;
}

/// A MediumRng whose key comes from a PCG32.
inline sg::MediumRng stream(sg::Pcg32& rng) {
  return sg::MediumRng((uint64_t(rng.next_u32()) << 32) | rng.next_u32());
}

}  // namespace sgtest
