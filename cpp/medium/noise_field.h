// What the noise media (ground_fog, clouds) share: their noise field -- normalized fBm of Perlin
// noise over space stretched to the features' size and drifted by the wind -- with the parameters
// that describe it, and the coverage mask that turns it into a share of space filled.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/noise.h"
#include "core/plugin.h"

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

/// The noise field: n(p) = fbm(((p - wind) / (feature_size, feature_height, feature_size))).
class NoiseField {
 public:
  /// From the parameters of noise_field_params.
  explicit NoiseField(const Params& params)
      : m_noise(uint64_t(params.get_int("seed"))),
        m_fractal(fractal_params(params)),
        m_wind(params.get_vec3("wind")),
        m_inv_scale(1.f / params.get_float("feature_size"), 1.f / params.get_float("feature_height"),
                    1.f / params.get_float("feature_size")),
        m_finest(std::min(params.get_float("feature_height"), params.get_float("feature_size")) /
                 std::pow(FractalParams().lacunarity, float(params.get_int("octaves") - 1))) {}

  const Fractal& fractal() const { return m_fractal; }
  float operator()(const Vec3f& p) const { return fbm(m_noise, NoiseKind::Perlin, point(p), m_fractal); }
  /// Conservative bounds of the field over the box [lo, hi] (fbm_range).
  void range(const Vec3f& lo, const Vec3f& hi, float* n_lo, float* n_hi) const {
    fbm_range(m_noise, point(lo), point(hi), m_fractal, n_lo, n_hi);
  }
  /// The labels' quadrature step: a quarter of the finest octave's lattice spacing (vertically,
  /// the smallest), at least `floor` metres.
  float quadrature_step(float floor) const { return std::max(0.25f * m_finest, floor); }

 private:
  static FractalParams fractal_params(const Params& params) {
    FractalParams fp;
    fp.octaves = int(params.get_int("octaves"));
    return fp;
  }
  Vec3f point(const Vec3f& p) const {
    const Vec3f q = p - m_wind;
    return Vec3f(q.x * m_inv_scale.x, q.y * m_inv_scale.y, q.z * m_inv_scale.z);
  }

  NoiseBasis m_noise;
  Fractal m_fractal;
  Vec3f m_wind;
  Vec3f m_inv_scale;
  float m_finest;
};

/// The noise media's parameters of their field and extent (declared here once for both, with each
/// medium's defaults and the name of its features): feature_size, feature_height, octaves, seed,
/// wind, extent, majorant_cells.
inline std::vector<ParamDecl> noise_field_params(const std::string& features, double feature_size,
                                                 double feature_height, int octaves, double extent) {
  return {param::real("feature_size", feature_size, "horizontal size in metres of the " + features +
                                                        " (the noise's coarsest lattice spacing)")
              .above(0),
          param::real("feature_height", feature_height, "vertical size in metres of the " + features + "' noise")
              .above(0),
          param::integer("octaves", octaves, "octaves of the fBm noise (detail down to feature_size / "
                                             "2^(octaves-1))")
              .in(1, 10),
          param::integer("seed", 0, "seed of the noise (another seed, other " + features + ")").at_least(0),
          param::vec3("wind", Vec3f(0.f), "offset in metres of the noise field: the " + features +
                                              " drift with it (wind velocity x time)"),
          param::real("extent", extent, "half-width in metres of the square around the origin (x and z) the "
                                        "medium fills")
              .above(0),
          param::vec3("majorant_cells", Vec3f(64.f, 16.f, 64.f), "cells of the majorant grid along x, y, z "
                                                                 "(whole numbers)")
              .in(1, 512)};
}

}  // namespace sg
