// The texture resolution estimate: before rendering, which mip level of every image texture
// the camera actually needs (docs/texture_lod.md).
//
// One camera ray per pixel (through its centre) with ray differentials -- the rays through
// the next pixel to the right and below, intersected with the plane of each hit -- gives at
// every hit the pixel's footprint in uv (the images of one pixel step along x and y). The
// hit's material is then evaluated once with that footprint while a FootprintRecorder is
// active (texture/footprint.h), so every image lookup the material makes (base colour,
// roughness, normal and bump maps, masks of blends and mixes, alpha cut-outs, emission)
// reports its pyramid and footprint, through any uv transform. From the hit the estimate
// follows the material's sharp lobes (Material::specular_events: mirrors, glass, car paint's
// coat) with the differentials reflected or refracted, so textures seen in them count too.
//
// The result per pyramid: the coarsest level at which every recorded lookup still has at
// least one texel per pixel in at least one axis (texture/footprint.h). Known limits, each
// documented and tested:
//  - behind curved mirrors the differentials are first order: the offset rays are reflected
//    about the shading normal interpolated at their own points of the hit's plane (vertex
//    normals of a coarse tessellation bend them approximately);
//  - magnified close-ups need more than level 0: the estimate is clamped to level 0;
//  - textures seen only through diffuse or rough bounces are not recorded ("unseen").
#pragma once

#include <cstdint>

#include "integrator/render_scene.h"
#include "texture/footprint.h"

namespace sg {

struct TextureEstimateSettings {
  /// Sharp bounces followed after the camera hit (0: camera hits only).
  uint32_t max_depth = 4;
  /// Rays traced per pixel at most (the camera ray and the branches of glass: reflection
  /// and refraction each continue).
  uint32_t max_rays_per_pixel = 16;
  /// Worker threads (0: all cores); the result does not depend on it.
  uint32_t threads = 0;
};

struct TextureEstimate {
  FootprintRecorder recorded;   ///< per pyramid and per texture: the smallest footprints
  uint64_t camera_rays = 0;     ///< camera rays traced (one per pixel)
  uint64_t bounce_rays = 0;     ///< rays traced along sharp lobes
};

/// Runs the estimate for the scene's camera (the scene committed).
TextureEstimate estimate_texture_footprints(const RenderScene& scene, const TextureEstimateSettings& settings);

}  // namespace sg
