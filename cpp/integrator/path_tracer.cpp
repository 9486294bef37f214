#include "integrator/path_tracer.h"

#include <tbb/blocked_range2d.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <string>

#include "core/error.h"
#include "core/rng.h"
#include "integrator/interaction.h"

namespace sg {

void RenderSettings::validate() const {
  if (spp == 0) throw Error("render settings: spp must be at least 1");
  if (max_depth == 0) throw Error("render settings: max_depth must be at least 1");
  if (tile_size == 0) throw Error("render settings: tile_size must be at least 1");
}

namespace {

// Sample dimensions: 0-1 pixel position, then a block of k_dims_per_vertex per path vertex.
constexpr uint32_t k_dims_per_vertex = 7;

struct PathCounters {
  uint64_t rays = 0;
  uint64_t nan = 0;
};

class PathTracer {
 public:
  PathTracer(const RenderScene& scene, const RenderSettings& settings) : m_scene(scene), m_s(settings) {}

  /// Radiance of one camera path. `hit_geometry` reports whether the camera ray hit.
  Color trace(Ray ray, PixelSampler& sampler, PathCounters& counters, bool* hit_geometry) const {
    const RenderScene& sc = m_scene;
    Color L(0.f), beta(1.f);
    float prev_pdf = 0.f;
    bool prev_delta = true;  // the camera "sampled" the first direction
    uint32_t segments = 1;
    *hit_geometry = false;
    for (uint32_t bounce = 0;; ++bounce) {
      RayHit hit;
      ++counters.rays;
      if (!sc.accel->intersect(ray, &hit)) {
        // Escaped: infinite lights, MIS-weighted against light sampling.
        for (uint32_t li : sc.infinite_lights) {
          const Light* light = sc.lights[li];
          Color le = light->le(ray.d);
          if (is_black(le)) continue;
          float w = 1.f;
          if (!prev_delta) w = power_heuristic(prev_pdf, sc.light_pick.pmf(li) * light->pdf_le(ray.d));
          L += beta * le * w;
        }
        break;
      }
      if (bounce == 0) *hit_geometry = true;
      const InstanceRecord& inst = sc.instances[hit.inst];
      SurfaceInteraction si = make_interaction(inst, hit);
      const Material* mat = sc.material_of(inst, hit.prim);
      Vec3f wo = -ray.d;

      // Emission seen by this segment.
      if (mat->is_emissive()) {
        Color le = mat->emission(si, wo);
        if (!is_black(le)) {
          float w = 1.f;
          if (!prev_delta && inst.light) {
            float cos_l = std::fabs(dot(si.ng, wo));
            float pdf_light = sc.light_pick.pmf(uint32_t(inst.light_index)) * inst.light->area_pdf(hit.prim) *
                              hit.t * hit.t / cos_l;
            w = power_heuristic(prev_pdf, pdf_light);
          }
          L += beta * le * w;
        }
      }
      if (segments >= m_s.max_depth) break;
      uint32_t flags = mat->flags();
      if (flags == k_bsdf_none) break;
      uint32_t base = 2 + bounce * k_dims_per_vertex;

      // Next-event estimation.
      if ((flags & ~uint32_t(k_bsdf_delta)) && !sc.lights.empty()) {
        float pick_pmf;
        size_t li = sc.light_pick.sample(sampler.get(base), &pick_pmf);
        const Light* light = sc.lights[li];
        LightSample ls;
        LightSampleContext ctx{si.p, si.p_error};
        if (light->sample(ctx, Vec2f(sampler.get(base + 1), sampler.get(base + 2)), &ls)) {
          Color f = mat->eval(si, wo, ls.wi);
          if (!is_black(f)) {
            Ray shadow;
            shadow.o = offset_ray_origin(si.p, si.p_error, si.ng, ls.wi);
            if (ls.infinite) {
              shadow.d = ls.wi;
              shadow.t_max = k_inf;
            } else {
              Vec3f target = ls.delta ? ls.p_light
                                      : offset_ray_origin(ls.p_light, ls.p_light_error, ls.n_light, -ls.wi);
              shadow.d = target - shadow.o;
              shadow.t_max = 1.f - k_shadow_epsilon;
            }
            ++counters.rays;
            if (!sc.accel->occluded(shadow)) {
              float light_pdf = pick_pmf * ls.pdf;
              float w = ls.delta ? 1.f : power_heuristic(light_pdf, mat->pdf(si, wo, ls.wi));
              L += beta * f * ls.li * (w / light_pdf);
            }
          }
        }
      }

      // BSDF sampling.
      BsdfSample bs;
      if (!mat->sample(si, wo, sampler.get(base + 3), Vec2f(sampler.get(base + 4), sampler.get(base + 5)), &bs))
        break;
      beta *= bs.weight;
      prev_pdf = bs.pdf;
      prev_delta = (bs.flags & k_bsdf_delta) != 0;
      ++segments;
      if (is_black(beta)) break;

      // NOTE: Russian roulette (Arvo & Kirk 1990) on the throughput's largest component.
      if (segments > m_s.rr_depth) {
        float q = std::max(0.05f, 1.f - max_component(beta));
        if (sampler.get(base + 6) < q) break;
        beta *= 1.f / (1.f - q);
      }
      ray = spawn_ray(si, bs.wi);
    }
    return L;
  }

  /// Labels from the camera ray through the pixel centre.
  void labels(uint32_t x, uint32_t y, Film* film, PathCounters& counters) const {
    const RenderScene& sc = m_scene;
    float z_per_t;
    Ray ray = sc.camera.generate_ray(float(x) + 0.5f, float(y) + 0.5f, &z_per_t);
    RayHit hit;
    ++counters.rays;
    if (!sc.accel->intersect(ray, &hit)) return;  // film is initialised to background
    const InstanceRecord& inst = sc.instances[hit.inst];
    SurfaceInteraction si = make_interaction(inst, hit);
    const Material* mat = sc.material_of(inst, hit.prim);
    size_t i = size_t(y) * film->width + x;
    film->depth[i] = hit.t * z_per_t;
    film->distance[i] = hit.t;
    film->normal[3 * i] = si.ns.x;
    film->normal[3 * i + 1] = si.ns.y;
    film->normal[3 * i + 2] = si.ns.z;
    Color a = mat->albedo(si);
    film->albedo[3 * i] = a.x;
    film->albedo[3 * i + 1] = a.y;
    film->albedo[3 * i + 2] = a.z;
    film->instance_id[i] = inst.instance_id;
    film->class_id[i] = inst.class_id;
  }

 private:
  const RenderScene& m_scene;
  const RenderSettings& m_s;
};

}  // namespace

void render_path_traced(const RenderScene& scene, const RenderSettings& settings, Film* film) {
  settings.validate();
  scene.camera.validate();
  const uint32_t w = scene.camera.width, h = scene.camera.height;
  film->allocate(w, h);
  PathTracer pt(scene, settings);
  std::atomic<uint64_t> rays{0}, nans{0};
  auto t0 = std::chrono::steady_clock::now();
  int threads = settings.threads ? int(settings.threads) : tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(threads);
  const uint32_t ts = settings.tile_size;
  arena.execute([&] {
    tbb::parallel_for(
        tbb::blocked_range2d<uint32_t>(0, h, ts, 0, w, ts),
        [&](const tbb::blocked_range2d<uint32_t>& r) {
          PathCounters c;
          for (uint32_t y = r.rows().begin(); y < r.rows().end(); ++y)
            for (uint32_t x = r.cols().begin(); x < r.cols().end(); ++x) {
              uint64_t pixel = uint64_t(y) * w + x;
              pt.labels(x, y, film, c);
              Color sum(0.f);
              uint32_t valid = 0, hits = 0;
              for (uint32_t s = 0; s < settings.spp; ++s) {
                PixelSampler sampler(settings.seed, pixel, s);
                float u = float(x) + sampler.get(0), v = float(y) + sampler.get(1);
                Ray ray = scene.camera.generate_ray(u, v);
                bool hit;
                Color L = pt.trace(ray, sampler, c, &hit);
                hits += hit;
                if (!is_finite(L)) {
                  ++c.nan;
                  continue;
                }
                sum += L;
                ++valid;
              }
              if (valid) sum = sum / float(valid);
              film->rgb[3 * pixel] = sum.x;
              film->rgb[3 * pixel + 1] = sum.y;
              film->rgb[3 * pixel + 2] = sum.z;
              film->alpha[pixel] = float(hits) / float(settings.spp);
            }
          rays += c.rays;
          nans += c.nan;
        },
        tbb::simple_partitioner());
  });
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  RenderStats& st = film->stats;
  st.wall_time_s = secs;
  st.samples = uint64_t(w) * h * settings.spp;
  st.rays = rays.load();
  st.nan_samples = nans.load();
  st.samples_per_s = secs > 0 ? double(st.samples) / secs : 0.0;
  st.rays_per_s = secs > 0 ? double(st.rays) / secs : 0.0;
  st.threads = uint32_t(threads);
}

}  // namespace sg
