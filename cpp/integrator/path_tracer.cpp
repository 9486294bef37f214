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
#include "integrator/adaptive.h"
#include "integrator/path_state.h"
#include "integrator/ray_cone.h"
#include "integrator/volume.h"

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
      .add(param::boolean("next_event", true, "next-event estimation (light sampling, MIS with BSDF and phase "
                                              "sampling); false: BSDF and phase sampling alone, for checks -- "
                                              "delta lights (point, spot, a 0-degree sun) then light nothing"))
      .add(param::integer("max_medium_depth", 64, "scattering events in a medium (fog, haze) a path may have "
                                                  "besides its max_depth segments: multiple scattering in thick "
                                                  "fog needs many; 0: single scattering").in(0, 4096))
      .add(param::integer("seed", 0, "random seed (images are deterministic per seed)").in(0, 18446744073709551615.0))
      .add(param::integer("threads", 0, "worker threads (0: all cores)").in(0, 4096))
      .add(param::integer("tile_size", 16, "tile edge in pixels").in(1, 4096))
      .add(param::boolean("texture_filtering", true, "filter textures over the ray footprint (ray cones)"))
      .add(param::real("exposure", 1.0, "factor the image is multiplied by when shown (the scene's exposure); "
                                        "clamp_indirect is in such displayed units").above(0))
      .add(param::real("noise_threshold", 0.0, "adaptive sampling: a pixel stops once its estimated RMS error "
                                               "(displayed units, 1 = white) is below this (0.01: about 40 dB; "
                                               "0: off)").at_least(0))
      .add(param::real("target_psnr", 0.0, "adaptive sampling: the image stops once its estimated PSNR (dB) "
                                           "reaches this (0: off)").at_least(0))
      .add(param::integer("min_spp", 0, "adaptive sampling: samples every pixel gets first (0: max(16, sqrt("
                                        "max_spp)), rounded up to whole rounds of 16)").in(0, 1 << 20))
      .add(param::integer("max_spp", 0, "adaptive sampling: most samples of a pixel (0: spp)").in(0, 1 << 20))
      .add(param::boolean("denoise", false, "denoise rgb after rendering (the feature-guided denoiser; the raw "
                                            "image stays available); labels are never filtered"))
      .add(param::boolean("texture_lod", false, "texture level of detail: before rendering, estimate which mip "
                                                "levels of each image texture the camera needs (at least one "
                                                "texel per pixel) and keep only those in memory "
                                                "(docs/texture_lod.md)"))
      .add(param::integer("texture_lod_margin", 0, "texture_lod: keep this many levels finer than the estimate "
                                                   "(each quadruples a texture's memory)").in(0, 8))
      .add(param::real("texture_budget_mib", 256.0, "texture_lod: texture memory (MiB) above which textures "
                                                    "the camera does not see drop their finer levels, least "
                                                    "recently used first").at_least(0))
      .add(param::real("clamp_indirect", 0.0, "largest sum of RGB (displayed units, 1 = white) one indirect "
                                              "contribution of a sample may add; 0: no clamping (removes "
                                              "fireflies of caustics at the cost of some energy)").at_least(0));
}

std::shared_ptr<RenderSettings> create_render_settings(const Params& p, const PluginContext&) {
  auto rs = std::make_shared<RenderSettings>();
  rs->spp = uint32_t(p.get_int("spp"));
  rs->max_depth = uint32_t(p.get_int("max_depth"));
  rs->rr_depth = uint32_t(p.get_int("rr_depth"));
  rs->max_medium_depth = uint32_t(p.get_int("max_medium_depth"));
  rs->next_event = p.get_bool("next_event");
  rs->seed = uint64_t(p.get_int("seed"));
  rs->threads = uint32_t(p.get_int("threads"));
  rs->tile_size = uint32_t(p.get_int("tile_size"));
  rs->texture_filtering = p.get_bool("texture_filtering");
  rs->exposure = p.get_float("exposure");
  rs->clamp_indirect = p.get_float("clamp_indirect");
  rs->denoise = p.get_bool("denoise");
  rs->noise_threshold = p.get_float("noise_threshold");
  rs->target_psnr = p.get_float("target_psnr");
  rs->min_spp = uint32_t(p.get_int("min_spp"));
  rs->max_spp = uint32_t(p.get_int("max_spp"));
  rs->texture_lod = p.get_bool("texture_lod");
  rs->texture_lod_margin = uint32_t(p.get_int("texture_lod_margin"));
  rs->texture_budget_mib = p.get_float("texture_budget_mib");
  return rs;
}

}  // namespace

SG_REGISTER_PLUGIN(RenderSettings, render_info(), create_render_settings)

namespace {

using namespace path_detail;

class PathTracer {
 public:
  PathTracer(const RenderScene& scene, const RenderSettings& settings)
      : m_scene(scene),
        m_s(settings),
        m_pixel_spread(settings.texture_filtering ? pixel_spread_angle(scene.camera) : 0.f),
        m_sample_spread(m_pixel_spread * camera_sample_spread_scale(settings.spp)),
        m_clamp(settings.clamp_indirect > 0.f ? settings.clamp_indirect / settings.exposure : k_inf),
        m_max_spp(settings.max_samples()),
        m_block(settings.adaptive() ? settings.adaptive_step() : 0),
        m_far(far_feature_depth(scene)),
        m_volume(scene, settings, m_clamp) {}

  /// The denoising feature depth of escaped samples: beyond everything in the scene.
  static float far_feature_depth(const RenderScene& sc) {
    if (sc.bounds.empty()) return 1.f;
    return 2.f * (length(sc.camera.position() - sc.bounds.center()) + sc.bounds.radius()) + 1.f;
  }

  /// A contribution clamped by clamp_indirect (path_state.h) when it is indirect.
  Color clamped(const Color& c, uint32_t vertex) const { return clamp_indirect(c, vertex, m_clamp); }

  /// The current ray escaped: infinite lights, MIS-weighted against light sampling.
  void on_miss(PathState& st) const {
    const RenderScene& sc = m_scene;
    for (uint32_t li : sc.infinite_lights) {
      const Light* light = sc.lights[li];
      if (st.bounce == 0 && !light->visible_to_camera()) continue;  // hidden from camera rays
      Color le = light->le(st.ray.d);
      if (is_black(le)) continue;
      float w = 1.f;
      if (!st.prev_delta && m_s.next_event) {
        LightSampleContext ctx{st.prev_p, Vec3f(0.f), st.prev_n};
        w = power_heuristic(st.prev_pdf, sc.light_pmf(st.prev_p, li, st.prev_light_total[sc.light_group[li]]) *
                                             light->pdf_li(ctx, st.ray.d));
      }
      // The segment from vertex bounce - 1: it lit that vertex.
      st.L += clamped(st.beta * le * w, st.bounce > 0 ? st.bounce - 1 : 0);
    }
    // Lights only reflections see: no MIS (never sampled), only at the end of a camera path of
    // glossy / specular bounces (what the camera sees reflected; never light on a diffuse surface).
    if (st.bounce > 0 && st.all_glossy)
      for (const Light* light : sc.reflection_lights) st.L += clamped(st.beta * light->le(st.ray.d), st.bounce - 1);
    st.active = false;
  }

  /// The current ray hit a surface: add emission, prepare the shadow rays of next-event
  /// estimation (one per light group: returns a bit mask of the groups whose `shadow[g]` it
  /// filled), and sample the next direction (or end the path by clearing `st.active`).
  /// `layer`: RayLayer::catchers for the pass without the inserted objects (their lights are
  /// then skipped too); `track` marks in the full-scene pass what the objects change.
  uint32_t on_hit(PathState& st, const RayHit& hit, const PixelSampler& sampler, VertexKeys& keys, Ray* shadow,
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
    SurfaceInteraction si = make_interaction(inst, hit, st.ray, (needs & k_needs_tangent) != 0);
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
    uint32_t shadow_requested = 0;

    // Emission seen by this segment.
    if (traits.emissive) {
      Color le = mat->emission(si, wo);
      if (!is_black(le)) {
        float w = 1.f;
        const int32_t li = inst.prim_light ? inst.prim_light[hit.prim] : -1;
        if (!st.prev_delta && li >= 0 && m_s.next_event) {
          float cos_l = std::fabs(dot(si.ng, wo));
          const AreaLight* area = static_cast<const AreaLight*>(sc.lights[size_t(li)]);
          float pdf_light = sc.light_pmf(st.prev_p, uint32_t(li), st.prev_light_total[sc.light_group[size_t(li)]]) *
                            area->area_pdf(hit.prim) *
                            hit.t * hit.t / cos_l;
          w = power_heuristic(st.prev_pdf, pdf_light);
        }
        st.L += clamped(st.beta * le * w, st.bounce > 0 ? st.bounce - 1 : 0);
      }
    }
    uint32_t flags = traits.flags;
    st.path_length += hit.t;
    if (!st.feature_final) {
      st.feature_albedo = mat->albedo(si);
      st.feature_normal = si.ns;
      st.feature_depth = st.path_length;
      st.feature_final = (flags & (k_bsdf_diffuse | k_bsdf_glossy)) || flags == k_bsdf_none || st.bounce >= 3;
    }
    if (st.segments >= m_s.max_depth || flags == k_bsdf_none) {
      st.active = false;
      return 0;
    }
    keys.update(st.bounce, sampler);
    // NOTE: the vertex's stratified pairs are drawn together, before any is used (each is a pure
    // function of its key): their hash chains are independent, so the CPU overlaps them.
    const Vec2f u_pick_lobe = sampler.get_2d_keyed(keys.pick_lobe);  // light choice, BSDF lobe
    const Vec2f u_light = sampler.get_2d_keyed(keys.light), u_bsdf = sampler.get_2d_keyed(keys.bsdf);
    Vec2f u_dome_pick, u_dome_light;  // the second light group's (a dome's) pairs
    if (!sc.group_lights[1].empty()) {
      u_dome_pick = sampler.get_2d_keyed(keys.dome_pick);
      u_dome_light = sampler.get_2d_keyed(keys.dome_light);
    }

    // Next-event estimation: sample a light of each group, defer the shadow rays.
    // Only lobes that are not Dirac deltas can be evaluated towards a sampled light.
    if ((flags & (k_bsdf_diffuse | k_bsdf_glossy)) && !sc.lights.empty() && m_s.next_event) {
      st.prev_p = si.p;
      st.prev_n = (flags & k_bsdf_transmission) ? Vec3f(0.f) : face_forward(si.ns, wo);
      const LightSampleContext ctx{si.p, si.p_error, st.prev_n};
      for (int g = 0; g < RenderScene::k_light_groups; ++g) {
        st.prev_light_total[g] = 0.f;
        if (sc.group_lights[g].empty()) continue;
        const float u_pick = g == 0 ? u_pick_lobe.x : u_dome_pick.x;
        float pick_pmf;
        size_t li = sc.pick_light(g, si.p, u_pick, &pick_pmf, &st.prev_light_total[g]);
        const Light* light = sc.lights[li];
        // Without the inserted objects their emitters are absent: the same choice adds nothing.
        if (layer == RayLayer::catchers && !sc.light_in_catcher_layer[li]) continue;
        LightSample ls;
        if (!light->sample(ctx, g == 0 ? u_light : u_dome_light, &ls)) continue;
        float bsdf_pdf;
        Color f = mat->eval_pdf(si, wo, ls.wi, &bsdf_pdf);
        if (is_black(f)) continue;
        const Ray& sh = shadow[g] = shadow_ray_to(offset_ray_origin(si.p, si.p_error, si.ng, ls.wi), ls);
        const float tr = m_volume.transmittance(sh, sampler, st.bounce, g);
        if (!(tr > 0.f)) continue;
        float light_pdf = pick_pmf * ls.pdf;
        float w = ls.delta ? 1.f : power_heuristic(light_pdf, bsdf_pdf);
        st.shadow_contrib[g] = clamped(st.beta * f * ls.li * (w * tr / light_pdf), st.bounce);
        shadow_requested |= 1u << g;
        if (track && !sc.light_in_catcher_layer[li]) st.touched = true;
      }
    }

    // BSDF sampling.
    BsdfSample bs;
    if (!mat->sample(si, wo, u_pick_lobe.y, u_bsdf, &bs)) {
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
    if (!survives_roulette(st, sampler, m_s.rr_depth)) {
      st.active = false;
      return shadow_requested;
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
    PixelSampler::PairSeeds pixel_key[2];  // per half of the samples (PixelSampler::half)
    for (uint32_t i = 0; i < uint32_t(W); ++i) {
      st[i] = PathState();
      samplers[i] = PixelSampler(m_s.seed, pixel, s0 + i, m_max_spp, m_block);
      if (i < 2) pixel_key[samplers[i].half()] = PixelSampler::PairSeeds(samplers[i].pair_key(0));
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
      constexpr int G = RenderScene::k_light_groups, S = k_shadow_slots;
      RayPacket shadow_packets[S];
      uint32_t n_shadow[S] = {};
      for (int i = 0; i < W; ++i) {
        for (int g = 0; g < S; ++g) shadow_packets[g].valid[i] = 0;
        if (!st[i].active) continue;
        Ray shadow[S];
        // The medium along the segment first (nothing without one): its decoupled light estimate,
        // then whether the path scatters before the segment's end.
        const float t_end = hp.found[i] ? hp.hit[i].t : k_inf;
        uint32_t mask = m_volume.next_event(st[i], t_end, samplers[i], shadow + G, layer, track) << G;
        float t_event;
        if (m_volume.event(st[i], t_end, samplers[i], &t_event)) {
          if (st[i].bounce == 0 && hp.found[i]) st[i].hit_geometry = true;  // alpha: geometry, not fog
          m_volume.scatter(st[i], t_event, samplers[i], keys[samplers[i].half()]);
        } else if (!hp.found[i]) {
          on_miss(st[i]);
        } else {
          mask |= on_hit(st[i], hp.hit[i], samplers[i], keys[samplers[i].half()], shadow, layer, track);
        }
        for (int g = 0; g < S; ++g)
          if (mask & (1u << g)) {
            shadow_packets[g].set(i, shadow[g]);
            ++n_shadow[g];
          }
      }
      for (int g = 0; g < S; ++g) {
        if (!n_shadow[g]) continue;
        const RayPacket& shadows = shadow_packets[g];
        bool occluded[W];
        sc.accel->occluded_packet(shadows, occluded, layer);
        counters.rays += n_shadow[g];
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
        // NOTE: a select, not a branch: whether a shadow ray is blocked is random, so the branch
        // mispredicted often; adding zero leaves L as it was (radiance is never -0).
        for (int i = 0; i < W; ++i)
          st[i].L += (shadows.valid[i] && !occluded[i]) ? st[i].shadow_contrib[g] : Color(0.f);
      }
    }
  }

  /// Traces samples [s0, s0 + n) of pixel (x, y), n <= k_packet_size; adds the valid samples'
  /// radiance to `m` and counts the camera-ray hits.
  /// Per-pixel sums of a plain render.
  struct PlainSums {
    PixelMoments m;
    uint32_t hits = 0;
    /// Into the film at `pixel`, of a pixel rendered with `spp` samples.
    void store(Film* film, uint64_t pixel, uint32_t spp) const {
      m.store(film, pixel);
      film->alpha[pixel] = float(hits) / float(spp);
    }
  };

  void trace_packet(uint32_t x, uint32_t y, uint32_t s0, uint32_t n, PlainSums* d, PathCounters& counters) const {
    PathState st[k_packet_size];
    trace_lanes(x, y, s0, n, nullptr, RayLayer::all, false, st, counters);
    for (uint32_t i = 0; i < n; ++i) {
      d->hits += st[i].hit_geometry;
      if (!is_finite(st[i].L)) {
        ++counters.nan;
        continue;
      }
      d->m.add(s0 + i, st[i].L, st[i], m_far);
    }
  }

  /// Per-pixel sums of differential rendering (Film::differential).
  struct DifferentialSums {
    PixelMoments full;
    Color synthetic{0.f}, with{0.f}, without{0.f}, behind{0.f};
    uint32_t hits = 0, synthetic_n = 0;
    void store(Film* film, uint64_t pixel, uint32_t spp) const {
      const uint32_t valid = full.count();
      const float inv = valid ? 1.f / float(valid) : 0.f;
      auto put = [&](std::vector<float>& buf, const Color& v) {
        buf[3 * pixel] = v.x * inv;
        buf[3 * pixel + 1] = v.y * inv;
        buf[3 * pixel + 2] = v.z * inv;
      };
      // NOTE: rgb divides like the plain path (sum / valid) so that it equals a plain render's.
      full.store(film, pixel);
      put(film->synthetic_rgb, synthetic);
      put(film->catcher_with, with);
      put(film->catcher_without, without);
      put(film->behind_synthetic, behind);
      film->synthetic_alpha[pixel] = float(synthetic_n) * inv;
      film->alpha[pixel] = float(hits) / float(spp);
    }
  };

  void trace_packet(uint32_t x, uint32_t y, uint32_t s0, uint32_t n, DifferentialSums* d,
                    PathCounters& counters) const {
    trace_packet_differential(x, y, s0, n, d, counters);
  }

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
      d->full.add(s0 + i, lf, full[i], m_far);
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
    SurfaceInteraction si = make_interaction(inst, hit, ray, (mat->needs() & k_needs_tangent) != 0);
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
  float m_clamp;          ///< clamp_indirect in radiance units (inf: off)
  uint32_t m_max_spp;     ///< the most samples a pixel gets
  uint32_t m_block;       ///< PixelSampler's block (adaptive rounds; 0: one block)
  float m_far;            ///< feature depth of escaped samples
  VolumeTracer m_volume;  ///< the segments' paths through the scene's medium (volume.h)
};

}  // namespace

void render_path_traced(const RenderScene& scene, const RenderSettings& settings, Film* film) {
  settings.validate();
  scene.camera.validate();
  const uint32_t w = scene.camera.width, h = scene.camera.height;
  const bool differential = scene.has_catchers && !settings.labels_only;
  film->allocate(w, h, differential, settings.labels_only);
  PathTracer pt(scene, settings);
  std::atomic<uint64_t> rays{0}, nans{0};
  auto t0 = std::chrono::steady_clock::now();
  // More threads than hardware threads cannot help (and TBB would warn): clamp.
  int hw = tbb::this_task_arena::max_concurrency();
  int threads = settings.threads ? std::min(int(settings.threads), hw) : hw;
  tbb::task_arena arena(threads);
  const uint32_t ts = settings.tile_size;
  const uint32_t most = settings.max_samples();
  std::vector<uint32_t>& count = film->sample_count;
  // One round: samples [begin, end) of every pixel still sampling (all in the first round,
  // which also takes the labels). Without adaptive sampling it is the only round, with each
  // pixel's sums on the stack; with it, the sums persist between rounds.
  std::vector<uint8_t> active;
  std::vector<PathTracer::PlainSums> plain_sums;
  std::vector<PathTracer::DifferentialSums> differential_sums;
  const bool adaptive = settings.adaptive() && !settings.labels_only;
  if (adaptive) {
    if (differential) differential_sums.resize(size_t(w) * h);
    else plain_sums.resize(size_t(w) * h);
  }
  auto round = [&](uint32_t begin, uint32_t end) {
    arena.execute([&] {
      tbb::parallel_for(
          tbb::blocked_range2d<uint32_t>(0, h, ts, 0, w, ts),
          [&](const tbb::blocked_range2d<uint32_t>& r) {
            PathCounters c;
            auto trace = [&](auto& sums, uint32_t x, uint32_t y, uint64_t pixel) {
              for (uint32_t s0 = begin; s0 < end; s0 += k_packet_size)
                pt.trace_packet(x, y, s0, std::min<uint32_t>(k_packet_size, end - s0), &sums, c);
              sums.store(film, pixel, end);
              count[pixel] = end;
            };
            for (uint32_t y = r.rows().begin(); y < r.rows().end(); ++y)
              for (uint32_t x = r.cols().begin(); x < r.cols().end(); ++x) {
                uint64_t pixel = uint64_t(y) * w + x;
                if (begin == 0) {
                  bool centre_hit = pt.labels(x, y, film, c);
                  if (settings.labels_only) {
                    film->alpha[pixel] = centre_hit ? 1.f : 0.f;
                    continue;
                  }
                } else if (!active[pixel]) {
                  continue;
                }
                if (adaptive) {
                  if (differential) trace(differential_sums[pixel], x, y, pixel);
                  else trace(plain_sums[pixel], x, y, pixel);
                } else if (differential) {
                  PathTracer::DifferentialSums d;
                  trace(d, x, y, pixel);
                } else {
                  PathTracer::PlainSums d;
                  trace(d, x, y, pixel);
                }
              }
            rays += c.rays;
            nans += c.nan;
          },
          tbb::simple_partitioner());
    });
  };
  uint32_t done = settings.labels_only ? 0 : settings.min_samples();
  round(0, std::max(done, 1u));
  if (adaptive) {
    // NOTE: rounds over the whole image, then the stopping test (integrator/adaptive.h): the
    // pixels that sample again depend only on the film, so images stay independent of threads.
    active.assign(size_t(w) * h, 1);
    AdaptiveStop stop(settings);
    while (done < most && stop.keep_going(*film, &active)) {
      const uint32_t next = std::min(done + RenderSettings::adaptive_step(), most);
      round(done, next);
      done = next;
    }
    film->stats.estimated_psnr_db = stop.last_psnr_db();
  }
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  RenderStats& st = film->stats;
  st.wall_time_s = secs;
  st.samples = 0;
  if (!settings.labels_only)
    for (uint32_t n : count) st.samples += n;
  st.rays = rays.load();
  st.nan_samples = nans.load();
  st.samples_per_s = secs > 0 ? double(st.samples) / secs : 0.0;
  st.rays_per_s = secs > 0 ? double(st.rays) / secs : 0.0;
  st.threads = uint32_t(threads);
}

}  // namespace sg
