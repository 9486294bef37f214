// Adaptive sampling's policy (integrator/adaptive.h) on films made by hand: the per-pixel
// and per-image error estimates against their formulas, which pixels keep sampling (3 x 3
// mean error against the threshold, dilated by one pixel, stopped pixels stay stopped), and
// the image target.
#include <gtest/gtest.h>

#include <cmath>

#include "integrator/adaptive.h"

using namespace sg;

namespace {

/// A w x h film whose pixels all have `n` samples and halves `a` (even) and `b` (odd) per channel.
Film film_of(uint32_t w, uint32_t h, uint32_t n, float a, float b) {
  Film f;
  f.allocate(w, h);
  for (size_t i = 0; i < size_t(w) * h; ++i) {
    f.sample_count[i] = n;
    for (int c = 0; c < 3; ++c) {
      f.rgb_even[3 * i + c] = a;
      f.rgb_odd[3 * i + c] = b;
      f.rgb[3 * i + c] = 0.5f * (a + b);
    }
  }
  return f;
}

void set_pixel(Film* f, size_t i, float a, float b) {
  for (int c = 0; c < 3; ++c) {
    f->rgb_even[3 * i + c] = a;
    f->rgb_odd[3 * i + c] = b;
    f->rgb[3 * i + c] = 0.5f * (a + b);
  }
}

}  // namespace

// (a - b)^2 / (n (1/n_e + 1/n_o)): a quarter of the halves' squared difference for equal
// halves; odd counts; exposure before clamping; the doubling where one half saturates.
TEST(adaptive, pixel_and_image_error_follow_the_dual_buffer_formula) {
  Film f = film_of(2, 1, 16, 0.3f, 0.5f);
  EXPECT_NEAR(pixel_squared_error(f, 0, 1.f), 0.04 / 4.0, 1e-8);
  EXPECT_NEAR(pixel_squared_error(f, 0, 2.f), 0.16 / 4.0, 1e-8);  // 0.6 vs 1.0
  f.sample_count[1] = 5;  // halves of 3 and 2: factor 1 / (5 (1/3 + 1/2)) = 0.24
  EXPECT_NEAR(pixel_squared_error(f, 1, 1.f), 0.04 * 0.24, 1e-8);
  EXPECT_NEAR(estimated_mse(f, 1.f), 0.5 * (0.01 + 0.04 * 0.24), 1e-8);
  set_pixel(&f, 0, 0.8f, 1.5f);  // one half saturates: (0.8 - 1)^2 / 4, doubled
  EXPECT_NEAR(pixel_squared_error(f, 0, 1.f), 2.0 * 0.04 / 4.0, 1e-7);
  set_pixel(&f, 0, 1.2f, 1.5f);  // both saturate: no visible error
  EXPECT_EQ(pixel_squared_error(f, 0, 1.f), 0.0);
  f.sample_count[0] = 1;  // no estimate from one sample
  EXPECT_LT(estimated_mse(f, 1.f), 0.0);
}

// A noisy 3 x 3 patch in a clean 12 x 10 image: only the pixels whose 3 x 3 mean error is
// above the threshold, and their neighbours, keep sampling; a stopped pixel never restarts.
TEST(adaptive, noisy_pixels_and_their_neighbours_keep_sampling) {
  const uint32_t w = 12, h = 10;
  Film f = film_of(w, h, 32, 0.5f, 0.5f);
  for (uint32_t y = 4; y < 7; ++y)
    for (uint32_t x = 5; x < 8; ++x) set_pixel(&f, size_t(y) * w + x, 0.3f, 0.7f);  // rms 0.2
  RenderSettings rs;
  rs.noise_threshold = 0.1f;
  AdaptiveStop stop(rs);
  std::vector<uint8_t> active(size_t(w) * h, 1);
  ASSERT_TRUE(stop.keep_going(f, &active));
  // A patch pixel's squared error is 0.4^2 / 4 = 0.04 (rms 0.2); a pixel is noisy when the
  // mean over its 3 x 3 neighbourhood is >= 0.1^2: at least a quarter of it in the patch.
  auto noisy = [&](int x, int y) {
    int k = 0, n = 0;
    for (int yy = std::max(0, y - 1); yy <= std::min(int(h) - 1, y + 1); ++yy)
      for (int xx = std::max(0, x - 1); xx <= std::min(int(w) - 1, x + 1); ++xx, ++n) k += yy >= 4 && yy < 7 && xx >= 5 && xx < 8;
    return 0.04 * k / n >= 0.01;
  };
  int on = 0;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      bool expect = false;
      for (int yy = int(y) - 1; yy <= int(y) + 1; ++yy)
        for (int xx = int(x) - 1; xx <= int(x) + 1; ++xx)
          if (yy >= 0 && yy < int(h) && xx >= 0 && xx < int(w)) expect = expect || noisy(xx, yy);
      EXPECT_EQ(bool(active[size_t(y) * w + x]), expect) << x << ", " << y;
      on += active[size_t(y) * w + x];
    }
  EXPECT_GT(on, 9);
  EXPECT_LT(on, int(w * h) / 2);
  // The noise is gone: everything stops; a stopped pixel stays stopped even if noisy again.
  for (size_t i = 0; i < size_t(w) * h; ++i) set_pixel(&f, i, 0.5f, 0.5f);
  EXPECT_FALSE(stop.keep_going(f, &active));
  set_pixel(&f, 0, 0.0f, 1.0f);
  EXPECT_FALSE(stop.keep_going(f, &active));
  EXPECT_EQ(active[0], 0);
}

// target_psnr: the image stops once its estimated PSNR reaches the target; without a
// threshold every pixel keeps sampling until then.
TEST(adaptive, the_image_stops_at_its_target_psnr) {
  Film f = film_of(8, 8, 16, 0.48f, 0.52f);  // mse 0.0004 -> 33.98 dB
  RenderSettings rs;
  rs.target_psnr = 35.f;
  AdaptiveStop stop(rs);
  std::vector<uint8_t> active(64, 0);
  EXPECT_TRUE(stop.keep_going(f, &active));
  EXPECT_NEAR(stop.last_psnr_db(), 10.0 * std::log10(1.0 / 0.0004), 1e-4);
  for (uint8_t a : active) EXPECT_EQ(a, 1);
  rs.target_psnr = 33.f;
  EXPECT_FALSE(stop.keep_going(f, &active));
}

// Settings: rounds of 16, min_spp rounded up to whole rounds and auto max(16, sqrt(max)),
// max_spp defaulting to spp; min_spp above the maximum is an error.
TEST(adaptive, settings_rounds_and_limits) {
  RenderSettings rs;
  rs.spp = 400;
  EXPECT_EQ(rs.max_samples(), 400u);
  EXPECT_EQ(rs.min_samples(), 400u);  // not adaptive: every pixel gets spp
  rs.noise_threshold = 0.01f;
  EXPECT_EQ(rs.min_samples(), 32u);  // sqrt(400) = 20 -> 32
  rs.max_spp = 4096;
  EXPECT_EQ(rs.max_samples(), 4096u);
  EXPECT_EQ(rs.min_samples(), 64u);
  rs.min_spp = 20;
  EXPECT_EQ(rs.min_samples(), 32u);
  rs.validate();
  rs.min_spp = 5000;
  EXPECT_THROW(rs.validate(), std::exception);
}
