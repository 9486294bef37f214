// Path tracing through the scene's participating medium (RenderScene::medium, medium/medium.h):
// the free flight of each ray segment, decoupled next-event estimation along it, and scattering
// by the phase function. The path tracer (path_tracer.cpp) calls these for every segment when
// the scene has a medium; a path's surface vertices stay its own.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "integrator/path_state.h"
#include "integrator/path_tracer.h"
#include "medium/medium.h"

namespace sg::path_detail {

class VolumeTracer {
 public:
  /// `clamp`: clamp_indirect's limit in radiance units (inf: off).
  VolumeTracer(const RenderScene& scene, const RenderSettings& settings, float clamp)
      : m_scene(scene), m_s(settings), m_clamp(clamp) {}

  /// Transmittance of the global medium along a shadow ray (1 without one): exact, or an unbiased
  /// estimate (ratio tracking) from the stream of the vertex's shadow slot.
  float transmittance(const Ray& r, const PixelSampler& sampler, uint32_t bounce, int slot) const {
    if (!m_scene.medium) return 1.f;
    MediumRng rng(sampler.independent_key(k_medium_shadow_dims + bounce * uint32_t(k_shadow_slots) + uint32_t(slot)));
    return m_scene.medium->transmittance_estimate(r.o, r.d, r.t_max, rng);
  }

  /// A free flight through the global medium along the current ray, up to `t_end` (its hit, or
  /// inf): true and the event's ray parameter in *t when it scatters first. The estimator's
  /// weight is the medium's albedo at an event and 1 when the flight passes (medium.h).
  bool event(const PathState& st, float t_end, const PixelSampler& sampler, float* t) const {
    if (!m_scene.medium) return false;
    MediumRng rng(sampler.independent_key(2 + st.bounce * k_dims_per_vertex + 7));
    return m_scene.medium->sample_distance(st.ray.o, st.ray.d, t_end, rng, t);
  }

  /// Decoupled next-event estimation in the medium along the current segment [0, t_end): the
  /// light scattered towards the path at a point drawn from the free-flight density conditioned
  /// on scattering within the segment, one light of each group, weighted by the probability of
  /// scattering at all (1 - T). Fills shadow[g] / st.shadow_contrib[k_light_groups + g]; returns
  /// the mask of the groups it filled. In a heterogeneous medium the point and its weight come
  /// from tracking (Medium::sample_in_segment): the same estimator in expectation.
  /// NOTE: the expectation equals next-event estimation at the vertex where the free flight
  /// scatters (which then does none), but every segment gets an estimate instead of the
  /// fraction 1 - T that scatters: far less noise in the single-scattered light (the "decoupled"
  /// direct lighting of production renderers, e.g. Cycles' volume integrator, which samples the
  /// direct-light point apart from the indirect scattering decision). MIS with phase sampling at
  /// the same point is consistent because both use the light choice there (scatter).
  uint32_t next_event(PathState& st, float t_end, const PixelSampler& sampler, Ray* shadow, RayLayer layer,
                      bool track) const {
    const RenderScene& sc = m_scene;
    if (!sc.medium || sc.lights.empty() || !m_s.next_event || st.medium_bounces >= m_s.max_medium_depth) return 0;
    const uint32_t dim = k_medium_nee_dims + st.bounce * 8u;
    float t, p_scatter;
    MediumRng rng(sampler.independent_key(dim));
    if (!sc.medium->sample_in_segment(st.ray.o, st.ray.d, t_end, rng, &t, &p_scatter)) return 0;
    const Medium& medium = *sc.medium;
    const Vec3f p = st.ray.o + st.ray.d * t;
    const Vec3f wo = -normalize(st.ray.d);
    const HenyeyGreenstein phase = medium.phase();
    const Color beta = st.beta * medium.albedo() * p_scatter;
    if (is_black(beta)) return 0;
    const LightSampleContext ctx{p, Vec3f(0.f), Vec3f(0.f)};
    uint32_t requested = 0;
    for (int g = 0; g < RenderScene::k_light_groups; ++g) {
      if (sc.group_lights[g].empty()) continue;
      const uint32_t d = dim + 1u + 3u * uint32_t(g);
      float pick_pmf;
      size_t li = sc.pick_light(g, p, sampler.get_independent(d), &pick_pmf);
      const Light* light = sc.lights[li];
      if (layer == RayLayer::catchers && !sc.light_in_catcher_layer[li]) continue;
      LightSample ls;
      if (!light->sample(ctx, Vec2f(sampler.get_independent(d + 1), sampler.get_independent(d + 2)), &ls)) continue;
      const float f = phase.eval(wo, ls.wi);
      if (!(f > 0.f)) continue;
      const Ray& sh = shadow[g] = shadow_ray_to(p, ls);
      const float tr = transmittance(sh, sampler, st.bounce, RenderScene::k_light_groups + g);
      if (!(tr > 0.f)) continue;
      const float light_pdf = pick_pmf * ls.pdf;
      // NOTE: MIS weights from the directions' densities alone (light vs phase sampling); the
      // free flight's probability of reaching the light (T) is left out of both, which keeps
      // the weights a partition of unity (unbiased) -- pbrt-v4's volumetric path tracer also
      // folds T into them (its r_u / r_l ratios), slightly better where the medium is thick.
      const float w = ls.delta ? 1.f : power_heuristic(light_pdf, f);
      st.shadow_contrib[RenderScene::k_light_groups + g] =
          clamp_indirect(beta * ls.li * (f * w * tr / light_pdf), st.bounce, m_clamp);
      requested |= 1u << g;
      if (track && !sc.light_in_catcher_layer[li]) st.touched = true;
    }
    return requested;
  }

  /// The current ray scattered in the medium at ray parameter t: a new direction from the phase
  /// function (the light the medium scatters along the segment was estimated by next_event). The
  /// same bookkeeping as the path tracer's surface vertices.
  void scatter(PathState& st, float t, const PixelSampler& sampler, VertexKeys& keys) const {
    const RenderScene& sc = m_scene;
    const Medium& medium = *sc.medium;
    const Vec3f p = st.ray.o + st.ray.d * t;
    const Vec3f wo = -normalize(st.ray.d);
    st.beta *= medium.albedo();
    st.path_length += t * length(st.ray.d);
    st.cone_width += st.cone_spread * t;
    if (!st.feature_final) {
      st.feature_albedo = medium.albedo();
      st.feature_normal = Vec3f(0.f);
      st.feature_depth = st.path_length;
      st.feature_final = true;
    }
    // NOTE: scattering events count apart from max_depth (Cycles' volume bounces, pbrt's
    // maxDepth counts both): multiple scattering in thick fog takes many, and cutting them off at
    // a surface budget darkens fog that is bright in reality (light diffuses through the layer).
    if (st.medium_bounces >= m_s.max_medium_depth || is_black(st.beta)) {
      st.active = false;
      return;
    }
    const HenyeyGreenstein phase = medium.phase();
    keys.update(st.bounce, sampler);
    // Light was sampled for this segment by next_event (decoupled); what a phase-sampled
    // direction finds is weighed against it with the light choice at this point.
    st.prev_p = p;
    st.prev_n = Vec3f(0.f);
    for (int g = 0; g < RenderScene::k_light_groups; ++g) {
      st.prev_light_total[g] = 0.f;
      if (sc.group_lights[g].empty()) continue;
      float pmf;
      sc.pick_light(g, p, 0.5f, &pmf, &st.prev_light_total[g]);
    }
    float pdf;
    const Vec3f wi = phase.sample(wo, sampler.get_2d_keyed(keys.bsdf), &pdf);
    if (!(pdf > 0.f)) {
      st.active = false;
      return;
    }
    // The phase function is sampled exactly: its value over its pdf is 1.
    st.prev_pdf = pdf;
    st.prev_delta = false;
    st.all_glossy = false;
    st.cone_spread += k_pi / 8.f;  // as a diffuse bounce's widest spread (ray_cone.h)
    ++st.medium_bounces;
    ++st.bounce;
    if (!survives_roulette(st, sampler, m_s.rr_depth)) {
      st.active = false;
      return;
    }
    st.ray = Ray{p, wi, k_inf};
  }

 private:
  const RenderScene& m_scene;
  const RenderSettings& m_s;
  float m_clamp;
};

}  // namespace sg::path_detail
