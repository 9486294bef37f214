// The coverage mask of the noise media (ground_fog, clouds): which share of space a density built
// from normalized fBm noise fills, and how sharp its edges are.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/noise.h"

namespace sg {

/// The noise mask of the noise media: m(n) = smoothstep(threshold - width, threshold + width, n)
/// of normalized fBm n (monotonic in n, so bounds of n bound it); coverage 1: 1 everywhere.
struct CoverageMask {
  float lo = 0.f, hi = 0.f;
  bool full = false;
  CoverageMask() = default;
  /// NOTE: normalized fBm is close to normal with standard deviation sigma_f = s sqrt(sum w_i^2) /
  /// sum w_i, s = 0.277 the Perlin basis' (mean |noise| 0.221 x sqrt(pi / 2), core/noise.cpp's
  /// measured mean); the threshold puts about `coverage` of space above it via the logistic
  /// approximation of the normal quantile, Phi^-1(p) ~ ln(p / (1 - p)) / 1.702 (Bowling et al.
  /// 2009, "A logistic approximation to the cumulative normal distribution").
  CoverageMask(const Fractal& f, float coverage, float contrast) {
    full = coverage >= 1.f;
    double w2 = 0.0, w = 0.0;
    for (int i = 0; i < f.octaves(); ++i) {
      w2 += double(f.weight(i)) * f.weight(i);
      w += f.weight(i);
    }
    sigma_f = float(0.277 * std::sqrt(w2) / w);
    const float c = std::clamp(coverage, 1e-4f, 1.f - 1e-4f);
    const float threshold = -sigma_f * std::log(c / (1.f - c)) / 1.702f;
    const float width = sigma_f / contrast;
    lo = threshold - width;
    hi = threshold + width;
  }
  /// The standard deviation of the normalized fBm (see the constructor).
  float sigma_f = 0.f;
  float operator()(float n) const { return full ? 1.f : smoothstep(lo, hi, n); }
};

}  // namespace sg
