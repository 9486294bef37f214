// Feature-guided denoising of a render's two half-sample images: a reduced NFOR
// (Bitterli, Rousselle, Moon, Iglesias-Guitian, Adler, Mitchell, Jarosz & Novak 2016,
// "Nonlinearly Weighted First-Order Regression for Denoising Monte Carlo Renderings").
// A pure function of its buffers: no scene, no film, no state.
#pragma once

#include <cstdint>

namespace sg {

/// The buffers of one render. Every pointer is row-major, H x W (x 3 where noted), float32.
/// Each feature comes as two halves like the radiance; a render without sample-averaged
/// feature halves passes its pixel-centre feature as both (the same pointer twice).
struct DenoiseInput {
  uint32_t width = 0, height = 0;
  const float* rgb[2] = {nullptr, nullptr};     ///< H x W x 3: the even- and odd-sample means (linear)
  const float* albedo[2] = {nullptr, nullptr};  ///< H x W x 3
  const float* normal[2] = {nullptr, nullptr};  ///< H x W x 3 (0 on background)
  const float* depth[2] = {nullptr, nullptr};   ///< H x W, metres; +inf, NaN or <= 0: background
  /// Optional H x W x 3 variance of the mean of all samples (Film::variance); without it the
  /// noise is estimated from the two halves' difference.
  const float* variance = nullptr;
};

/// Settings of denoise(); the defaults are the ones measured in docs/denoise.md.
struct DenoiseSettings {
  /// Half-size of the regression window ((2r+1)^2 neighbours; NFOR: 9).
  int radius = 4;
  /// Half-size of the NL-means patches of the regression weights (NFOR: 3; 1 measured better
  /// here, docs/denoise.md).
  int patch_radius = 1;
  /// NL-means bandwidth of the larger of the two candidate filters; the other uses k / 2
  /// (NFOR's candidates are 1 and 0.5). Each pixel blends the two by their estimated error.
  float k = 1.0f;
  /// Window half-size of the feature prefilter (NFOR: 5, patches 3, k 0.5); it runs only when
  /// some feature has two different halves.
  int feature_radius = 5;
  /// Window half-size of the NL-means filter of the error estimates and of the selection map
  /// (patches 1, k 1; NFOR: 9).
  int selection_radius = 2;
  /// Divide radiance by max(albedo, albedo_floor) before filtering and multiply after, so
  /// textures stay sharp; 0 disables the demodulation.
  float albedo_floor = 0.01f;
  /// Ridge added to the regression's normal equations (times the sum of weights) for the
  /// feature slopes: keeps windows where a feature is constant solvable.
  float ridge = 1e-3f;
  /// Outliers: a half's value above firefly_ratio x the other half's 3 x 3 maximum (+ its
  /// image mean) is clamped before filtering and the excess added back spread over the
  /// window, adding at most 10% to a pixel (beyond that it is dropped); 0 disables.
  float firefly_ratio = 2.f;
  /// NFOR's second pass: the averaged result filtered once more (about 1.5 x the cost).
  bool second_pass = false;
  /// Relative variance floor of the regression weights' patch distance: floor * (u_p^2 +
  /// u_q^2) is added to the halves' variances, so that differences below about
  /// sqrt(2 floor) of the value weigh like noise (pixels next to noise-free ones -- sky,
  /// emitters -- find neighbours); 0 disables.
  float distance_floor = 1e-3f;
  /// Bilateral normal term of the regression weights, exp(-normal_weight |n_q - n_p|^2);
  /// 0 disables.
  float normal_weight = 5.f;
};

/// Denoises a render from its two half-sample images and features into `out_rgb` (H x W x 3).
/// Each half is filtered by a per-pixel first-order weighted regression on the features
/// (position, depth, normal, albedo), with NL-means weights computed from the OTHER half
/// (cross filtering), at two bandwidths; the per-pixel error of each candidate is estimated
/// from the halves, filtered, and selects the blend; the result is the mean of the two filtered
/// halves. Radiance is demodulated by the albedo. Deterministic (the same bytes for any number
/// of threads), NaN-free (non-finite inputs are read as 0), non-negative. Throws sg::Error on
/// missing buffers, a zero size or bad settings.
void denoise(const DenoiseInput& input, const DenoiseSettings& settings, float* out_rgb);

}  // namespace sg
