// Builds the SurfaceInteraction of a ray hit and spawns rays off surfaces robustly.
#pragma once

#include <cmath>
#include <cstring>

#include "integrator/render_scene.h"

namespace sg {

/// The next float above v when `dir` > 0, below it when `dir` < 0 (pbrt-v4 NextFloatUp /
/// NextFloatDown: a zero steps to the smallest subnormal of that sign, an infinity of that sign
/// stays), else v; without branches.
/// NOTE: the sign of an offset component depends on the surface and the new direction, so pbrt's
/// two branching functions (this file's before) mispredicted often (a profile of the Cornell
/// box); here they are selects (both steps computed, one kept): conditional moves.
inline float next_float_away(float v, float dir) {
  uint32_t ui;
  std::memcpy(&ui, &v, 4);
  const bool zero = v == 0.f;
  const uint32_t up = zero ? 1u : (v >= 0.f ? ui + 1u : ui - 1u);
  const uint32_t down = zero ? 0x80000001u : (v > 0.f ? ui - 1u : ui + 1u);
  uint32_t r = dir > 0.f ? (v == k_inf ? ui : up) : ui;
  r = dir < 0.f ? (v == -k_inf ? ui : down) : r;
  float out;
  std::memcpy(&out, &r, 4);
  return out;
}

/// NOTE: floating-point error bounds follow pbrt-v4 (Pharr, Jakob, Humphreys 2023),
/// sec. 6.8: gamma(n) = n u / (1 - n u), u = 2^-24.
constexpr float gamma_n(int n) { return (n * 0x1p-24f) / (1 - n * 0x1p-24f); }

/// The interaction of a hit on a user shape (TriangleMesh::shape): the point along the world
/// ray, the shape's normal and surface coordinates from the hit.
inline SurfaceInteraction make_shape_interaction(const InstanceRecord& inst, const RayHit& hit, const Ray& ray) {
  const Transform& T = inst.world_from_object;
  SurfaceInteraction si;
  si.p = ray.o + ray.d * hit.t;
  si.p_object = T.apply_inverse_point(si.p);
  float l = length(hit.ng);
  si.n_object = l > 0.f && std::isfinite(l) ? hit.ng / l : Vec3f(0.f, 0.f, 1.f);
  si.ng = normalize(T.apply_normal(si.n_object));
  si.ns = si.ng;
  // NOTE: the hit point is as exact as the shape's routine (sphere tracing stops at a
  // tolerance): its error is taken as 1e-5 of the shape's world-space size plus the
  // rounding of o + t d (pbrt-v4 sec. 6.8.5 style, gamma(7) of the largest coordinate),
  // which the shapes of synthgen_ext.h must stay within.
  Vec3f ext = inst.object_hi - inst.object_lo;
  float size = max_component(ext) / std::max(inst.object_per_world, 1e-20f);
  si.p_error = Vec3f(1e-5f * size + gamma_n(7) * max_component(vabs(si.p)));
  si.uv = Vec2f(hit.u, hit.v);
  si.dpdu = Frame(si.ns).s;
  si.inst = hit.inst;
  si.prim = hit.prim;
  si.object_lo = inst.object_lo;
  si.object_hi = inst.object_hi;
  si.object_per_world = inst.object_per_world;
  si.world_from_object = &inst.world_from_object;
  return si;
}

/// `need_tangent` = false skips dpdu (left zero) for materials that do not read it. `ray` is
/// the ray that found the hit (read for user shapes only).
inline SurfaceInteraction make_interaction(const InstanceRecord& inst, const RayHit& hit, const Ray& ray,
                                           bool need_tangent = true) {
  const TriangleMesh& m = *inst.mesh;
  if (m.shape) return make_shape_interaction(inst, hit, ray);
  uint32_t i0 = m.indices[3 * hit.prim], i1 = m.indices[3 * hit.prim + 1], i2 = m.indices[3 * hit.prim + 2];
  const Vec3f &p0 = m.positions[i0], &p1 = m.positions[i1], &p2 = m.positions[i2];
  float b1 = hit.u, b2 = hit.v, b0 = 1.f - b1 - b2;
  Vec3f po = p0 * b0 + p1 * b1 + p2 * b2;
  const Transform& T = inst.world_from_object;
  SurfaceInteraction si;
  si.p = T.apply_point(po);
  // NOTE: error bound of the hit point. pbrt-v4 (sec. 6.8.5, eq. 6.31-6.32) bounds the
  // barycentric interpolation by gamma(7) sum|b_i p_i| and the affine transform by
  // gamma(3)(|M||p| + |t|) per axis. Embree's watertight test and its transformation of
  // the ray into instance space make errors of the order of the *largest* coordinate of
  // the triangle on every axis (an axis-aligned plane at y = 0 still has errors from x and
  // z), so the bound is taken as gamma(7) (||M||_inf max_i |p_i|_inf + |t|_inf) on every
  // axis, with the matrix terms precomputed per instance (InstanceRecord::error_scale).
  float max_abs = max_component(vmax(vabs(p0), vmax(vabs(p1), vabs(p2))));
  si.p_error = Vec3f(inst.error_scale * max_abs + inst.error_offset);
  Vec3f ng_o = cross(p1 - p0, p2 - p0);
  si.ng = normalize(T.apply_normal(ng_o));
  {
    float l = length(ng_o);
    si.n_object = l > 0.f ? ng_o / l : Vec3f(0.f, 0.f, 1.f);
  }
  if (!m.normals.empty()) {
    Vec3f ns_o = m.normals[i0] * b0 + m.normals[i1] * b1 + m.normals[i2] * b2;
    {
      float l = length(ns_o);
      if (l > 0.f && std::isfinite(l)) si.n_object = ns_o / l;
    }
    Vec3f ns = T.apply_normal(ns_o);
    float l = length(ns);
    if (l > 0.f && std::isfinite(l)) {
      ns = ns / l;
      // Authored normals decide the front side: orient the geometric normal to them.
      if (dot(ns, si.ng) < 0.f) si.ng = -si.ng;
      si.ns = ns;
    } else {
      si.ns = si.ng;
    }
  } else {
    si.ns = si.ng;
  }
  Vec3f dpdu_o(0.f);
  bool has_dpdu = false;
  si.inst = hit.inst;
  si.prim = hit.prim;
  si.p_object = po;
  si.object_lo = inst.object_lo;
  si.object_hi = inst.object_hi;
  si.object_per_world = inst.object_per_world;
  si.world_from_object = &inst.world_from_object;
  if (!need_tangent) {
    si.uv = m.uvs.empty() ? Vec2f(b1, b2) : m.uvs[i0] * b0 + m.uvs[i1] * b1 + m.uvs[i2] * b2;
    si.dpdu = Vec3f(0.f);
    return si;
  }
  if (!m.uvs.empty()) {
    si.uv = m.uvs[i0] * b0 + m.uvs[i1] * b1 + m.uvs[i2] * b2;
    // NOTE: dp/du from the triangle's uv parameterization (pbrt-v4 sec. 6.5.3):
    // [dp02 dp12] = [duv02 duv12] [dpdu dpdv]^T, solved by Cramer's rule.
    Vec2f duv02 = m.uvs[i0] - m.uvs[i2], duv12 = m.uvs[i1] - m.uvs[i2];
    float det = duv02.x * duv12.y - duv02.y * duv12.x;
    if (std::fabs(det) > 1e-12f) {
      Vec3f dp02 = p0 - p2, dp12 = p1 - p2;
      dpdu_o = (dp02 * duv12.y - dp12 * duv02.y) / det;
      has_dpdu = is_finite(dpdu_o) && length_squared(dpdu_o) > 0.f;
    }
  } else {
    si.uv = Vec2f(b1, b2);
  }
  // Unit tangent orthogonal to the shading normal (Gram-Schmidt); any tangent if none.
  Vec3f t = has_dpdu ? T.apply_vector(dpdu_o) : Vec3f(0.f);
  t = t - si.ns * dot(si.ns, t);
  float tl = length(t);
  si.dpdu = (tl > 1e-12f && std::isfinite(tl)) ? t / tl : Frame(si.ns).s;
  si.inst = hit.inst;
  si.prim = hit.prim;
  return si;
}

/// The alpha test of candidate hits (geometry/accel.h AlphaTest; `user` is the RenderScene):
/// false where the hit's material is cut out (Material::alpha_opaque). Only `uv`, `inst` and
/// `prim` of the interaction are set, uv interpolated exactly as make_interaction does.
inline bool alpha_test_hit(const void* user, uint32_t inst_slot, uint32_t prim, float u, float v) {
  const RenderScene& sc = *static_cast<const RenderScene*>(user);
  const InstanceRecord& inst = sc.instances[inst_slot];
  const Material* mat = sc.material_of(inst, prim);
  if (!mat->has_alpha()) return true;
  const TriangleMesh& m = *inst.mesh;
  SurfaceInteraction si;
  if (!m.uvs.empty() && !m.shape) {
    uint32_t i0 = m.indices[3 * prim], i1 = m.indices[3 * prim + 1], i2 = m.indices[3 * prim + 2];
    si.uv = m.uvs[i0] * (1.f - u - v) + m.uvs[i1] * u + m.uvs[i2] * v;
  } else {
    si.uv = Vec2f(u, v);
  }
  si.inst = inst_slot;
  si.prim = prim;
  return mat->alpha_opaque(si);
}

/// Error bound of points sampled on an emissive triangle: the hit-point bound of
/// make_interaction (object-space vertices o0..o2 through the instance transform) plus the
/// barycentric interpolation of the world-space vertices w0..w2 (pbrt-v4 sec. 6.8.5).
inline float emissive_triangle_error(const InstanceRecord& inst, const Vec3f& o0, const Vec3f& o1, const Vec3f& o2,
                                     const Vec3f& w0, const Vec3f& w1, const Vec3f& w2) {
  float obj = max_component(vmax(vabs(o0), vmax(vabs(o1), vabs(o2))));
  float world = max_component(vmax(vabs(w0), vmax(vabs(w1), vabs(w2))));
  return inst.error_scale * obj + inst.error_offset + gamma_n(7) * world;
}

/// Offsets a ray origin along the geometric normal beyond the error bound of `p`,
/// to the side of direction `w`.
/// NOTE: pbrt-v4 OffsetRayOrigin (sec. 6.8.6), with a safety factor of 4 covering
/// Embree's own transformation of the ray into instance space.
inline Vec3f offset_ray_origin(const Vec3f& p, const Vec3f& p_error, const Vec3f& n, const Vec3f& w) {
  float d = 4.f * dot(vabs(n), p_error);
  Vec3f offset = n * d;
  if (dot(w, n) < 0.f) offset = -offset;
  Vec3f po = p + offset;
  for (int i = 0; i < 3; ++i) po[i] = next_float_away(po[i], offset[i]);
  return po;
}

inline Ray spawn_ray(const SurfaceInteraction& si, const Vec3f& d) {
  Ray r;
  r.o = offset_ray_origin(si.p, si.p_error, si.ng, d);
  r.d = d;
  r.t_max = k_inf;
  return r;
}

/// NOTE: pbrt-v4 ShadowEpsilon: the shadow ray stops just short of the light point.
constexpr float k_shadow_epsilon = 1e-4f;

}  // namespace sg
