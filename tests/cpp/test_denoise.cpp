// The denoiser (film/denoise.h) on synthetic buffers: noise on a constant is removed, a
// noise-free textured image is returned unchanged (albedo demodulation), a noisy linear ramp
// is reproduced up to the image border (first-order regression), the result does not depend
// on the number of threads, and background (+inf depth, zero normal), NaN and HDR inputs give
// finite, non-negative output.
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "core/error.h"
#include "film/denoise.h"

namespace {

/// Buffers of a synthetic render: two radiance halves and pixel-centre features.
struct Buffers {
  uint32_t w, h;
  std::vector<float> a, b, albedo, normal, depth;
  Buffers(uint32_t w_, uint32_t h_)
      : w(w_), h(h_), a(size_t(w) * h * 3), b(size_t(w) * h * 3), albedo(size_t(w) * h * 3, 0.5f),
        normal(size_t(w) * h * 3, 0.f), depth(size_t(w) * h, 2.f) {
    for (size_t i = 0; i < size_t(w) * h; ++i) normal[3 * i + 2] = 1.f;
  }
  sg::DenoiseInput input() const {
    sg::DenoiseInput in;
    in.width = w;
    in.height = h;
    in.rgb[0] = a.data();
    in.rgb[1] = b.data();
    in.albedo[0] = in.albedo[1] = albedo.data();
    in.normal[0] = in.normal[1] = normal.data();
    in.depth[0] = in.depth[1] = depth.data();
    return in;
  }
  std::vector<float> run(const sg::DenoiseSettings& s = {}) const {
    std::vector<float> out(a.size());
    sg::denoise(input(), s, out.data());
    return out;
  }
};

/// Fills the halves with `truth` plus Gaussian noise of `sigma` (per half).
template <class Truth>
void fill(Buffers& buf, float sigma, uint32_t seed, Truth truth) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, sigma);
  for (uint32_t y = 0; y < buf.h; ++y)
    for (uint32_t x = 0; x < buf.w; ++x)
      for (int c = 0; c < 3; ++c) {
        const size_t i = (size_t(y) * buf.w + x) * 3 + c;
        const float t = truth(x, y, c);
        buf.a[i] = t + noise(rng);
        buf.b[i] = t + noise(rng);
      }
}

TEST(Denoise, NoiseOnAConstantIsRemoved) {
  Buffers buf(64, 48);
  const float sigma = 0.05f;  // per half: the mean of the halves has sigma / sqrt(2) = 0.035
  fill(buf, sigma, 1, [](uint32_t, uint32_t, int) { return 0.5f; });
  const std::vector<float> out = buf.run();
  double se = 0.0, se_in = 0.0, worst = 0.0;
  for (size_t i = 0; i < out.size(); ++i) {
    se += (out[i] - 0.5) * (out[i] - 0.5);
    const double m = 0.5 * (buf.a[i] + buf.b[i]) - 0.5;
    se_in += m * m;
    worst = std::max(worst, std::abs(out[i] - 0.5));
  }
  const double rms = std::sqrt(se / out.size()), rms_in = std::sqrt(se_in / out.size());
  EXPECT_LT(rms, 0.2 * rms_in) << "rms " << rms << " input rms " << rms_in;
  EXPECT_LT(worst, 0.05) << "worst pixel (the input's is about 4 x 0.035)";
}

TEST(Denoise, NoiseFreeTextureStaysExact) {
  // A sharp albedo edge and a 2-pixel checker under constant light: the halves agree (no
  // noise), and demodulation leaves the filter a constant to filter.
  Buffers buf(48, 32);
  for (uint32_t y = 0; y < buf.h; ++y)
    for (uint32_t x = 0; x < buf.w; ++x)
      for (int c = 0; c < 3; ++c) {
        const size_t i = (size_t(y) * buf.w + x) * 3 + c;
        const float alb = x < 20 ? 0.15f + 0.1f * c : (((x / 2) + (y / 2)) % 2 ? 0.9f : 0.3f);
        buf.albedo[i] = alb;
        buf.a[i] = buf.b[i] = 0.8f * alb;
      }
  const std::vector<float> out = buf.run();
  for (size_t i = 0; i < out.size(); ++i) ASSERT_NEAR(out[i], buf.a[i], 1e-5f * buf.a[i]) << "at " << i / 3;
}

TEST(Denoise, NoisyLinearRampIsReproducedToTheBorder) {
  // Radiance 0.2 + 0.6 x / (w - 1) with noise; the normal's x component follows the same ramp.
  // A zeroth-order filter misses the border by about slope * radius / 2 (one-sided window); the
  // first-order regression does not. Averaged over 8 noise seeds.
  const uint32_t w = 64, h = 32;
  const float slope = 0.6f / float(w - 1);
  std::vector<double> mean(size_t(w) * h * 3, 0.0);
  const int seeds = 8;
  for (int s = 0; s < seeds; ++s) {
    Buffers buf(w, h);
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        const float nx = -0.5f + float(x) / float(w - 1);
        buf.normal[3 * i] = nx;
        buf.normal[3 * i + 2] = std::sqrt(1.f - nx * nx);
        buf.albedo[3 * i] = buf.albedo[3 * i + 1] = buf.albedo[3 * i + 2] = 1.f;
      }
    fill(buf, 0.02f, 100 + s, [&](uint32_t x, uint32_t, int) { return 0.2f + slope * float(x); });
    const std::vector<float> out = buf.run();
    for (size_t i = 0; i < out.size(); ++i) mean[i] += out[i] / seeds;
  }
  const sg::DenoiseSettings st;
  const double zeroth_order_miss = slope * st.radius / 2.0;
  for (uint32_t x : {0u, 1u, w / 2, w - 2, w - 1}) {
    double err = 0.0;
    for (uint32_t y = 0; y < h; ++y)
      for (int c = 0; c < 3; ++c) err += mean[(size_t(y) * w + x) * 3 + c] - (0.2 + slope * x);
    err /= 3.0 * h;
    EXPECT_LT(std::abs(err), 0.25 * zeroth_order_miss) << "column " << x << ": mean error " << err;
  }
}

TEST(Denoise, SameBytesForOneAndTwoThreads) {
  Buffers buf(70, 45);  // not a multiple of the tile size
  fill(buf, 0.1f, 7,
       [](uint32_t x, uint32_t y, int c) { return 0.3f + 0.2f * float((x / 9 + y / 7) % 2) + 0.05f * c; });
  buf.a[3 * 500] = 40.f;  // a firefly
  std::vector<float> one, two;
  tbb::task_arena(1).execute([&] { one = buf.run(); });
  tbb::task_arena(2).execute([&] { two = buf.run(); });
  ASSERT_EQ(one.size(), two.size());
  EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(float)));
}

TEST(Denoise, BackgroundNanAndHdrGiveFiniteOutput) {
  Buffers buf(40, 30);
  fill(buf, 0.2f, 3, [](uint32_t x, uint32_t, int) { return x < 10 ? 50.f : 0.4f; });  // an emitter
  for (uint32_t y = 0; y < buf.h; ++y)
    for (uint32_t x = 0; x < buf.w; ++x) {
      const size_t i = size_t(y) * buf.w + x;
      if (y < 8) {  // background: no hit
        buf.depth[i] = std::numeric_limits<float>::infinity();
        for (int c = 0; c < 3; ++c) buf.normal[3 * i + c] = buf.albedo[3 * i + c] = 0.f;
      }
    }
  buf.a[3 * 300] = std::numeric_limits<float>::quiet_NaN();
  buf.b[3 * 301 + 1] = std::numeric_limits<float>::infinity();
  buf.a[3 * 302 + 2] = -std::numeric_limits<float>::infinity();
  buf.depth[400] = std::numeric_limits<float>::quiet_NaN();
  buf.normal[3 * 401] = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> out = buf.run();
  for (size_t i = 0; i < out.size(); ++i) {
    ASSERT_TRUE(std::isfinite(out[i])) << "pixel " << i / 3;
    ASSERT_GE(out[i], 0.f);
  }
  // The emitter stays an emitter.
  EXPECT_GT(out[3 * (15 * buf.w + 3)], 40.f);
}

TEST(Denoise, NoisyFeatureHalvesArePrefiltered) {
  // Sample-averaged feature halves (different buffers): the prefilter path runs; a noisy
  // albedo does not make the output noisier than the input.
  Buffers buf(48, 32);
  fill(buf, 0.05f, 11, [](uint32_t, uint32_t, int) { return 0.25f; });
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.f, 0.02f);
  std::vector<float> alb_a(buf.albedo), alb_b(buf.albedo);
  for (size_t i = 0; i < alb_a.size(); ++i) {
    alb_a[i] += noise(rng);
    alb_b[i] += noise(rng);
  }
  sg::DenoiseInput in = buf.input();
  in.albedo[0] = alb_a.data();
  in.albedo[1] = alb_b.data();
  std::vector<float> out(buf.a.size());
  sg::denoise(in, {}, out.data());
  double se = 0.0, se_in = 0.0;
  for (size_t i = 0; i < out.size(); ++i) {
    se += (out[i] - 0.25) * (out[i] - 0.25);
    const double m = 0.5 * (buf.a[i] + buf.b[i]) - 0.25;
    se_in += m * m;
  }
  EXPECT_LT(se, 0.25 * se_in);
}

TEST(Denoise, SecondPassRemovesNoiseToo) {
  Buffers buf(48, 32);
  fill(buf, 0.05f, 13, [](uint32_t x, uint32_t, int) { return x < 24 ? 0.2f : 0.6f; });
  sg::DenoiseSettings s;
  s.second_pass = true;
  const std::vector<float> out = buf.run(s);
  double se = 0.0, se_in = 0.0;
  for (size_t i = 0; i < out.size(); ++i) {
    const double truth = (i / 3) % buf.w < 24 ? 0.2 : 0.6;
    se += (out[i] - truth) * (out[i] - truth);
    const double m = 0.5 * (buf.a[i] + buf.b[i]) - truth;
    se_in += m * m;
  }
  EXPECT_LT(se, 0.1 * se_in);
}

TEST(Denoise, BadInputThrows) {
  Buffers buf(8, 8);
  std::vector<float> out(buf.a.size());
  sg::DenoiseInput in = buf.input();
  in.normal[1] = nullptr;
  EXPECT_THROW(sg::denoise(in, {}, out.data()), sg::Error);
  in = buf.input();
  in.width = 0;
  EXPECT_THROW(sg::denoise(in, {}, out.data()), sg::Error);
  sg::DenoiseSettings s;
  s.radius = 0;
  EXPECT_THROW(sg::denoise(buf.input(), s, out.data()), sg::Error);
  s = {};
  s.k = -1.f;
  EXPECT_THROW(sg::denoise(buf.input(), s, out.data()), sg::Error);
  s = {};
  s.distance_floor = -1e-3f;
  EXPECT_THROW(sg::denoise(buf.input(), s, out.data()), sg::Error);
  s = {};
  s.normal_weight = std::numeric_limits<float>::infinity();
  EXPECT_THROW(sg::denoise(buf.input(), s, out.data()), sg::Error);
}

}  // namespace
