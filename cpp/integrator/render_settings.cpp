// RenderSettings: the settings from their declaration (the "render" plugin, registered in
// integrator/path_tracer.cpp under its key), and their checks.
#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/plugin.h"
#include "integrator/path_tracer.h"

namespace sg {

RenderSettings RenderSettings::from_params(const ParamSet& params, const std::string& context) {
  return *Registry::instance().create<RenderSettings>("render", "path_tracer", params, PluginContext{}, context);
}

ParamSet RenderSettings::to_params() const {
  ParamSet p;
  p.set("spp", int64_t(spp));
  p.set("max_depth", int64_t(max_depth));
  p.set("rr_depth", int64_t(rr_depth));
  p.set("max_medium_depth", int64_t(max_medium_depth));
  p.set("next_event", next_event);
  p.set("seed", int64_t(seed));
  p.set("threads", int64_t(threads));
  p.set("tile_size", int64_t(tile_size));
  p.set("texture_filtering", texture_filtering);
  p.set("exposure", double(exposure));
  p.set("clamp_indirect", double(clamp_indirect));
  p.set("denoise", denoise);
  p.set("noise_threshold", double(noise_threshold));
  p.set("target_psnr", double(target_psnr));
  p.set("min_spp", int64_t(min_spp));
  p.set("max_spp", int64_t(max_spp));
  p.set("labels_only", labels_only);
  p.set("texture_lod", texture_lod);
  p.set("texture_lod_margin", int64_t(texture_lod_margin));
  p.set("texture_budget_mib", double(texture_budget_mib));
  return p;
}

void RenderSettings::validate() const {
  if (spp == 0) throw Error("render settings: spp must be at least 1");
  if (max_depth == 0) throw Error("render settings: max_depth must be at least 1");
  if (tile_size == 0) throw Error("render settings: tile_size must be at least 1");
  if (!(exposure > 0.f) || !std::isfinite(exposure)) throw Error("render settings: exposure must be positive");
  if (!(clamp_indirect >= 0.f)) throw Error("render settings: clamp_indirect must be 0 (off) or positive");
  if (!(noise_threshold >= 0.f) || !(target_psnr >= 0.f))
    throw Error("render settings: noise_threshold and target_psnr must be 0 (off) or positive");
  // NOTE: the denoiser weighs each half-sample image by the other and estimates the noise from
  // their difference; with one sample a pixel has one half only (measured on the Cornell box at
  // 256 x 192: 19.7 dB denoised against 26.1 dB raw).
  if (denoise && !labels_only && spp < 2)
    throw Error("render settings: denoise needs at least 2 samples per pixel (its two half-sample images); "
                "spp is " + std::to_string(spp));
  if (adaptive() && min_spp && min_spp > max_samples())
    throw Error("render settings: min_spp (" + std::to_string(min_spp) + ") is more than the most samples a pixel "
                "gets (max_spp or spp: " + std::to_string(max_samples()) + ")");
}

uint32_t RenderSettings::min_samples() const {
  const uint32_t most = max_samples();
  if (!adaptive()) return most;
  uint32_t m = min_spp ? min_spp : std::max<uint32_t>(16, uint32_t(std::ceil(std::sqrt(double(most)))));
  m = (m + adaptive_step() - 1) / adaptive_step() * adaptive_step();
  return std::min(m, most);
}

}  // namespace sg
