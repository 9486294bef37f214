// PixelSampler (core/rng.h): padded, Owen-scrambled Sobol sample values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "chi2.h"
#include "core/rng.h"

using namespace sg;

TEST(rng, permute_index_is_a_permutation) {
  for (uint32_t n : {1u, 2u, 3u, 7u, 16u, 33u, 1000u})
    for (uint32_t key : {0u, 1u, 0xdeadbeefu}) {
      std::set<uint32_t> seen;
      for (uint32_t i = 0; i < n; ++i) {
        uint32_t p = permute_index(i, n, key);
        ASSERT_LT(p, n);
        seen.insert(p);
      }
      EXPECT_EQ(seen.size(), n) << "n=" << n << " key=" << key;
    }
}

TEST(rng, sobol_dim1_first_points) {
  // Second Sobol dimension (direction numbers 1/2, 3/4, 5/8, ...), natural order.
  const double expect[] = {0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875};
  for (uint32_t i = 0; i < 8; ++i) EXPECT_DOUBLE_EQ(sobol_dim1(i) * 0x1p-32, expect[i]) << i;
}

// The fast bit tricks (GFNI byte reversal, superset transform) against their definitions.
TEST(rng, bit_reversal_and_reversed_sobol_match_their_definitions) {
  auto naive_reverse = [](uint32_t v) {
    uint32_t r = 0;
    for (int b = 0; b < 32; ++b) r |= ((v >> b) & 1u) << (31 - b);
    return r;
  };
  Pcg32 rng(5);
  for (uint32_t k = 0; k < 100000; ++k) {
    uint32_t i = k < 4096 ? k : rng.next_u32();
    ASSERT_EQ(reverse_bits32(i), naive_reverse(i)) << i;
    ASSERT_EQ(sobol_dim1_reversed(i), naive_reverse(sobol_dim1(i))) << i;
  }
}

// Every pair of dimensions of a pixel's spp samples is a (0, 2)-net in base 2 for
// power-of-two spp: each elementary interval of area 1/spp holds exactly one point.
// The even- and the odd-numbered samples are two independent randomizations (the film's
// half-sample images must be independent estimates): each half's points of every pair form a
// (0, 2)-net over that half, and the halves differ.
TEST(rng, each_dimension_pair_is_stratified_over_each_half_of_the_pixel_samples) {
  const uint32_t spp = 128, half_n = spp / 2;
  for (uint64_t pixel : {0ull, 17ull, 123456ull})
    for (uint32_t pair = 0; pair < 6; ++pair) {
      std::vector<std::pair<float, float>> pts[2];
      for (uint32_t s = 0; s < spp; ++s) {
        PixelSampler ps(7, pixel, s, spp);
        EXPECT_EQ(ps.half(), s & 1u);
        pts[s & 1u].push_back({ps.get(2 * pair), ps.get(2 * pair + 1)});
      }
      for (int h = 0; h < 2; ++h)
        for (uint32_t bx = 1; bx <= half_n; bx *= 2) {
          uint32_t by = half_n / bx;
          std::vector<int> cells(half_n, 0);
          for (auto& p : pts[h]) {
            uint32_t cx = std::min(bx - 1, uint32_t(p.first * bx)), cy = std::min(by - 1, uint32_t(p.second * by));
            ++cells[cy * bx + cx];
          }
          EXPECT_TRUE(std::all_of(cells.begin(), cells.end(), [](int c) { return c == 1; }))
              << "pixel " << pixel << " pair " << pair << " half " << h << " intervals " << bx << "x" << by;
        }
      // Independent scrambles: the halves' point sets are not the same set.
      auto a = pts[0], b = pts[1];
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      EXPECT_NE(a, b);
    }
}

// With 2 to 16 samples, the halves are not complementary strata: neither half keeps to one
// side of the pixel in the first dimension (what a single net split by parity did).
TEST(rng, halves_are_not_complementary_strata) {
  int both_sides = 0, cases = 0;
  for (uint32_t spp : {4u, 8u, 16u})
    for (uint64_t pixel = 0; pixel < 200; ++pixel) {
      int low[2] = {0, 0}, high[2] = {0, 0};
      for (uint32_t s = 0; s < spp; ++s) {
        PixelSampler ps(3, pixel, s, spp);
        (ps.get(0) < 0.5f ? low : high)[s & 1u]++;
      }
      both_sides += (low[0] > 0 && high[0] > 0) + (low[1] > 0 && high[1] > 0);
      cases += 2;
    }
  // Each half of 2-8 stratified points spans both sides of the pixel (a net of >= 2 points).
  EXPECT_EQ(both_sides, cases);
}

// Across pixels, every dimension is uniform (chi-square, 10^6 values) and dimensions of
// different pairs are uncorrelated.
TEST(rng, values_are_uniform_and_pairs_decorrelated) {
  const uint32_t spp = 16, bins = 100;
  for (uint32_t dim : {0u, 1u, 5u, 12u, 33u}) {
    std::vector<double> obs(bins, 0.0), exp(bins, 0.0);
    double corr = 0.0, n = 0.0;
    for (uint64_t pixel = 0; pixel < 62500; ++pixel)
      for (uint32_t s = 0; s < spp; ++s) {
        PixelSampler ps(3, pixel, s, spp);
        float u = ps.get(dim);
        ASSERT_GE(u, 0.f);
        ASSERT_LT(u, 1.f);
        obs[std::min(bins - 1, uint32_t(u * bins))] += 1.0;
        corr += (u - 0.5) * (ps.get(dim + 2) - 0.5);
        n += 1.0;
      }
    for (auto& e : exp) e = n / bins;
    sgtest::Chi2Result res = sgtest::chi2_test(obs, exp);
    EXPECT_TRUE(res.ok) << "dimension " << dim << ": " << res.message;
    // Correlation coefficient of uniform variables: cov / (1/12); |r| < 5 sigma.
    double r = (corr / n) * 12.0;
    EXPECT_LT(std::fabs(r), 5.0 / std::sqrt(n)) << "dimensions " << dim << ", " << dim + 2;
  }
}

TEST(rng, deterministic_and_seed_dependent) {
  PixelSampler a(1, 99, 5, 32), b(1, 99, 5, 32), c(2, 99, 5, 32);
  int differ = 0;
  for (uint32_t d = 0; d < 40; ++d) {
    EXPECT_EQ(a.get(d), b.get(d));
    differ += a.get(d) != c.get(d);
  }
  EXPECT_GT(differ, 30);
}

// Each sample's 2D point, over seeds (pixels), is uniform on the square: the two coordinates'
// Owen scrambles are independent. (With y's scramble seed derived from x's, a sample's point
// lay on a curve -- y a function of x -- and low-spp renders were biased the same way for
// every seed.) Chi-square over an 8 x 8 grid of the points of fixed sample indices.
TEST(rng, each_samples_2d_point_is_uniform_over_seeds) {
  for (uint32_t spp : {1u, 4u, 16u, 32u})
    for (uint32_t sample : {0u, 1u, 5u})
      for (uint32_t dim : {0u, 2u, 8u}) {
        if (sample >= spp) continue;
        std::vector<double> obs(64, 0.0), exp(64, 0.0);
        const int n = 64000;
        for (int p = 0; p < n; ++p) {
          PixelSampler ps(12345, uint64_t(p), sample, spp);
          Vec2f v = ps.get_2d(dim);
          obs[std::min(7, int(v.y * 8)) * 8 + std::min(7, int(v.x * 8))] += 1.0;
        }
        for (double& e : exp) e = n / 64.0;
        sgtest::Chi2Result r = sgtest::chi2_test(obs, exp);
        EXPECT_TRUE(r.ok) << "spp " << spp << " sample " << sample << " dim " << dim << ": " << r.message;
      }
}

// Adaptive sampling's blocks: with `block` samples per round, each block of samples is a
// padded Sobol set of its own (every half of every block stratified like a pixel with only
// those samples), block 0 is the same as without blocks, and later blocks are other
// randomizations (not the first block's points again).
TEST(rng, blocks_are_stratified_on_their_own) {
  const uint32_t spp = 96, block = 32, half_n = block / 2;
  for (uint64_t pixel : {3ull, 4242ull})
    for (uint32_t pair = 0; pair < 4; ++pair) {
      std::vector<std::pair<float, float>> first;
      for (uint32_t b = 0; b < spp / block; ++b) {
        std::vector<std::pair<float, float>> pts[2];
        for (uint32_t i = 0; i < block; ++i) {
          const uint32_t s = b * block + i;
          PixelSampler ps(11, pixel, s, spp, block);
          EXPECT_EQ(ps.half(), s & 1u);
          pts[s & 1u].push_back({ps.get(2 * pair), ps.get(2 * pair + 1)});
          if (b == 0) {
            PixelSampler plain(11, pixel, i, block);  // a pixel of `block` samples
            EXPECT_EQ(ps.get(2 * pair), plain.get(2 * pair));
            first.push_back(pts[s & 1u].back());
          }
        }
        for (int h = 0; h < 2; ++h)
          for (uint32_t bx = 1; bx <= half_n; bx *= 2) {
            const uint32_t by = half_n / bx;
            std::vector<int> cells(half_n, 0);
            for (auto& p : pts[h])
              ++cells[std::min(by - 1, uint32_t(p.second * by)) * bx + std::min(bx - 1, uint32_t(p.first * bx))];
            EXPECT_TRUE(std::all_of(cells.begin(), cells.end(), [](int c) { return c == 1; }))
                << "block " << b << " half " << h << " intervals " << bx << "x" << by;
          }
        if (b > 0) {
          std::vector<std::pair<float, float>> all(pts[0]);
          all.insert(all.end(), pts[1].begin(), pts[1].end());
          std::sort(all.begin(), all.end());
          std::vector<std::pair<float, float>> f(first);
          std::sort(f.begin(), f.end());
          EXPECT_NE(all, f) << "block " << b << " repeats block 0";
        }
      }
    }
}
