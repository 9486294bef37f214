// Deterministic random numbers.
//
// Every random number used while rendering is a pure function of
// (seed, pixel index, sample index, dimension): `PixelSampler` hashes that tuple.
// No state is shared between pixels or threads, so images are bit-identical for
// any thread count or tile order.
#pragma once

#include <algorithm>
#include <cstdint>
#if defined(__GFNI__) && defined(__SSE2__)
#include <immintrin.h>
#endif

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

inline uint32_t reverse_bits32(uint32_t v) {
#if defined(__GFNI__) && defined(__SSE2__)
  // NOTE: GF2P8AFFINEQB with the matrix 0x8040201008040201 reverses the bits of every byte
  // (Intel SDM, "Galois Field New Instructions"); a byte swap completes the reversal.
  __m128i x = _mm_cvtsi32_si128(int(v));
  x = _mm_gf2p8affine_epi64_epi8(x, _mm_set1_epi64x(0x8040201008040201ll), 0);
  return __builtin_bswap32(uint32_t(_mm_cvtsi128_si32(x)));
#else
  v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
  v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
  v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
  v = ((v >> 8) & 0x00ff00ffu) | ((v & 0x00ff00ffu) << 8);
  return (v >> 16) | (v << 16);
#endif
}

/// Second dimension of the Sobol sequence (primitive polynomial x + 1): direction numbers
/// v_1 = 2^31, v_{k+1} = v_k ^ (v_k >> 1). (The first dimension is the van der Corput
/// sequence, reverse_bits32(i).)
inline uint32_t sobol_dim1(uint32_t i) {
  uint32_t x = 0, v = 0x80000000u;
  for (; i; i >>= 1, v ^= v >> 1)
    if (i & 1u) x ^= v;
  return x;
}

/// reverse_bits32(sobol_dim1(i)), computed directly with bit-reversed direction numbers.
/// NOTE: the bit-reversed direction numbers of this dimension are the rows of Pascal's
/// triangle mod 2: bit j of w_k is binom(k, j) mod 2, which by Lucas' theorem is 1 iff the
/// bits of j are a subset of those of k. So bit j of the result is the xor of the index
/// bits k that are supersets of j: a superset (zeta) transform over the 5 bit positions of
/// j, done with five masked shift-xor steps instead of a loop over the index bits.
inline uint32_t sobol_dim1_reversed(uint32_t i) {
  i ^= (i >> 1) & 0x55555555u;
  i ^= (i >> 2) & 0x33333333u;
  i ^= (i >> 4) & 0x0f0f0f0fu;
  i ^= (i >> 8) & 0x00ff00ffu;
  i ^= (i >> 16) & 0x0000ffffu;
  return i;
}

/// The hash of Burley 2020 applied to bit-reversed input (see owen_scramble).
inline uint32_t laine_karras(uint32_t x, uint32_t seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}

/// Nested uniform (Owen) scrambling of a 32-bit fixed-point value.
/// NOTE: Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4): the
/// Laine-Karras-style hash applied to the bit-reversed value (its Listing 2 constants).
inline uint32_t owen_scramble(uint32_t x, uint32_t seed) {
  x = reverse_bits32(x);
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return reverse_bits32(x);
}

/// The smallest 2^b - 1 >= n - 1 (the bit mask permute_index walks in).
inline uint32_t permutation_mask(uint32_t n) {
  uint32_t mask = n > 1 ? n - 1 : 0;
  mask |= mask >> 1;
  mask |= mask >> 2;
  mask |= mask >> 4;
  mask |= mask >> 8;
  mask |= mask >> 16;
  return mask;
}

/// permute_index with the mask of n precomputed by permutation_mask(n).
/// NOTE: Kensler 2013, "Correlated Multi-Jittered Sampling", Listing "permute": a keyed hash
/// that is a bijection on the next power of two, cycle-walked into [0, n). Its many rounds
/// matter: a weaker family (xor with the key and two multiply-xorshift rounds) gave, for n <= 32,
/// permutations so close to an index xor that different pairs of a padded Sobol sampler saw the
/// same net order -- a digital shift, which Owen scrambling absorbs -- and their dimensions came
/// out dependent: 1-4 % regional bias in 64-spp Cornell-box renders split into two 32-sample
/// halves.
inline uint32_t permute_index_masked(uint32_t i, uint32_t n, uint32_t mask, uint32_t key) {
  if (n <= 1) return 0;
  const uint32_t w = mask, p = key;
  do {
    i ^= p;
    i *= 0xe170893du;
    i ^= p >> 16;
    i ^= (i & w) >> 4;
    i ^= p >> 8;
    i *= 0x0929eb3fu;
    i ^= p >> 23;
    i ^= (i & w) >> 1;
    i *= 1u | p >> 27;
    i *= 0x6935fa69u;
    i ^= (i & w) >> 11;
    i *= 0x74dcb303u;
    i ^= (i & w) >> 2;
    i *= 0x9e501cc3u;
    i ^= (i & w) >> 2;
    i *= 0xc860a3dfu;
    i &= w;
    i ^= i >> 5;
  } while (i >= n);
  return (i + p) % n;
}

/// A pseudo-random permutation of [0, n) evaluated at i, keyed by `key` (see
/// permute_index_masked).
inline uint32_t permute_index(uint32_t i, uint32_t n, uint32_t key) {
  return permute_index_masked(i, n, permutation_mask(n), key);
}

/// Sampler for one (seed, pixel, sample) triple of a pixel rendered with `spp` samples.
///
/// Dimensions come in pairs (2k, 2k + 1); each pair is a 2D Owen-scrambled Sobol point set
/// over the pixel's samples, with the sample order shuffled per pixel and pair ("padded"
/// Sobol, as in pbrt-v4's PaddedSobolSampler). So every pair is stratified over the
/// pixel's samples (a (0, 2)-net for powers of two) while different pairs are
/// decorrelated. Everything is a pure function of (seed, pixel, sample, dimension, spp):
/// images are bit-identical for any thread count or tile order.
///
/// NOTE: the even- and the odd-numbered samples are two independent randomizations, each
/// its own padded Sobol set over its half of the samples (half(): 0 or 1; keys differ): the
/// film's two half-sample images are then independent estimates, so their difference
/// measures the error of their mean (randomized QMC error estimation, Owen 1997; one net
/// split in two would not: its halves are complementary strata -- for 16 spp or fewer the
/// even samples covered one half of the pixel, the odd ones the other).
class PixelSampler {
 public:
  PixelSampler() : m_key(0), m_sample(0), m_spp(1), m_mask(0) {}
  /// `block` (adaptive sampling's rounds; 0: all spp samples are one block): samples
  /// [b block, (b + 1) block) are randomized on their own, as if the pixel had only those, so
  /// that a pixel can stop after any whole block. An even block keeps the halves' parity.
  PixelSampler(uint64_t seed, uint64_t pixel_index, uint32_t sample_index, uint32_t spp = 1, uint32_t block = 0) {
    spp = spp ? spp : 1;
    uint64_t block_key = 0;
    if (block && block < spp) {
      const uint32_t b = sample_index / block;
      sample_index -= b * block;
      spp = std::min(block, spp - b * block);
      block_key = b ? mix64(uint64_t(b) * 0xd1b54a32d192ed03ull) : 0ull;
    }
    m_half = spp >= 2 ? (sample_index & 1u) : 0u;
    m_key = mix64(mix64(seed) ^ pixel_index) ^ (m_half ? 0xa0761d6478bd642full : 0ull) ^ block_key;
    m_sample = spp >= 2 ? sample_index >> 1 : sample_index;
    m_spp = spp >= 2 ? (m_half ? spp / 2 : (spp + 1) / 2) : spp;
    m_mask = permutation_mask(m_spp);
  }

  /// Which of the two independent halves of the pixel's samples this sample belongs to.
  uint32_t half() const { return m_half; }

  /// Value of dimension `dim` in [0, 1), independent of the order of calls.
  float get(uint32_t dim) const {
    Vec2f p = get_2d(dim & ~1u);
    return (dim & 1u) ? p.y : p.x;
  }

  /// An unstratified value for dimension `dim` (a plain hash; for decisions such as
  /// Russian roulette that gain nothing from stratification and are on the hot path).
  float get_independent(uint32_t dim) const { return bits_to_unit_float(uint32_t(independent_key(dim) >> 32)); }

  /// The 64-bit hash behind get_independent(dim) (its value is the high 24 bits): a key for a
  /// stream of further numbers drawn from one dimension (MediumRng, medium/medium.h).
  uint64_t independent_key(uint32_t dim) const {
    return mix64(m_key ^ (uint64_t(m_sample) << 32) ^ (0x51ed27u + dim));
  }

  /// Dimensions (dim, dim + 1) for an even `dim`: one 2D point of the pair's net.
  Vec2f get_2d(uint32_t dim) const { return get_2d_keyed(pair_key(dim)); }

  /// The per-pixel key of the pair holding `dim`: the same for every sample of the pixel,
  /// so callers that draw the same pair for many samples can compute it once.
  uint64_t pair_key(uint32_t dim) const { return mix64(m_key ^ (uint64_t(dim >> 1) * 0x9e3779b97f4a7c15ull)); }

  /// get_2d with the pair's key from pair_key() of any sampler of the same (seed, pixel).
  /// NOTE: owen_scramble(reverse(i)) = reverse(laine_karras(i)), and likewise with the
  /// bit-reversed Sobol direction numbers, so each coordinate costs one bit reversal.
  /// NOTE: the two coordinates' scrambles must be independent (Owen 1995: one random
  /// permutation tree per dimension). They once came from one 32-bit seed (y's was x's xor a
  /// constant): over all seeds a sample's point then lay on a curve -- y a function of x --
  /// instead of filling the square, and renders at 16-32 spp were biased by up to 1 % of a
  /// 32 x 32 block's radiance in the Cornell box, the same for every seed
  /// (tests/python/test_sampler_bias.py).
  Vec2f get_2d_keyed(uint64_t h) const { return get_2d_keyed(PairSeeds(h)); }

  /// The three 32-bit seeds get_2d_keyed derives from a pair key: the sample order's
  /// permutation and the two coordinates' scrambles. Lanes that share a key share these.
  struct PairSeeds {
    uint32_t permutation = 0, x = 0, y = 0;
    PairSeeds() = default;
    explicit PairSeeds(uint64_t h) : permutation(uint32_t(h)), x(uint32_t(h >> 32)), y(uint32_t(mix64(h) >> 32)) {}
  };
  /// get_2d_keyed with the seeds of the key precomputed (the same values).
  Vec2f get_2d_keyed(const PairSeeds& k) const {
    uint32_t index = permute_index_masked(m_sample, m_spp, m_mask, k.permutation);
    uint32_t x = reverse_bits32(laine_karras(index, k.x));
    uint32_t y = reverse_bits32(laine_karras(sobol_dim1_reversed(index), k.y));
    return {bits_to_unit_float(x), bits_to_unit_float(y)};
  }

 private:
  uint64_t m_key;
  uint32_t m_sample, m_spp, m_mask, m_half = 0;
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
