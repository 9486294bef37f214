// Procedural noise: Perlin gradient noise (2D/3D), value noise, fractal sums (fBm,
// turbulence) with footprint band-limiting, cellular (Worley) noise; colour ramps.
// Deterministic: every function is a pure function of its inputs and a seed.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/math.h"

namespace sg {

/// Lattice noise with a seeded permutation (one table per seed).
class NoiseBasis {
 public:
  explicit NoiseBasis(uint64_t seed = 0);
  /// Improved Perlin gradient noise in [-1, 1] (Perlin 2002, "Improving Noise"), 3D.
  float perlin(const Vec3f& p) const;
  /// perlin() and its gradient (analytic, without the final clamp to [-1, 1]).
  float perlin_grad(const Vec3f& p, Vec3f* grad) const;
  /// Conservative bounds [*mn, *mx] of perlin() over the box [lo, hi] (exact up to rounding for a
  /// box inside one lattice cell, looser across cells); [-1, 1] when the box spans more than
  /// `max_cells` lattice cells.
  void perlin_range(const Vec3f& lo, const Vec3f& hi, float* mn, float* mx, int max_cells = 64) const;
  /// 2D Perlin noise in [-1, 1] (gradients on the unit circle).
  float perlin2(float x, float y) const;
  /// Value noise in [-1, 1]: random lattice values, quintic interpolation.
  float value(const Vec3f& p) const;
  /// A hash of a lattice cell (for cellular noise and per-cell randomness), in [0, 2^32).
  uint32_t hash(int x, int y, int z) const { return hash_cell(m_hash_seed, x, y, z); }
  uint32_t hash_seed() const { return m_hash_seed; }
  /// The hash behind hash(): 32-bit integer arithmetic only, so that it vectorizes.
  /// NOTE: the spatial hash of Teschner et al. 2003 ("Optimized Spatial Hashing for
  /// Collision Detection of Deformable Objects": x p1 xor y p2 xor z p3) with odd
  /// multipliers, then MurmurHash3's fmix32 finalizer (Appleby) for full avalanche.
  static uint32_t hash_cell(uint32_t seed, int x, int y, int z) {
    uint32_t h = seed ^ (uint32_t(x) * 0x8da6b343u) ^ (uint32_t(y) * 0xd8163841u) ^ (uint32_t(z) * 0xcb1ab31fu);
    h ^= h >> 16;
    h *= 0x85ebca6bu;
    h ^= h >> 13;
    h *= 0xc2b2ae35u;
    return h ^ (h >> 16);
  }

 private:
  std::array<uint8_t, 512> m_perm;
  uint32_t m_hash_seed;
};

enum class NoiseKind { Perlin, Value };

/// Parameters of a fractal sum, the seed's equations (4-5)-(4-7):
/// f_s(x) = sum_i w_i f_noise(s_i x), s_i = lacunarity * s_{i-1}, w_i = w_{i-1} * lacunarity^-H,
/// s_0 = w_0 = 1.
struct FractalParams {
  int octaves = 5;
  float lacunarity = 2.f;
  float H = 1.f;  ///< spectral exponent: w_i = lacunarity^(-H i)
  /// Divide by sum_i w_i, so fBm stays in [-1, 1] and turbulence in [0, 1].
  bool normalize = true;
  /// w_i / w_{i-1} = lacunarity^-H.
  float weight_ratio() const { return std::pow(lacunarity, -H); }
};

/// A fractal sum's per-octave constants (frequency s_i, weight w_i, the normalization),
/// computed once from FractalParams (a texture keeps one; the functions below also accept
/// FractalParams, converted per call).
class Fractal {
 public:
  static constexpr int k_max_octaves = 16;
  Fractal(const FractalParams& f);  // NOLINT: implicit, so fbm(b, kind, p, params) reads naturally
  int octaves() const { return m_octaves; }
  float frequency(int i) const { return m_freq[i]; }
  float weight(int i) const { return m_weight[i]; }
  /// 1 / sum_i w_i when normalized, else 1.
  float norm() const { return m_norm; }

 private:
  int m_octaves;
  float m_freq[k_max_octaves], m_weight[k_max_octaves];
  float m_norm;
};

/// Fractal Brownian motion sum_i w_i noise(s_i p).
/// `footprint` is the width of the filter footprint in the units of p (0 = none): octaves
/// above the Nyquist rate of the footprint (period < 2 footprints) are faded out, gone at a
/// period of one footprint (replaced by their mean, 0), so the sum does not alias.
float fbm(const NoiseBasis& b, NoiseKind kind, const Vec3f& p, const Fractal& f, float footprint = 0.f);
/// Turbulence sum_i w_i |noise(s_i p)|, band-limited like fbm (faded octaves are replaced
/// by the mean of |noise|).
float turbulence(const NoiseBasis& b, NoiseKind kind, const Vec3f& p, const Fractal& f, float footprint = 0.f);
/// fbm / turbulence (Perlin basis) with their analytic gradient in the units of p.
float fbm_grad(const NoiseBasis& b, const Vec3f& p, const Fractal& f, float footprint, Vec3f* grad);
float turbulence_grad(const NoiseBasis& b, const Vec3f& p, const Fractal& f, float footprint, Vec3f* grad);
/// Conservative bounds [*mn, *mx] of fbm(b, NoiseKind::Perlin, p, f) (no footprint) for p in the
/// box [lo, hi]: the sum of each octave's perlin_range (for majorants of media, medium/tracking.h).
void fbm_range(const NoiseBasis& b, const Vec3f& lo, const Vec3f& hi, const Fractal& f, float* mn, float* mx);
/// Fade weight of an octave of frequency `freq` for a footprint (1 = kept, 0 = removed).
float octave_fade(float freq, float footprint);
/// Mean of |noise| over space (used for faded turbulence octaves).
float mean_abs_noise(NoiseKind kind);

/// Cellular (Worley 1996) noise: one jittered feature point per unit cell.
struct CellularResult {
  float f1 = 0.f, f2 = 0.f;  ///< distances to the nearest and second-nearest feature points
  float edge = 0.f;          ///< distance to the nearest Voronoi cell boundary
  uint32_t cell_hash = 0;    ///< hash of the nearest feature point's cell (per-cell randomness)
};
/// `jitter` in [0, 1] scales the feature points' random offsets (0 = a regular grid).
/// The exact edge distance costs a second search over 125 cells: computed only with `edge`.
CellularResult cellular(const NoiseBasis& b, const Vec3f& p, float jitter = 1.f, bool edge = true);

/// Piecewise-linear colour map over [0, 1] ("colour maps" of the seed): stops sorted by
/// position, constant beyond the first and last stop.
class ColorRamp {
 public:
  ColorRamp() = default;
  ColorRamp(std::vector<float> positions, std::vector<Color> colors);
  Color eval(float t) const;
  bool empty() const { return m_pos.empty(); }

 private:
  std::vector<float> m_pos;
  std::vector<Color> m_col;
};

/// Hermite smoothstep of x between e0 and e1 (e0 > e1 reverses it).
inline float smoothstep(float e0, float e1, float x) {
  float t = (x - e0) / (e1 - e0);
  t = t < 0.f ? 0.f : (t > 1.f ? 1.f : t);
  return t * t * (3.f - 2.f * t);
}

}  // namespace sg
