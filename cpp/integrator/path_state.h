// The path tracer's per-path and per-pixel state (integrator/path_tracer.cpp, its only user):
// the sample-dimension layout, one camera path's state, a vertex's sampler keys, the local
// ray probes of materials (ambient occlusion, convex edges) and a pixel's sample sums.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/rng.h"
#include "film/film.h"
#include "integrator/interaction.h"
#include "integrator/render_scene.h"

namespace sg::path_detail {

// Sample dimensions: 0-1 pixel position, then a block of k_dims_per_vertex per path vertex:
// (+0, +1) light position, (+2, +3) BSDF direction — the 2D-stratified pairs of
// PixelSampler — then +4 light choice, +5 BSDF lobe (a pair too), +6 Russian roulette
// (unstratified), +7 the free flight through a medium of the segment arriving at the vertex
// (unstratified), (+8, +9) the dome light's direction, +10 the dome's choice (a pair with
// the unused +11): the two light groups' samples (RenderScene::group_lights).
constexpr uint32_t k_dims_per_vertex = 12;

/// Shadow rays a path vertex may request at once: one per light group at a surface or medium
/// vertex, one per light group for the medium along the segment that reached it.
constexpr int k_shadow_slots = 2 * RenderScene::k_light_groups;

/// First sample dimension (unstratified) of decoupled next-event estimation in a medium, per
/// vertex: +0 the point, then per light group +1 the choice and +2, +3 the light sample.
constexpr uint32_t k_medium_nee_dims = 0x30000u;
/// First sample dimension of the transmittance estimates (ratio tracking) of shadow rays through a
/// heterogeneous medium: + bounce * k_shadow_slots + the shadow slot; each dimension keys a stream
/// (MediumRng). The free flight (+7 of a vertex) and the decoupled point (k_medium_nee_dims) key
/// their own streams the same way.
constexpr uint32_t k_medium_shadow_dims = 0x38000u;

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
  /// NEE contributions, each added if its shadow ray is unoccluded: per light group at the
  /// vertex (slots 0 .. k_light_groups - 1), then per light group at the point the medium
  /// scatters along the segment (decoupled next-event estimation, VolumeTracer::next_event in volume.h).
  Color shadow_contrib[k_shadow_slots];
  float prev_pdf = 0.f;
  /// Where the previous vertex chose its lights, each group's light weights' sum there
  /// (RenderScene::pick_light) and the normal lights sampled by (LightSampleContext::n): the
  /// MIS weight of emission the next segment finds reuses them.
  Vec3f prev_p{0.f}, prev_n{0.f};
  float prev_light_total[RenderScene::k_light_groups] = {0.f, 0.f};
  uint32_t segments = 1;  ///< ray segments so far (the camera ray is segment 1)
  uint32_t medium_bounces = 0;  ///< scattering events in a medium so far (RenderSettings::max_medium_depth)
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
  /// The denoiser's features of this sample (Film::albedo_even ...): albedo, shading normal
  /// and path length at its first vertex that is not a Dirac delta (through mirrors and
  /// glass, at most 3 bounces); the background's (albedo 1, normal 0, far) when it escapes.
  Color feature_albedo{1.f};
  Vec3f feature_normal{0.f};
  float feature_depth = 0.f, path_length = 0.f;
  bool feature_final = false;
  /// Differential rendering (full-scene pass): the camera ray first hit an inserted
  /// (non-catcher) object; the path met an inserted object somewhere (a hit, a shadow ray it
  /// blocked, its emission sampled), so the path without the objects differs.
  bool synthetic_first = false;
  bool touched = false;
  float cone_width = 0.f, cone_spread = 0.f;  ///< ray cone for texture filtering (ray_cone.h)
};

/// A contribution to a sample's radiance: clamped when it is indirect (`vertex`, the index of
/// the surface it lights, >= 1: it reached the camera over more than one surface) to `limit`.
/// NOTE: as Cycles' sample_clamp_indirect (intern/cycles/kernel/film/light_passes.h,
/// film_clamp_light): the contribution is scaled down so that the sum of its channels is at
/// most the limit, keeping its colour.
inline Color clamp_indirect(const Color& c, uint32_t vertex, float limit) {
  if (vertex == 0) return c;
  const float sum = c.x + c.y + c.z;
  return sum > limit ? c * (limit / sum) : c;
}

/// The shadow ray of next-event estimation from `o` (already offset off its surface, if any)
/// towards light sample `ls`: to infinity for infinite lights, else to just before the light's
/// point (offset off the emitter, except for delta lights).
inline Ray shadow_ray_to(const Vec3f& o, const LightSample& ls) {
  Ray sh;
  sh.o = o;
  if (ls.infinite) {
    sh.d = ls.wi;
    sh.t_max = k_inf;
  } else {
    Vec3f target = ls.delta ? ls.p_light : offset_ray_origin(ls.p_light, ls.p_light_error, ls.n_light, -ls.wi);
    sh.d = target - sh.o;
    sh.t_max = 1.f - k_shadow_epsilon;
  }
  return sh;
}

/// Russian roulette once the path has more than `rr_depth` vertices (surfaces and scattering
/// events; its direction sampled, st.bounce already advanced): false ends it, else the survivor's
/// throughput is scaled up.
/// NOTE: Russian roulette (Arvo & Kirk 1990) on the throughput's largest component; eta_scale
/// as in pbrt-v4 (paths inside glass are not culled).
inline bool survives_roulette(PathState& st, const PixelSampler& sampler, uint32_t rr_depth) {
  if (st.segments + st.medium_bounces <= rr_depth) return true;
  const float q = std::max(0.05f, 1.f - max_component(st.beta) * st.eta_scale);
  if (sampler.get_independent(2 + (st.bounce - 1) * k_dims_per_vertex + 6) < q) return false;
  st.beta *= 1.f / (1.f - q);
  return true;
}

/// The pair seeds (PixelSampler::PairSeeds of pair_key) of one path vertex's sample dimensions.
/// They depend only on (seed, pixel, bounce), so the lanes of a packet share them.
struct VertexKeys {
  uint32_t bounce = ~0u;
  PixelSampler::PairSeeds light, bsdf, pick_lobe, dome_light, dome_pick;
  void update(uint32_t b, const PixelSampler& sampler) {
    if (b == bounce) return;
    uint32_t base = 2 + b * k_dims_per_vertex;
    light = PixelSampler::PairSeeds(sampler.pair_key(base));
    bsdf = PixelSampler::PairSeeds(sampler.pair_key(base + 2));
    pick_lobe = PixelSampler::PairSeeds(sampler.pair_key(base + 4));
    dome_light = PixelSampler::PairSeeds(sampler.pair_key(base + 8));
    dome_pick = PixelSampler::PairSeeds(sampler.pair_key(base + 10));
    bounce = b;
  }
};

/// How many of the `n` probe rays of a shading point reach their t_max unblocked; `probe(j, &ray)`
/// makes ray j and returns false for one that counts as blocked without tracing.
/// NOTE: the probes of one shading point (ambient occlusion, edges) share their origin and are
/// short, so they are traced as packets of k_packet_size (Embree's 8- or 16-wide kernels) rather
/// than one call per ray: the same rays, a fraction of the traversal cost.
template <class Probe>
int count_open_probes(const RenderScene& sc, int n, const Probe& probe) {
  int open = 0;
  for (int j0 = 0; j0 < n; j0 += k_packet_size) {
    const int m = std::min(n - j0, k_packet_size);
    RayPacket rays;
    for (int k = 0; k < k_packet_size; ++k) {
      rays.valid[k] = 0;
      Ray r;
      if (k < m && probe(j0 + k, &r)) rays.set(k, r);
    }
    bool occluded[k_packet_size];
    sc.accel->occluded_packet(rays, occluded, RayLayer::all);
    for (int k = 0; k < m; ++k) open += rays.valid[k] && !occluded[k];
  }
  return open;
}

/// Ambient occlusion at a shading point: the fraction of `n` cosine-distributed rays of
/// length `radius` over the hemisphere of the shading normal (on the side of `wo`) that hit
/// nothing. Random numbers: unstratified dimensions `dim0`.. of the path's sampler.
inline float estimate_ao(const RenderScene& sc, const SurfaceInteraction& si, const Vec3f& wo, float radius, int n,
                         const PixelSampler& sampler, uint32_t dim0) {
  float side = dot(si.ng, wo) >= 0.f ? 1.f : -1.f;
  Vec3f nrm = si.ns * side, ng = si.ng * side;
  Frame f(nrm);
  const int open = count_open_probes(sc, n, [&](int j, Ray* r) {
    const uint32_t d0 = dim0 + 2 * uint32_t(j);
    const Vec3f d = f.to_world(square_to_cosine_hemisphere(Vec2f(sampler.get_independent(d0),
                                                                 sampler.get_independent(d0 + 1))));
    if (dot(d, ng) <= 0.f) return false;  // below the geometric surface: occluded by it
    r->o = offset_ray_origin(si.p, si.p_error, ng, d);
    r->d = d;
    r->t_max = radius;
    return true;
  });
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
  const int open = count_open_probes(sc, n, [&](int j, Ray* r) {
    const float phi = 6.2831853f * (float(j) + u) / float(n);
    r->o = o;
    r->d = f.to_world(Vec3f(c * std::cos(phi), c * std::sin(phi), -s));
    r->t_max = radius;
    return true;
  });
  return float(open) / float(n);
}

/// One pixel's sample statistics: the sums of its even- and odd-numbered samples (by sample
/// index) and of the squares, in double (the variance is a small difference of large sums),
/// and the sums of the halves' denoising features.
struct PixelMoments {
  double sum[2][3] = {{0, 0, 0}, {0, 0, 0}};
  double sq[3] = {0, 0, 0};
  uint32_t n[2] = {0, 0};
  float albedo[2][3] = {{0, 0, 0}, {0, 0, 0}}, normal[2][3] = {{0, 0, 0}, {0, 0, 0}}, depth[2] = {0, 0};

  void add(uint32_t sample_index, const Color& l, const PathState& st, float far) {
    const int h = int(sample_index & 1u);
    const double v[3] = {l.x, l.y, l.z};
    for (int c = 0; c < 3; ++c) {
      sum[h][c] += v[c];
      sq[c] += v[c] * v[c];
      albedo[h][c] += st.feature_albedo[c];
      normal[h][c] += st.feature_normal[c];
    }
    depth[h] += st.feature_depth > 0.f ? st.feature_depth : far;
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
      film->albedo_even[3 * pixel + c] = n[0] ? albedo[0][c] / float(n[0]) : 0.f;
      film->albedo_odd[3 * pixel + c] = n[1] ? albedo[1][c] / float(n[1]) : 0.f;
      film->normal_even[3 * pixel + c] = n[0] ? normal[0][c] / float(n[0]) : 0.f;
      film->normal_odd[3 * pixel + c] = n[1] ? normal[1][c] / float(n[1]) : 0.f;
    }
    film->depth_even[pixel] = n[0] ? depth[0] / float(n[0]) : 0.f;
    film->depth_odd[pixel] = n[1] ? depth[1] / float(n[1]) : 0.f;
  }
};

}  // namespace sg::path_detail
