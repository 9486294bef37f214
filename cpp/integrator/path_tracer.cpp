#include "integrator/path_tracer.h"

#include "core/plugin.h"

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
#include "integrator/ray_cone.h"

namespace sg {

namespace {

// NOTE: `seed` is an unsigned 64-bit value; the declared bound 2^64 - 1 (as a double, 2^64)
// is exported to Python as the uint64 maximum (bindings/module.cpp).
PluginInfo render_info() {
  return PluginInfo("render", "path_tracer",
                    "Settings of the path tracer (keyword arguments of Scene.render; the `render` section of "
                    "scene files and scenarios).")
      .add(param::integer("spp", 16, "samples per pixel").in(1, 1 << 20))
      .add(param::integer("max_depth", 8, "maximum ray segments from the camera (1: emitters only)").in(1, 1024))
      .add(param::integer("rr_depth", 5, "path length at which Russian roulette starts").in(0, 1024))
      .add(param::integer("seed", 0, "random seed (images are deterministic per seed)").in(0, 18446744073709551615.0))
      .add(param::integer("threads", 0, "worker threads (0: all cores)").in(0, 4096))
      .add(param::integer("tile_size", 16, "tile edge in pixels").in(1, 4096))
      .add(param::boolean("texture_filtering", true, "filter textures over the ray footprint (ray cones)"));
}

std::shared_ptr<RenderSettings> create_render_settings(const Params& p, const PluginContext&) {
  auto rs = std::make_shared<RenderSettings>();
  rs->spp = uint32_t(p.get_int("spp"));
  rs->max_depth = uint32_t(p.get_int("max_depth"));
  rs->rr_depth = uint32_t(p.get_int("rr_depth"));
  rs->seed = uint64_t(p.get_int("seed"));
  rs->threads = uint32_t(p.get_int("threads"));
  rs->tile_size = uint32_t(p.get_int("tile_size"));
  rs->texture_filtering = p.get_bool("texture_filtering");
  return rs;
}

}  // namespace

SG_REGISTER_PLUGIN(RenderSettings, render_info(), create_render_settings)

RenderSettings RenderSettings::from_params(const ParamSet& params, const std::string& context) {
  return *Registry::instance().create<RenderSettings>("render", "path_tracer", params, PluginContext{}, context);
}

void RenderSettings::validate() const {
  if (spp == 0) throw Error("render settings: spp must be at least 1");
  if (max_depth == 0) throw Error("render settings: max_depth must be at least 1");
  if (tile_size == 0) throw Error("render settings: tile_size must be at least 1");
}

namespace {

// Sample dimensions: 0-1 pixel position, then a block of k_dims_per_vertex per path vertex:
// (+0, +1) light position, (+2, +3) BSDF direction — the 2D-stratified pairs of
// PixelSampler — then +4 light choice, +5 BSDF lobe (a pair too), +6 Russian roulette
// (unstratified).
constexpr uint32_t k_dims_per_vertex = 8;

struct PathCounters {
  uint64_t rays = 0;
  uint64_t nan = 0;
};

/// State of one camera path. Paths of the same pixel advance together in packets of
/// up to k_packet_size so that Embree can trace their rays with packet traversal; every lane does
/// exactly what a scalar path tracer would do, so results do not depend on packing.
struct PathState {
  Ray ray;
  Color L{0.f}, beta{1.f};
  Color shadow_contrib{0.f};  ///< NEE contribution, added if the shadow ray is unoccluded
  float prev_pdf = 0.f;
  /// Where the previous vertex chose its light and the light weights' sum there
  /// (RenderScene::pick_light): the MIS weight of emission the next segment finds reuses them.
  Vec3f prev_p{0.f};
  float prev_light_total = 0.f;
  uint32_t segments = 1;  ///< ray segments so far (the camera ray is segment 1)
  uint32_t bounce = 0;
  bool prev_delta = true;  ///< the camera "sampled" the first direction
  /// Every bounce so far was a glossy or specular lobe: the camera sees a reflection (of a
  /// reflection ...): only such paths see reflection_only lights.
  bool all_glossy = true;
  /// Product of eta^2 over refractions: removes the 1/eta^2 radiance scaling from the
  /// Russian-roulette decision (pbrt-v4 "etaScale"), so paths inside glass are not culled.
  float eta_scale = 1.f;
  bool active = true;
  bool hit_geometry = false;
  /// Differential rendering (full-scene pass): the camera ray first hit an inserted
  /// (non-catcher) object; the path met an inserted object somewhere (a hit, a shadow ray it
  /// blocked, its emission sampled), so the path without the objects differs.
  bool synthetic_first = false;
  bool touched = false;
  float cone_width = 0.f, cone_spread = 0.f;  ///< ray cone for texture filtering (ray_cone.h)
};

/// Pair keys (PixelSampler::pair_key) of one path vertex's sample dimensions. They depend
/// only on (seed, pixel, bounce), so the lanes of a packet share them.
struct VertexKeys {
  uint32_t bounce = ~0u;
  uint64_t light = 0, bsdf = 0, pick_lobe = 0;
  void update(uint32_t b, const PixelSampler& sampler) {
    if (b == bounce) return;
    uint32_t base = 2 + b * k_dims_per_vertex;
    light = sampler.pair_key(base);
    bsdf = sampler.pair_key(base + 2);
    pick_lobe = sampler.pair_key(base + 4);
    bounce = b;
  }
};

/// Ambient occlusion at a shading point: the fraction of `n` cosine-distributed rays of
/// length `radius` over the hemisphere of the shading normal (on the side of `wo`) that hit
/// nothing. Random numbers: unstratified dimensions `dim0`.. of the path's sampler.
inline float estimate_ao(const RenderScene& sc, const SurfaceInteraction& si, const Vec3f& wo, float radius, int n,
                         const PixelSampler& sampler, uint32_t dim0) {
  float side = dot(si.ng, wo) >= 0.f ? 1.f : -1.f;
  Vec3f nrm = si.ns * side, ng = si.ng * side;
  Frame f(nrm);
  int open = 0;
  for (int j = 0; j < n; ++j) {
    Vec2f u(sampler.get_independent(dim0 + 2 * uint32_t(j)), sampler.get_independent(dim0 + 2 * uint32_t(j) + 1));
    Vec3f d = f.to_world(square_to_cosine_hemisphere(u));
    if (dot(d, ng) <= 0.f) continue;  // below the geometric surface: occluded by it
    Ray r;
    r.o = offset_ray_origin(si.p, si.p_error, ng, d);
    r.d = d;
    r.t_max = radius;
    open += !sc.accel->occluded(r);
  }
  return float(open) / float(n);
}

/// Convex-edge measure at an interaction: `n` rays (stratified in azimuth) from a point lifted a
/// tenth of `radius` off the surface, heading along it and 15 degrees into it, at most `radius`
/// long; the fraction that finds no surface.
/// NOTE: over an open panel each ray meets the surface again (at 0.39 radius: lift / sin 15);
/// near a convex edge (curvature radius under ~0.75 radius) or a sheet's border the surface
/// falls away from the rays that cross it, which escape; creases stop them (they are AO's).
inline float estimate_edges(const RenderScene& sc, const SurfaceInteraction& si, const Vec3f& wo, float radius,
                            int n, const PixelSampler& sampler, uint32_t dim) {
  float side = dot(si.ng, wo) >= 0.f ? 1.f : -1.f;
  Vec3f ng = si.ng * side;
  Frame f(ng);
  const float lift = 0.1f * radius, c = 0.96592583f, s = 0.25881905f;  // cos, sin 15 degrees
  Vec3f o = si.p + ng * (lift + 1e-4f * (1.f + std::fabs(si.p.x) + std::fabs(si.p.y) + std::fabs(si.p.z)));
  float u = sampler.get_independent(dim);
  int open = 0;
  for (int j = 0; j < n; ++j) {
    float phi = 6.2831853f * (float(j) + u) / float(n);
    Vec3f d = f.to_world(Vec3f(c * std::cos(phi), c * std::sin(phi), -s));
    Ray r;
    r.o = o;
    r.d = d;
    r.t_max = radius;
    open += !sc.accel->occluded(r);
  }
  return float(open) / float(n);
}

/// One pixel's sample statistics: the sums of its even- and odd-numbered samples (by sample
/// index) and of the squares, in double (the variance is a small difference of large sums).
struct PixelMoments {
  double sum[2][3] = {{0, 0, 0}, {0, 0, 0}};
  double sq[3] = {0, 0, 0};
  uint32_t n[2] = {0, 0};

  void add(uint32_t sample_index, const Color& l) {
    const int h = int(sample_index & 1u);
    const double v[3] = {l.x, l.y, l.z};
    for (int c = 0; c < 3; ++c) {
      sum[h][c] += v[c];
      sq[c] += v[c] * v[c];
    }
    ++n[h];
  }
  uint32_t count() const { return n[0] + n[1]; }
  /// rgb (the mean of all samples), rgb_even / rgb_odd (the halves' means) and the variance
  /// of the mean into the film at `pixel`.
  void store(Film* film, uint64_t pixel) const {
    const uint32_t total = count();
    for (int c = 0; c < 3; ++c) {
      const double s = sum[0][c] + sum[1][c];
      const double mean = total ? s / total : 0.0;
      film->rgb[3 * pixel + c] = float(mean);
      film->rgb_even[3 * pixel + c] = n[0] ? float(sum[0][c] / n[0]) : 0.f;
      film->rgb_odd[3 * pixel + c] = n[1] ? float(sum[1][c] / n[1]) : 0.f;
      double var = total > 1 ? std::max(0.0, (sq[c] - s * mean) / double(total - 1)) / double(total) : 0.0;
      film->variance[3 * pixel + c] = float(var);
    }
  }
};

class PathTracer {
 public:
  PathTracer(const RenderScene& scene, const RenderSettings& settings)
      : m_scene(scene),
        m_s(settings),
        m_pixel_spread(settings.texture_filtering ? pixel_spread_angle(scene.camera) : 0.f),
        m_sample_spread(m_pixel_spread * camera_sample_spread_scale(settings.spp)) {}

  /// The current ray escaped: infinite lights, MIS-weighted against light sampling.
  void on_miss(PathState& st) const {
    const RenderScene& sc = m_scene;
    for (uint32_t li : sc.infinite_lights) {
      const Light* light = sc.lights[li];
      if (st.bounce == 0 && !light->visible_to_camera()) continue;  // hidden from camera rays
      Color le = light->le(st.ray.d);
      if (is_black(le)) continue;
      float w = 1.f;
      if (!st.prev_delta)
        w = power_heuristic(st.prev_pdf, sc.light_pmf(st.prev_p, li, st.prev_light_total) * light->pdf_le(st.ray.d));
      st.L += st.beta * le * w;
    }
    // Lights only reflections see: no MIS (never sampled), only at the end of a camera path of
    // glossy / specular bounces (what the camera sees reflected; never light on a diffuse surface).
    if (st.bounce > 0 && st.all_glossy)
      for (const Light* light : sc.reflection_lights) st.L += st.beta * light->le(st.ray.d);
    st.active = false;
  }

  /// The current ray hit a surface: add emission, prepare a shadow ray for next-event
  /// estimation (returns true and fills `shadow`), and sample the next direction (or end
  /// the path by clearing `st.active`).
  /// `layer`: RayLayer::catchers for the pass without the inserted objects (their lights are
  /// then skipped too); `track` marks in the full-scene pass what the objects change.
  bool on_hit(PathState& st, const RayHit& hit, const PixelSampler& sampler, VertexKeys& keys, Ray* shadow,
              RayLayer layer, bool track) const {
    const RenderScene& sc = m_scene;
    if (st.bounce == 0) st.hit_geometry = true;
    const InstanceRecord& inst = sc.instances[hit.inst];
    if (track && !inst.catcher) {
      st.touched = true;
      if (st.bounce == 0) st.synthetic_first = true;
    }
    const Material* mat = sc.material_of(inst, hit.prim);
    const Material::Traits traits = mat->traits();
    const uint32_t needs = traits.needs;
    SurfaceInteraction si = make_interaction(inst, hit, (needs & k_needs_tangent) != 0);
    si.primary = st.bounce == 0;
    if (m_s.texture_filtering) {
      st.cone_width += st.cone_spread * hit.t;  // ray_cone.h, eq. (29)
      if (needs & k_needs_footprint) set_ray_cone_footprint(&si, inst, hit.prim, st.ray.d, st.cone_width);
      si.world_footprint = surface_footprint(st.cone_width, st.ray.d, si.ng);
    }
    Vec3f wo = -st.ray.d;
    if (needs & k_needs_ao)
      si.ao = estimate_ao(sc, si, wo, mat->ao_radius(), mat->ao_samples(), sampler, 0x10000u + st.bounce * 256u);
    if (needs & k_needs_edges)
      si.edge = estimate_edges(sc, si, wo, mat->edge_radius(), mat->edge_samples(), sampler,
                               0x10000u + st.bounce * 256u + 200u);
    bool shadow_requested = false;

    // Emission seen by this segment.
    if (traits.emissive) {
      Color le = mat->emission(si, wo);
      if (!is_black(le)) {
        float w = 1.f;
        const int32_t li = inst.prim_light ? inst.prim_light[hit.prim] : -1;
        if (!st.prev_delta && li >= 0) {
          float cos_l = std::fabs(dot(si.ng, wo));
          const AreaLight* area = static_cast<const AreaLight*>(sc.lights[size_t(li)]);
          float pdf_light = sc.light_pmf(st.prev_p, uint32_t(li), st.prev_light_total) * area->area_pdf(hit.prim) *
                            hit.t * hit.t / cos_l;
          w = power_heuristic(st.prev_pdf, pdf_light);
        }
        st.L += st.beta * le * w;
      }
    }
    uint32_t flags = traits.flags;
    if (st.segments >= m_s.max_depth || flags == k_bsdf_none) {
      st.active = false;
      return false;
    }
    keys.update(st.bounce, sampler);
    const Vec2f u_pick_lobe = sampler.get_2d_keyed(keys.pick_lobe);  // light choice, BSDF lobe

    // Next-event estimation: sample a light, defer the shadow ray.
    // Only lobes that are not Dirac deltas can be evaluated towards a sampled light.
    if ((flags & (k_bsdf_diffuse | k_bsdf_glossy)) && !sc.lights.empty()) {
      float pick_pmf;
      size_t li = sc.pick_light(si.p, u_pick_lobe.x, &pick_pmf, &st.prev_light_total);
      st.prev_p = si.p;
      const Light* light = sc.lights[li];
      // Without the inserted objects their emitters are absent: the same choice adds nothing.
      const bool light_absent = layer == RayLayer::catchers && !sc.light_in_catcher_layer[li];
      LightSample ls;
      LightSampleContext ctx{si.p, si.p_error};
      if (!light_absent && light->sample(ctx, sampler.get_2d_keyed(keys.light), &ls)) {
        float bsdf_pdf;
        Color f = mat->eval_pdf(si, wo, ls.wi, &bsdf_pdf);
        if (!is_black(f)) {
          shadow->o = offset_ray_origin(si.p, si.p_error, si.ng, ls.wi);
          if (ls.infinite) {
            shadow->d = ls.wi;
            shadow->t_max = k_inf;
          } else {
            Vec3f target = ls.delta ? ls.p_light : offset_ray_origin(ls.p_light, ls.p_light_error, ls.n_light, -ls.wi);
            shadow->d = target - shadow->o;
            shadow->t_max = 1.f - k_shadow_epsilon;
          }
          float light_pdf = pick_pmf * ls.pdf;
          float w = ls.delta ? 1.f : power_heuristic(light_pdf, bsdf_pdf);
          st.shadow_contrib = st.beta * f * ls.li * (w / light_pdf);
          shadow_requested = true;
          if (track && !sc.light_in_catcher_layer[li]) st.touched = true;
        }
      }
    }

    // BSDF sampling.
    BsdfSample bs;
    if (!mat->sample(si, wo, u_pick_lobe.y, sampler.get_2d_keyed(keys.bsdf), &bs)) {
      st.active = false;
      return shadow_requested;
    }
    st.beta *= bs.weight;
    st.prev_pdf = bs.pdf;
    if (bs.flags & k_bsdf_transmission) st.eta_scale *= bs.eta * bs.eta;
    st.prev_delta = (bs.flags & k_bsdf_delta) != 0;
    st.all_glossy = st.all_glossy && (bs.flags & (k_bsdf_delta | k_bsdf_glossy)) != 0;
    st.cone_spread += bsdf_spread_angle(bs);
    ++st.segments;
    ++st.bounce;
    // The next ray could only find emission; without hittable emitters it is not traced.
    if (is_black(st.beta) || (st.segments >= m_s.max_depth && !sc.has_hittable_emitters)) {
      st.active = false;
      return shadow_requested;
    }
    // NOTE: Russian roulette (Arvo & Kirk 1990) on the throughput's largest component.
    if (st.segments > m_s.rr_depth) {
      float q = std::max(0.05f, 1.f - max_component(st.beta) * st.eta_scale);
      if (sampler.get_independent(2 + (st.bounce - 1) * k_dims_per_vertex + 6) < q) {
        st.active = false;
        return shadow_requested;
      }
      st.beta *= 1.f / (1.f - q);
    }
    st.ray = spawn_ray(si, bs.wi);
    return shadow_requested;
  }

  /// Traces samples [s0, s0 + n) of pixel (x, y), n <= k_packet_size, of the lanes i < n with
  /// lane_on[i] (all when null), in the scene `layer`; fills per lane the final path state
  /// (radiance L, hit_geometry, and with `track` synthetic_first / touched).
  void trace_lanes(uint32_t x, uint32_t y, uint32_t s0, uint32_t n, const bool* lane_on, RayLayer layer, bool track,
                   PathState* st, PathCounters& counters) const {
    const RenderScene& sc = m_scene;
    uint64_t pixel = uint64_t(y) * sc.camera.width + x;
    constexpr int W = k_packet_size;
    PixelSampler samplers[W];
    uint64_t pixel_key[2] = {0, 0};  // per half of the samples (PixelSampler::half)
    for (uint32_t i = 0; i < uint32_t(W); ++i) {
      st[i] = PathState();
      samplers[i] = PixelSampler(m_s.seed, pixel, s0 + i, m_s.spp);
      if (i < 2) pixel_key[samplers[i].half()] = samplers[i].pair_key(0);
      if (i >= n || (lane_on && !lane_on[i])) {
        st[i].active = false;
        continue;
      }
      {
        Vec2f j = samplers[i].get_2d_keyed(pixel_key[samplers[i].half()]);
        st[i].ray = sc.camera.generate_ray(float(x) + j.x, float(y) + j.y);
      }
      st[i].cone_spread = m_sample_spread;
    }
    VertexKeys keys[2];
    for (;;) {
      RayPacket rays;
      uint32_t n_active = 0;
      for (int i = 0; i < W; ++i) {
        if (st[i].active) {
          rays.set(i, st[i].ray);
          ++n_active;
        } else {
          rays.valid[i] = 0;
        }
      }
      if (!n_active) break;
      HitPacket hp;
      sc.accel->intersect_packet(rays, &hp, layer);
      counters.rays += n_active;
      RayPacket shadows;
      uint32_t n_shadow = 0;
      for (int i = 0; i < W; ++i) {
        shadows.valid[i] = 0;
        if (!st[i].active) continue;
        if (!hp.found[i]) {
          on_miss(st[i]);
          continue;
        }
        Ray shadow;
        if (on_hit(st[i], hp.hit[i], samplers[i], keys[samplers[i].half()], &shadow, layer, track)) {
          shadows.set(i, shadow);
          ++n_shadow;
        }
      }
      if (n_shadow) {
        bool occluded[W];
        sc.accel->occluded_packet(shadows, occluded, layer);
        counters.rays += n_shadow;
        if (track) {
          // A shadow ray blocked in the full scene but not by catchers: an inserted object
          // casts this shadow.
          RayPacket blocked;
          uint32_t n_blocked = 0;
          for (int i = 0; i < W; ++i) {
            blocked.valid[i] = 0;
            if (shadows.valid[i] && occluded[i] && !st[i].touched) {
              blocked.set(i, shadows.get(i));
              ++n_blocked;
            }
          }
          if (n_blocked) {
            bool by_catchers[W];
            sc.accel->occluded_packet(blocked, by_catchers, RayLayer::catchers);
            counters.rays += n_blocked;
            for (int i = 0; i < W; ++i)
              if (blocked.valid[i] && !by_catchers[i]) st[i].touched = true;
          }
        }
        for (int i = 0; i < W; ++i)
          if (shadows.valid[i] && !occluded[i]) st[i].L += st[i].shadow_contrib;
      }
    }
  }

  /// Traces samples [s0, s0 + n) of pixel (x, y), n <= k_packet_size; adds the valid samples'
  /// radiance to `m` and counts the camera-ray hits.
  void trace_packet(uint32_t x, uint32_t y, uint32_t s0, uint32_t n, PixelMoments* m, uint32_t* hits,
                    PathCounters& counters) const {
    PathState st[k_packet_size];
    trace_lanes(x, y, s0, n, nullptr, RayLayer::all, false, st, counters);
    for (uint32_t i = 0; i < n; ++i) {
      *hits += st[i].hit_geometry;
      if (!is_finite(st[i].L)) {
        ++counters.nan;
        continue;
      }
      m->add(s0 + i, st[i].L);
    }
  }

  /// Per-pixel sums of differential rendering (Film::differential).
  struct DifferentialSums {
    PixelMoments full;
    Color synthetic{0.f}, with{0.f}, without{0.f}, behind{0.f};
    uint32_t hits = 0, synthetic_n = 0;
  };

  /// Samples [s0, s0 + n) traced in the full scene and, where a path met an inserted object,
  /// again without the objects (same random numbers: common random numbers, so the difference
  /// of the two estimates is exactly 0 where the objects have no influence).
  void trace_packet_differential(uint32_t x, uint32_t y, uint32_t s0, uint32_t n, DifferentialSums* d,
                                 PathCounters& counters) const {
    constexpr int W = k_packet_size;
    PathState full[W], without[W];
    trace_lanes(x, y, s0, n, nullptr, RayLayer::all, true, full, counters);
    bool again[W];
    bool any = false;
    for (int i = 0; i < W; ++i) {
      again[i] = uint32_t(i) < n && full[i].touched;
      any = any || again[i];
    }
    if (any) trace_lanes(x, y, s0, n, again, RayLayer::catchers, false, without, counters);
    for (uint32_t i = 0; i < n; ++i) {
      d->hits += full[i].hit_geometry;
      const Color& lf = full[i].L;
      const Color& lw = again[i] ? without[i].L : full[i].L;
      if (!is_finite(lf) || !is_finite(lw)) {
        ++counters.nan;
        continue;
      }
      d->full.add(s0 + i, lf);
      if (full[i].synthetic_first) {
        d->synthetic += lf;
        d->behind += lw;
        ++d->synthetic_n;
      } else {
        d->with += lf;
        d->without += lw;
      }
    }
  }

  /// Labels from the camera ray through the pixel centre.
  bool labels(uint32_t x, uint32_t y, Film* film, PathCounters& counters) const {
    const RenderScene& sc = m_scene;
    float z_per_t;
    Ray ray = sc.camera.generate_ray(float(x) + 0.5f, float(y) + 0.5f, &z_per_t);
    RayHit hit;
    ++counters.rays;
    if (!sc.accel->intersect(ray, &hit)) return false;  // film is initialised to background
    const InstanceRecord& inst = sc.instances[hit.inst];
    const Material* mat = sc.material_of(inst, hit.prim);
    SurfaceInteraction si = make_interaction(inst, hit, (mat->needs() & k_needs_tangent) != 0);
    // The albedo label is filtered over the whole pixel's cone (no sub-pixel scaling):
    // the pixel-centre ray stands for the pixel.
    if (m_s.texture_filtering) {
      set_ray_cone_footprint(&si, inst, hit.prim, ray.d, m_pixel_spread * hit.t);
      si.world_footprint = surface_footprint(m_pixel_spread * hit.t, ray.d, si.ng);
    }
    if (mat->traits().needs & k_needs_ao) {
      PixelSampler centre(m_s.seed, uint64_t(y) * sc.camera.width + x, 0, m_s.spp);
      si.ao = estimate_ao(sc, si, -ray.d, mat->ao_radius(), mat->ao_samples(), centre, 0x20000u);
    }
    if (mat->traits().needs & k_needs_edges) {
      PixelSampler centre(m_s.seed, uint64_t(y) * sc.camera.width + x, 0, m_s.spp);
      si.edge = estimate_edges(sc, si, -ray.d, mat->edge_radius(), mat->edge_samples(), centre, 0x20000u + 200u);
    }
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
    return true;
  }

 private:
  const RenderScene& m_scene;
  const RenderSettings& m_s;
  float m_pixel_spread;   ///< camera cone spread angle (0 without texture filtering)
  float m_sample_spread;  ///< spread of one path sample's camera cone
};

}  // namespace

void render_path_traced(const RenderScene& scene, const RenderSettings& settings, Film* film) {
  settings.validate();
  scene.camera.validate();
  const uint32_t w = scene.camera.width, h = scene.camera.height;
  const bool differential = scene.has_catchers && !settings.labels_only;
  film->allocate(w, h, differential);
  PathTracer pt(scene, settings);
  std::atomic<uint64_t> rays{0}, nans{0};
  auto t0 = std::chrono::steady_clock::now();
  // More threads than hardware threads cannot help (and TBB would warn): clamp.
  int hw = tbb::this_task_arena::max_concurrency();
  int threads = settings.threads ? std::min(int(settings.threads), hw) : hw;
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
              bool centre_hit = pt.labels(x, y, film, c);
              if (settings.labels_only) {
                film->alpha[pixel] = centre_hit ? 1.f : 0.f;
                continue;
              }
              if (differential) {
                PathTracer::DifferentialSums d;
                for (uint32_t s0 = 0; s0 < settings.spp; s0 += k_packet_size)
                  pt.trace_packet_differential(x, y, s0, std::min<uint32_t>(k_packet_size, settings.spp - s0), &d, c);
                const uint32_t valid = d.full.count();
                const float inv = valid ? 1.f / float(valid) : 0.f;
                auto put = [&](std::vector<float>& buf, const Color& v) {
                  buf[3 * pixel] = v.x * inv;
                  buf[3 * pixel + 1] = v.y * inv;
                  buf[3 * pixel + 2] = v.z * inv;
                };
                // NOTE: rgb divides like the plain path (sum / valid) so that it equals a plain render's.
                d.full.store(film, pixel);
                put(film->synthetic_rgb, d.synthetic);
                put(film->catcher_with, d.with);
                put(film->catcher_without, d.without);
                put(film->behind_synthetic, d.behind);
                film->synthetic_alpha[pixel] = float(d.synthetic_n) * inv;
                film->alpha[pixel] = float(d.hits) / float(settings.spp);
                continue;
              }
              PixelMoments m;
              uint32_t hits = 0;
              for (uint32_t s0 = 0; s0 < settings.spp; s0 += k_packet_size)
                pt.trace_packet(x, y, s0, std::min<uint32_t>(k_packet_size, settings.spp - s0), &m, &hits, c);
              m.store(film, pixel);
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
  st.samples = settings.labels_only ? 0 : uint64_t(w) * h * settings.spp;
  st.rays = rays.load();
  st.nan_samples = nans.load();
  st.samples_per_s = secs > 0 ? double(st.samples) / secs : 0.0;
  st.rays_per_s = secs > 0 ? double(st.rays) / secs : 0.0;
  st.threads = uint32_t(threads);
}

}  // namespace sg
