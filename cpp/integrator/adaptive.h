// Adaptive sampling: the host policy that decides, between rounds of samples, which pixels
// sample again (render_path_traced runs the rounds; the per-path code knows nothing of it).
//
// Both measures read the film's two half-sample images (Film::rgb_even / rgb_odd: two
// independent estimates of each pixel with half its samples each).
#pragma once

#include <cstdint>
#include <vector>

#include "film/film.h"
#include "integrator/path_tracer.h"

namespace sg {

/// The estimated squared error of pixel i against its converged value, in displayed units
/// (radiance x exposure, clamped to [0, 1]; mean over the channels), from its half-sample
/// images: synthgen.post.quality's definition of image error, per pixel (see estimated_mse).
double pixel_squared_error(const Film& film, size_t i, float exposure);

/// The estimated MSE of the film's rgb against the converged image, after exposure and clamped
/// to [0, 1] (synthgen.post.quality.estimate_noise's definition, per pixel with its own sample
/// count Film::sample_count): E[(a - b)^2] / (n (1/n_e + 1/n_o)) for halves a, b of n_e and n_o
/// samples, doubled where one half saturates and the other does not. -1 without estimates
/// (fewer than 2 samples).
double estimated_mse(const Film& film, float exposure);

/// Between rounds: marks the pixels that sample again.
class AdaptiveStop {
 public:
  explicit AdaptiveStop(const RenderSettings& settings) : m_s(settings) {}
  /// Reads the film after a round; sets (*active)[i] for the pixels that get another round
  /// (its 3 x 3 neighbourhood's RMS error -- the root of the mean of pixel_squared_error --
  /// >= noise_threshold, that set dilated by one pixel -- a pixel next to one still noisy keeps
  /// sampling too, as Cycles' adaptive_sampling_filter_x / _y do -- among those still
  /// sampling, or all of them without a threshold).
  /// NOTE: Cycles stops a pixel by |I - A|_1 / sqrt(I) (Dammertz et al. 2010, sec. 2.1). Measured
  /// on the Ignis Cornell box at 128 x 96 (up to 256 spp, threshold 0.01) that spent its samples
  /// on the light's saturated edges and stopped dark pixels early: 47.05 dB at a mean of 184
  /// spp, below uniform 64 spp (46.06 dB) per sample. The error that the image's PSNR counts
  /// (clamped, displayed units) is what is tested here; a single pixel's estimate from two
  /// halves is noisy (a chi-square of 3 degrees of freedom), so it is averaged over the pixel's
  /// 3 x 3 neighbourhood. Returns false when the image is done: no pixel needs more, or the
  /// estimated PSNR reached target_psnr.
  bool keep_going(const Film& film, std::vector<uint8_t>* active);
  /// The image's estimated PSNR (dB) at the last keep_going (0 before).
  double last_psnr_db() const { return m_psnr; }

 private:
  const RenderSettings& m_s;
  std::vector<uint8_t> m_noisy;
  std::vector<double> m_error;
  double m_psnr = 0.0;
};

}  // namespace sg
