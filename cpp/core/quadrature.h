// Numerical quadrature used to tabulate BSDF albedos at material creation.
#pragma once

#include <array>
#include <cmath>

namespace sg {

/// Gauss-Legendre nodes and weights on [-1, 1].
/// NOTE: Newton iteration on the Legendre recurrence (Numerical Recipes, 3rd ed., sec. 4.6,
/// routine gauleg).
template <int N>
struct GaussLegendre {
  std::array<double, N> x{}, w{};
  GaussLegendre() {
    for (int i = 0; i < N; ++i) {
      double z = std::cos(3.14159265358979323846 * (i + 0.75) / (N + 0.5)), dp = 1.0;
      for (int it = 0; it < 100; ++it) {
        double p1 = 1.0, p2 = 0.0;
        for (int j = 0; j < N; ++j) {
          double p3 = p2;
          p2 = p1;
          p1 = ((2.0 * j + 1.0) * z * p2 - j * p3) / (j + 1.0);
        }
        dp = N * (z * p1 - p2) / (z * z - 1.0);
        double z_old = z;
        z = z_old - p1 / dp;
        if (std::fabs(z - z_old) < 1e-15) break;
      }
      x[size_t(i)] = z;
      w[size_t(i)] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
  }
};

}  // namespace sg
