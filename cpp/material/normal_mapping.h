// Normal and bump mapping: perturb the shading frame of a SurfaceInteraction before a
// BSDF is evaluated. Used by "principled"; any material can call these helpers.
//
// Tangent space. The frame is (T, B, N) = (si.dpdu, ns x dpdu, si.ns). make_interaction
// (integrator/interaction.h) derives dpdu per triangle from the uv parameterization
// (pbrt-v4 sec. 6.5.3) and Gram-Schmidt-orthogonalizes it against the interpolated shading
// normal, so T follows increasing u and, for uv islands that are not mirrored, B = N x T
// follows increasing v. This is MikkTSpace's tangent with the bitangent sign +1, computed
// per triangle instead of averaged per vertex (so tangents are discontinuous across
// triangle edges where the uv mapping shears; MikkTSpace, Mikkelsen 2008, "Simulation of
// Wrinkled Surfaces Revisited", sec. 3, smooths them). Mirrored uv islands (negative
// bitangent sign) get a flipped green channel: a known limitation. Meshes without uvs get
// an arbitrary tangent (normal maps are then meaningless, but harmless).
//
// Conventions (glTF 2.0 spec, sec. 3.9.3 "normalTexture"): RGB in [0, 1] maps to
// [-1, 1]^3, +X along u (right), +Y along v (up; OpenGL convention: assimp flips glTF's v
// so that v = 0 is the bottom row, which is also how image textures are addressed), +Z
// along the normal; the scale multiplies X and Y:
//   n = normalize((2 rgb - 1) * (scale, scale, 1)).
#pragma once

#include <cmath>
#include <cstring>

#include "material/material.h"

namespace sg {

/// Replaces si.ns by the tangent-space direction `n_t` (not necessarily unit) and
/// re-orthonormalizes dpdu. The new normal is kept in the hemisphere of ng (at least
/// `k_min_cos` above the geometric surface): a normal map can tilt the shading normal past
/// the geometric horizon, which would make the BSDF's side tests (which use ng) and its
/// frame disagree for every direction.
/// NOTE: the same clamp-to-hemisphere fix as pbrt-v4's NormalMap()/FaceForward usage and
/// Blender Cycles' ensure_valid_reflection (Schuessler et al. 2017, "Microfacet-based
/// Normal Mapping for Robust Monte Carlo Path Tracing", sec. 2, describe the problem).
/// The world-space normal of tangent-space direction `n_t` in frame `f` at `si`, kept in the
/// hemisphere of ng as described above; returns si.ns when n_t is zero or not finite.
inline Vec3f perturbed_normal(const SurfaceInteraction& si, const Frame& f, const Vec3f& n_t) {
  constexpr float k_min_cos = 1e-3f;
  float len = length(n_t);
  if (!(len > 0.f) || !std::isfinite(len)) return si.ns;
  Vec3f n = f.to_world(n_t / len);
  float c = dot(n, si.ng);
  if (c < k_min_cos) {
    // Move n towards ng until it lies k_min_cos above the geometric plane.
    Vec3f tangential = n - si.ng * c;
    float tl = length(tangential);
    if (tl > 0.f) n = tangential / tl * std::sqrt(1.f - k_min_cos * k_min_cos) + si.ng * k_min_cos;
    else n = si.ng;
  }
  return normalize(n);
}

inline void apply_tangent_normal(SurfaceInteraction* si, Vec3f n_t) {
  float len = length(n_t);
  if (!(len > 0.f) || !std::isfinite(len)) return;
  Vec3f n = perturbed_normal(*si, si->shading_frame(), n_t);
  // Gram-Schmidt: the tangent keeps following u as closely as possible.
  Vec3f t = si->dpdu - n * dot(n, si->dpdu);
  float tl = length(t);
  si->ns = n;
  si->dpdu = (tl > 1e-6f && std::isfinite(tl)) ? t / tl : Frame(n).s;
}

/// Tangent-space normal from a normal-map texel (linear RGB, glTF convention).
inline Vec3f decode_normal_texel(const Color& rgb, float scale) {
  return Vec3f((2.f * rgb.x - 1.f) * scale, (2.f * rgb.y - 1.f) * scale, 2.f * rgb.z - 1.f);
}

/// Normal mapping with a tangent-space normal texture.
inline void apply_normal_map(SurfaceInteraction* si, const Texture& normal_map, float scale) {
  apply_tangent_normal(si, decode_normal_texel(eval_texture(normal_map, *si), scale));
}

/// Bump mapping with a height texture (first channel), height in uv units times `scale`
/// (SurfaceInteraction carries the unit tangent only, not |dp/du|, so the height is
/// measured relative to the uv parameterization: a slope of 1 in uv tilts by 45 degrees).
/// The gradient is a central difference over half the ray footprint in uv, or over
/// `k_min_delta` (about one texel of a 2048^2 texture) when the footprint is smaller or
/// unknown; the lookups are filtered over the footprint so that the difference sees the
/// same band-limited height as the shading.
/// NOTE: Blinn 1978, "Simulation of Wrinkled Surfaces"; the displaced-surface normal
/// n' ~ n - (dh/du) T - (dh/dv) B for a locally orthonormal (u, v) parameterization
/// (pbrt-v4 sec. 10.5.2 BumpMap(), with its shift du = 0.5 (|dudx| + |dudy|), else 0.0005).
inline void apply_bump_map_uncached(SurfaceInteraction* si, const Texture& height, float scale);

/// Cache key of a bumped frame: a function of the point, the height and `scale`, kept in the
/// texture cache under keys next to the texture's address, the scale's bits as the tag.
inline const char* bump_cache_key(const Texture& height, float scale, int* tag) {
  std::memcpy(tag, &scale, sizeof(*tag));
  return reinterpret_cast<const char*>(&height);
}

/// The slopes (dh/ds, dh/dt) of a 3D height along frame f's tangents, from the texture's
/// analytic gradient; false when it has none (or no instance transform is known).
inline bool analytic_height_slopes(const SurfaceInteraction& si, const Texture& height, const Frame& f, float* dhds,
                                   float* dhdt) {
  Vec3f g;
  bool world_space;
  if (!height.needs_position() || !si.world_from_object || !height.eval_gradient(texture_point(si), &g, &world_space))
    return false;
  auto along = [&](const Vec3f& dir) {
    return dot(g, world_space ? dir : si.world_from_object->apply_inverse_vector(dir));
  };
  *dhds = along(f.s);
  *dhdt = along(f.t);
  return true;
}

inline void apply_bump_map(SurfaceInteraction* si, const Texture& height, float scale) {
  // The bumped frame is computed once per hit (bump_cache_key).
  int tag;
  const char* key = bump_cache_key(height, scale, &tag);
  Color ns, dpdu;
  if (si->tex_cache.find(key + 1, tag, &ns) && si->tex_cache.find(key + 2, tag, &dpdu)) {
    si->ns = ns;
    si->dpdu = dpdu;
    return;
  }
  apply_bump_map_uncached(si, height, scale);
  si->tex_cache.put(key + 1, tag, si->ns);
  si->tex_cache.put(key + 2, tag, si->dpdu);
}

inline void apply_bump_map_uncached(SurfaceInteraction* si, const Texture& height, float scale) {
  // The gradient is a function of the point: computed once per hit (tag 1 of the cache).
  Color g;
  if (si->tex_cache.find(&height, 1, &g)) {
    apply_tangent_normal(si, Vec3f(-scale * g.x, -scale * g.y, 1.f));
    return;
  }
  if (height.needs_position() && si->world_from_object) {
    // Analytic gradient when the texture has one (procedural noise): one evaluation.
    Frame f = si->shading_frame();
    float dhds, dhdt;
    if (analytic_height_slopes(*si, height, f, &dhds, &dhdt)) {
      si->tex_cache.put(&height, 1, Color(dhds, dhdt, 0.f));
      apply_tangent_normal(si, Vec3f(-scale * dhds, -scale * dhdt, 1.f));
      return;
    }
    // Procedural heights over 3D mappings: a central difference along the shading
    // tangents in world space (height and `scale` in world units: a slope of 1 per metre
    // tilts by 45 degrees), over half the world footprint or 0.1 mm, with p_object moved
    // by the same offset through the instance transform.
    float d = std::max(0.5f * si->world_footprint, 1e-4f);
    auto h = [&](const Vec3f& dir, float sgn) {
      SurfaceInteraction q = *si;
      q.tex_cache.clear();  // another point
      Vec3f dw = dir * (sgn * d);
      q.p = si->p + dw;
      q.p_object = si->p_object + si->world_from_object->apply_inverse_vector(dw);
      return eval_texture(height, q).x;
    };
    dhds = (h(f.s, 1.f) - h(f.s, -1.f)) / (2.f * d);
    dhdt = (h(f.t, 1.f) - h(f.t, -1.f)) / (2.f * d);
    si->tex_cache.put(&height, 1, Color(dhds, dhdt, 0.f));
    apply_tangent_normal(si, Vec3f(-scale * dhds, -scale * dhdt, 1.f));
    return;
  }
  constexpr float k_min_delta = 0.0005f;
  float d = std::max(0.5f * si->uv_footprint, k_min_delta);
  float fp = si->uv_footprint;
  auto h = [&](float du, float dv) { return height.eval(Vec2f(si->uv.x + du, si->uv.y + dv), fp).x; };
  float dhdu = (h(d, 0.f) - h(-d, 0.f)) / (2.f * d);
  float dhdv = (h(0.f, d) - h(0.f, -d)) / (2.f * d);
  si->tex_cache.put(&height, 1, Color(dhdu, dhdv, 0.f));
  apply_tangent_normal(si, Vec3f(-scale * dhdu, -scale * dhdv, 1.f));
}

/// The bump-mapped shading normal (what apply_bump_map leaves in si.ns) without touching
/// `si`: computed once per hit (kept in si.tex_cache under apply_bump_map's key). Heights
/// over 3D mappings with an analytic gradient take the direct route: the gradient's
/// component in the tangent plane of any frame around ns (no uv tangent needed, no copy of
/// the interaction); a zero gradient (all octaves faded by the footprint) leaves ns as is.
inline Vec3f bump_normal(const SurfaceInteraction& si, const Texture& height, float scale) {
  int tag;
  const char* key = bump_cache_key(height, scale, &tag);
  Color cached;
  if (si.tex_cache.find(key + 1, tag, &cached)) return cached;
  Vec3f n;
  const Frame f = si.shading_frame();
  float dhds, dhdt;
  if (analytic_height_slopes(si, height, f, &dhds, &dhdt)) {
    n = (dhds == 0.f && dhdt == 0.f) ? si.ns : perturbed_normal(si, f, Vec3f(-scale * dhds, -scale * dhdt, 1.f));
  } else {
    SurfaceInteraction b = si;
    apply_bump_map_uncached(&b, height, scale);
    n = b.ns;
  }
  si.tex_cache.put(key + 1, tag, n);
  return n;
}

}  // namespace sg
