// Film: the render outputs. Radiance is the box-filtered mean of the samples;
// every label output comes from the first hit of one camera ray through the pixel
// centre and is never filtered or averaged.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace sg {

struct RenderStats {
  double wall_time_s = 0.0;
  double samples_per_s = 0.0;
  double rays_per_s = 0.0;
  uint64_t samples = 0;
  uint64_t rays = 0;             ///< camera, bounce and shadow rays
  uint64_t nan_samples = 0;      ///< discarded NaN / infinite samples
  uint64_t mesh_bvh_builds = 0;  ///< total bottom-level BVH builds of the scene so far
  uint64_t mesh_bvh_builds_last_commit = 0;
  uint64_t top_level_builds = 0;
  uint64_t alpha_test_calls = 0;  ///< candidate hits alpha-tested (cut-outs) during the render
  uint32_t threads = 0;
  /// Adaptive sampling: the image's estimated PSNR (dB) when it stopped (0 otherwise).
  double estimated_psnr_db = 0.0;
  double denoise_time_s = 0.0;  ///< RenderSettings::denoise: the denoiser's wall time (in wall_time_s too)
  /// RenderSettings::texture_lod: the estimate's wall time (not in wall_time_s), and the
  /// texel memory of the scene's image textures at full resolution and as rendered, and of
  /// the images baked for bakeable procedural textures (bake: auto; the time in
  /// texture_lod_time_s).
  double texture_lod_time_s = 0.0;
  uint64_t texture_bytes_full = 0, texture_bytes_resident = 0, texture_baked_bytes = 0;
};

struct Film {
  uint32_t width = 0, height = 0;
  std::vector<float> rgb;       ///< H x W x 3, linear
  std::vector<float> alpha;     ///< H x W, fraction of samples whose camera ray hit geometry
  std::vector<float> depth;     ///< H x W, camera-space z (metres), +inf on background
  std::vector<float> distance;  ///< H x W, camera-ray length, +inf on background
  std::vector<float> normal;    ///< H x W x 3, world-space shading normal, 0 on background
  std::vector<float> albedo;    ///< H x W x 3
  std::vector<uint32_t> instance_id;  ///< H x W, 0 = background
  std::vector<uint32_t> class_id;     ///< H x W, 0 = background

  /// Noise estimation (not in labels-only renders): the mean radiance of each pixel's
  /// even-numbered and of its odd-numbered samples (H x W x 3 each: two independent estimates
  /// with half the samples each, whose difference measures rgb's noise -- Rousselle, Knaus
  /// & Zwicker 2012, "Adaptive rendering with non-local means filtering"), and the variance
  /// of rgb's mean (H x W x 3: the samples' unbiased variance / their number; 0 with fewer
  /// than two samples).
  std::vector<float> rgb_even, rgb_odd, variance;
  /// The denoiser's features (not in labels-only renders), as the halves' means over their
  /// samples (so antialiased and, through glass or depth of field, noisy like rgb): albedo,
  /// shading normal (H x W x 3) and path length to the surface (H x W, metres) of each
  /// sample's first vertex that is not a Dirac delta (after up to 3 mirror / glass
  /// bounces); escaped samples count as albedo 1, normal 0, a depth beyond the scene.
  std::vector<float> albedo_even, albedo_odd, normal_even, normal_odd, depth_even, depth_odd;
  /// With RenderSettings::denoise: rgb before denoising (H x W x 3; rgb is then the denoised
  /// image); empty otherwise.
  std::vector<float> rgb_noisy;
  /// Samples each pixel got (H x W): spp, or with adaptive sampling its own count.
  std::vector<uint32_t> sample_count;

  /// Differential rendering (scenes with catchers, Scene::set_instance_catcher), per pixel,
  /// each the sum over the pixel's valid samples divided by their number. A sample is
  /// "synthetic" when its camera ray first hits a non-catcher instance (an inserted object);
  /// the others hit a catcher or nothing. Every sample is traced twice with the same random
  /// numbers: in the full scene and in the scene without the inserted objects; a path that
  /// never met an inserted object (hit, shadow ray, light) is the same path in both, so pixels
  /// the objects do not influence have catcher_with == catcher_without bit for bit.
  bool differential = false;
  std::vector<float> synthetic_rgb;     ///< H x W x 3, full-scene radiance of synthetic samples
  std::vector<float> synthetic_alpha;   ///< H x W, fraction of synthetic samples
  std::vector<float> catcher_with;      ///< H x W x 3, full-scene radiance of the other samples
  std::vector<float> catcher_without;   ///< H x W x 3, their radiance without the inserted objects
  std::vector<float> behind_synthetic;  ///< H x W x 3, synthetic samples' radiance without the objects
  RenderStats stats;

  /// Sizes and clears the buffers for a w x h render. `labels_only` (a label-only render):
  /// only the label buffers (alpha, depth, distance, normal, albedo, the ids); rgb, the noise
  /// and feature buffers and sample_count are left empty (the bindings show them as zeros).
  void allocate(uint32_t w, uint32_t h, bool differential = false, bool labels_only = false);
};

/// RenderSettings::denoise: moves rgb to rgb_noisy and writes the denoised image (film/denoise.h,
/// default settings) from the half-sample images and the features' means into rgb; adds the time
/// to stats (denoise_time_s and wall_time_s). Labels and the differential buffers are untouched.
void denoise_film(Film* film);

}  // namespace sg
