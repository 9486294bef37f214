#include "film/film.h"

#include <chrono>
#include <limits>
#include <new>
#include <string>

#include "core/error.h"
#include "film/denoise.h"

namespace sg {

void Film::allocate(uint32_t w, uint32_t h, bool diff) {
  width = w;
  height = h;
  size_t n = size_t(w) * h;
  constexpr float inf = std::numeric_limits<float>::infinity();
  try {
    rgb.assign(3 * n, 0.f);
    alpha.assign(n, 0.f);
    depth.assign(n, inf);
    distance.assign(n, inf);
    normal.assign(3 * n, 0.f);
    albedo.assign(3 * n, 0.f);
    instance_id.assign(n, 0u);
    class_id.assign(n, 0u);
    for (auto* v : {&rgb_even, &rgb_odd, &variance, &albedo_even, &albedo_odd, &normal_even, &normal_odd})
      v->assign(3 * n, 0.f);
    for (auto* v : {&depth_even, &depth_odd}) v->assign(n, 0.f);
    sample_count.assign(n, 0u);
    std::vector<float>().swap(rgb_noisy);
    differential = diff;
    for (auto* v : {&synthetic_rgb, &catcher_with, &catcher_without, &behind_synthetic}) {
      if (diff) v->assign(3 * n, 0.f);
      else std::vector<float>().swap(*v);
    }
    if (diff) synthetic_alpha.assign(n, 0.f);
    else std::vector<float>().swap(synthetic_alpha);
  } catch (const std::bad_alloc&) {
    *this = Film();
    throw Error("render: cannot allocate the buffers of a " + std::to_string(w) + " x " + std::to_string(h) +
                " image (" + std::to_string(n * (diff ? 204 : 152) / (1 << 20)) + " MiB): not enough memory");
  }
}

void denoise_film(Film* film) {
  const auto t0 = std::chrono::steady_clock::now();
  DenoiseInput in;
  in.width = film->width;
  in.height = film->height;
  in.rgb[0] = film->rgb_even.data();
  in.rgb[1] = film->rgb_odd.data();
  in.albedo[0] = film->albedo_even.data();
  in.albedo[1] = film->albedo_odd.data();
  in.normal[0] = film->normal_even.data();
  in.normal[1] = film->normal_odd.data();
  in.depth[0] = film->depth_even.data();
  in.depth[1] = film->depth_odd.data();
  film->rgb_noisy = film->rgb;
  denoise(in, DenoiseSettings(), film->rgb.data());
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  film->stats.denoise_time_s = secs;
  film->stats.wall_time_s += secs;
}

}  // namespace sg
