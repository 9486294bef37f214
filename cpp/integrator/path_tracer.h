// Unidirectional path tracer with next-event estimation and multiple importance
// sampling (power heuristic) between light and BSDF sampling.
#pragma once

#include <cstdint>
#include <string>

#include "core/params.h"
#include "film/film.h"
#include "integrator/render_scene.h"

namespace sg {

struct RenderSettings {
  uint32_t spp = 16;         ///< samples per pixel
  uint32_t max_depth = 8;    ///< maximum number of ray segments from the camera (1 = direct view of emitters)
  uint32_t rr_depth = 5;     ///< Russian roulette starts once a path has this many segments
  uint32_t max_medium_depth = 64;  ///< scattering events in media a path may have (besides max_depth)
  bool next_event = true;  ///< light sampling with MIS; false: BSDF / phase sampling alone (checks)
  uint64_t seed = 0;
  uint32_t threads = 0;      ///< 0 = all hardware threads
  uint32_t tile_size = 16;
  /// Filter texture lookups over the ray-cone footprint (integrator/ray_cone.h); false =
  /// point-sampled (bilinear, finest mip level) textures.
  bool texture_filtering = true;
  /// The factor the image is multiplied by before it is shown (a scene's exposure): the
  /// thresholds below are in such displayed units (1 = white).
  float exposure = 1.f;
  /// Largest sum of RGB (displayed units) that one indirect contribution of a sample may add
  /// (light that reached the camera over more than one surface: caustics, bright
  /// interreflections); 0 = no clamping. Trades fireflies for a bias (energy lost), as Cycles'
  /// "clamp indirect".
  float clamp_indirect = 0.f;
  /// Adaptive sampling (integrator/adaptive.h): with noise_threshold > 0 a pixel stops once its
  /// estimated RMS error (displayed units, clamped to [0, 1], over its 3 x 3 neighbourhood) is below
  /// it; with target_psnr > 0 the
  /// whole image stops once its estimated PSNR (synthgen.post.quality's definition) reaches
  /// it. Pixels then get between min_spp (0: max(16, sqrt(max))) and max_spp (0: spp)
  /// samples, in rounds of adaptive_step() samples. Labels are unaffected.
  float noise_threshold = 0.f;
  float target_psnr = 0.f;
  uint32_t min_spp = 0, max_spp = 0;
  bool adaptive() const { return noise_threshold > 0.f || target_psnr > 0.f; }
  /// The most samples a pixel gets.
  uint32_t max_samples() const { return adaptive() && max_spp ? max_spp : spp; }
  /// Samples per adaptive round (a pixel stops only after whole rounds).
  static constexpr uint32_t adaptive_step() { return 16; }
  /// The samples every pixel gets before adaptive stopping, a whole number of rounds.
  uint32_t min_samples() const;
  /// Denoise rgb after rendering (film/denoise.h, from the film's half-sample images and
  /// feature halves); the raw image stays in Film::rgb_noisy. Labels are never filtered.
  bool denoise = false;
  /// Only the label outputs (depth, normal, albedo, ids, from the pixel-centre ray); rgb is
  /// left 0 and alpha is 1 where the pixel-centre ray hits. For masks (e.g. amodal ones).
  bool labels_only = false;
  /// Texture level of detail (docs/texture_lod.md): before rendering, the texture resolution
  /// estimate (integrator/texture_estimate.h) picks each pyramid's levels for the camera and
  /// only those stay resident, `texture_lod_margin` levels finer than its guarantee of one
  /// texel per pixel; pyramids the camera does not see keep their levels until the scene's
  /// texture memory exceeds `texture_budget_mib`, then the least recently used drop to their
  /// tail first (Scene).
  bool texture_lod = false;
  uint32_t texture_lod_margin = 0;
  float texture_budget_mib = 256.f;

  void validate() const;
  /// Settings from parameters declared by plugin ("render", "path_tracer")
  /// (integrator/path_tracer.cpp: one default per setting, shared by the bindings and the
  /// YAML formats). Throws sg::Error naming `context`.
  static RenderSettings from_params(const ParamSet& params, const std::string& context = "render settings");
  /// The settings as the parameters from_params reads (every one given): from_params(to_params())
  /// gives these settings back exactly (the change journal records renders so).
  ParamSet to_params() const;
};

/// Renders `scene` into `film` (allocated here). Deterministic for a given seed,
/// independent of `threads` and tile scheduling.
void render_path_traced(const RenderScene& scene, const RenderSettings& settings, Film* film);

}  // namespace sg
