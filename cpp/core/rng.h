// Deterministic random numbers.
//
// Every random number used while rendering is a pure function of
// (seed, pixel index, sample index, dimension): `PixelSampler` hashes that tuple.
// No state is shared between pixels or threads, so images are bit-identical for
// any thread count or tile order.
#pragma once

#include <cstdint>

#include "core/math.h"

namespace sg {

/// NOTE: SplitMix64 finalizer (Steele, Lea, Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014); a bijective 64-bit mixer with full avalanche.
inline uint64_t mix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/// Maps the high 24 bits of a 32-bit integer to a float in [0, 1).
inline float bits_to_unit_float(uint32_t bits) { return float(bits >> 8) * 0x1p-24f; }

/// Counter-based sampler for one (seed, pixel, sample) triple.
class PixelSampler {
 public:
  PixelSampler() : m_key(0) {}
  PixelSampler(uint64_t seed, uint64_t pixel_index, uint32_t sample_index)
      : m_key(mix64(mix64(mix64(seed) ^ pixel_index) ^ sample_index)) {}

  /// Value of dimension `dim`, independent of the order of calls.
  float get(uint32_t dim) const { return bits_to_unit_float(uint32_t(mix64(m_key ^ (uint64_t(dim) << 32)) >> 32)); }
  float next_1d() { return get(m_dim++); }
  Vec2f next_2d() {
    float a = get(m_dim++);
    return {a, get(m_dim++)};
  }
  /// Jumps to a fixed dimension, so that each path vertex uses a stable block of dimensions.
  void set_dimension(uint32_t dim) { m_dim = dim; }

 private:
  uint64_t m_key;
  uint32_t m_dim = 0;
};

/// Small sequential generator (PCG32, O'Neill 2014) for tests and scene-building code.
/// Always constructed from an explicit seed; there is no global generator.
class Pcg32 {
 public:
  explicit Pcg32(uint64_t seed, uint64_t stream = 0x14057b7ef767814full) {
    m_inc = (stream << 1u) | 1u;
    next_u32();
    m_state += seed;
    next_u32();
  }
  uint32_t next_u32() {
    uint64_t old = m_state;
    m_state = old * 6364136223846793005ull + m_inc;
    uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
  }
  float next_float() { return bits_to_unit_float(next_u32()); }
  Vec2f next_2d() {
    float a = next_float();
    return {a, next_float()};
  }

 private:
  uint64_t m_state = 0x853c49e6748fea9bull, m_inc;
};

}  // namespace sg
