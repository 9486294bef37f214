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
  uint64_t seed = 0;
  uint32_t threads = 0;      ///< 0 = all hardware threads
  uint32_t tile_size = 16;
  /// Filter texture lookups over the ray-cone footprint (integrator/ray_cone.h); false =
  /// point-sampled (bilinear, finest mip level) textures.
  bool texture_filtering = true;
  /// Only the label outputs (depth, normal, albedo, ids, from the pixel-centre ray); rgb is
  /// left 0 and alpha is 1 where the pixel-centre ray hits. For masks (e.g. amodal ones).
  bool labels_only = false;

  void validate() const;
  /// Settings from parameters declared by plugin ("render", "path_tracer")
  /// (integrator/path_tracer.cpp: one default per setting, shared by the bindings and the
  /// YAML formats). Throws sg::Error naming `context`.
  static RenderSettings from_params(const ParamSet& params, const std::string& context = "render settings");
};

/// Renders `scene` into `film` (allocated here). Deterministic for a given seed,
/// independent of `threads` and tile scheduling.
void render_path_traced(const RenderScene& scene, const RenderSettings& settings, Film* film);

}  // namespace sg
