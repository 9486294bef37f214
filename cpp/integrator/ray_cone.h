// Ray cones for texture level of detail: every path carries a cone (width, spread
// angle) whose footprint on a hit triangle, mapped to texture space, is the filter width
// of the texture lookups there (SurfaceInteraction::uv_footprint).
//
// NOTE: Akenine-Moller, Nilsson, Andersson, Barre-Brisebois, Toth, Karras, "Texture
// Level of Detail Strategies for Real-Time Ray Tracing", Ray Tracing Gems ch. 20, 2019,
// sec. 20.3.4 (equation numbers of the chapter):
//  - camera spread angle gamma_0 = arctan(2 tan(psi/2) / H) (eq. (30)); for a pinhole with
//    focal length f pixels 2 tan(psi/2) / H = 1/f, so gamma_0 = arctan(1/f);
//  - propagation w_i = w_{i-1} + gamma_{i-1} t_i, gamma_i = gamma_{i-1} + beta_i (eq. (29));
//  - footprint: lambda = Delta + log2|w_i| - log2|n.d| (eq. (34)) with the triangle LOD
//    Delta = 0.5 log2(t_a / p_a) (texture-space over world-space triangle area); without
//    the log and the texture resolution (applied by the texture itself, mipmap.h), the
//    uv-space width is w_i / |n.d| * sqrt(uv area / world area).
// Beyond the chapter, the footprint is also given as an ellipse (minor axis w across the
// ray, major axis w / |n.d| along it, mapped to uv exactly) so that image textures filter
// anisotropically: the isotropic width over-blurs surfaces seen at grazing angles by
// 1/|n.d| across the ray.
#pragma once

#include <algorithm>
#include <cmath>

#include "camera/camera.h"
#include "integrator/render_scene.h"
#include "material/material.h"

namespace sg {

/// Full cone angle of one pixel at the principal point (eq. (30)); with fx != fy the
/// larger of the two pixel angles (the cone is isotropic, so the conservative one).
inline float pixel_spread_angle(const PinholeCamera& camera) {
  return std::atan(1.f / std::min(camera.fx, camera.fy));
}

/// World-space edges and uv edges of triangle `prim` of `inst` (after the instance
/// transform), read once per hit and shared by the footprint computations below. Meshes
/// without uvs use the barycentric parameterization (uv edges (1, 0) and (0, 1)).
struct ConeTriangle {
  Vec3f e1, e2;
  Vec2f u1{1.f, 0.f}, u2{0.f, 1.f};
};

inline ConeTriangle cone_triangle(const InstanceRecord& inst, uint32_t prim) {
  const TriangleMesh& m = *inst.mesh;
  // A user shape has no triangle: a degenerate one (no uv footprint; the world footprint of
  // 3D procedural textures is still known).
  if (m.shape) return ConeTriangle{Vec3f(0.f), Vec3f(0.f), Vec2f(0.f, 0.f), Vec2f(0.f, 0.f)};
  uint32_t i0 = m.indices[3 * prim], i1 = m.indices[3 * prim + 1], i2 = m.indices[3 * prim + 2];
  const Transform& T = inst.world_from_object;
  ConeTriangle t;
  t.e1 = T.apply_vector(m.positions[i1] - m.positions[i0]);
  t.e2 = T.apply_vector(m.positions[i2] - m.positions[i0]);
  if (!m.uvs.empty()) {
    t.u1 = m.uvs[i1] - m.uvs[i0];
    t.u2 = m.uvs[i2] - m.uvs[i0];
  }
  return t;
}

/// Maps world-space vectors in a triangle's plane to uv through its affine
/// parameterization v = alpha e1 + beta e2 -> alpha duv1 + beta duv2 (exact for any, also
/// stretched, uv mapping). `valid` is false for a degenerate triangle.
/// NOTE: pbrt-v4 sec. 6.5.3 solves the same 2 x 2 system for dp/du, dp/dv; here its normal
/// equations (the Gram matrix of e1, e2) by Cramer's rule.
struct TriangleUvMap {
  explicit TriangleUvMap(const ConeTriangle& t)
      : tri(t), g11(dot(t.e1, t.e1)), g12(dot(t.e1, t.e2)), g22(dot(t.e2, t.e2)), det(g11 * g22 - g12 * g12) {}
  bool valid() const { return det > 0.f; }
  Vec2f operator()(const Vec3f& v) const {
    float r1 = dot(tri.e1, v), r2 = dot(tri.e2, v);
    float alpha = (g22 * r1 - g12 * r2) / det, beta = (g11 * r2 - g12 * r1) / det;
    return tri.u1 * alpha + tri.u2 * beta;
  }
  const ConeTriangle& tri;
  float g11, g12, g22, det;
};

/// sqrt(uv area / world area) of the triangle (uv area 1/2 without uvs). Returns 0 for a
/// degenerate uv mapping (the lookup is then a point sample).
inline float uv_per_world_length(const ConeTriangle& t) {
  float world2 = length(cross(t.e1, t.e2));
  float uv2 = std::fabs(t.u1.x * t.u2.y - t.u1.y * t.u2.x);  // twice the uv area
  float r = std::sqrt(uv2 / world2);
  return std::isfinite(r) ? r : 0.f;
}
inline float uv_per_world_length(const InstanceRecord& inst, uint32_t prim) {
  return uv_per_world_length(cone_triangle(inst, prim));
}

/// Texture-space footprint width of a cone of width `cone_width` arriving along unit
/// direction `d` on a surface with geometric normal `ng` (eq. (34) without the log).
inline float ray_cone_uv_footprint(float cone_width, const Vec3f& ng, const Vec3f& d, float uv_per_world) {
  if (!(uv_per_world > 0.f) || !(cone_width > 0.f)) return 0.f;
  float cos_theta = std::fabs(dot(ng, d));
  // Exactly grazing: infinite footprint, i.e. the texture average (mipmap top level).
  return cos_theta > 0.f ? cone_width * uv_per_world / cos_theta : k_inf;
}

/// The cone's footprint ellipse on the triangle's plane, mapped to uv space: conjugate
/// axes (full widths) `axis_a` (major: w / |n.d| along the projection of d on the plane)
/// and `axis_b` (minor: w across). Returns false when there is none (head-on degenerate
/// uv mapping, exactly grazing ray).
/// NOTE: the cone of width w cut by a plane at incidence theta is an ellipse with axes w
/// and w / cos(theta) (the anisotropic counterpart of eq. (34)'s 1/|n.d| term); world
/// tangent vectors are mapped to uv by TriangleUvMap.
inline bool ray_cone_uv_ellipse(const ConeTriangle& tri, const Vec3f& ng, const Vec3f& d, float cone_width,
                                Vec2f* axis_a, Vec2f* axis_b) {
  float cos_theta = std::fabs(dot(ng, d));
  if (!(cone_width > 0.f) || !(cos_theta > 1e-6f)) return false;
  const TriangleUvMap to_uv(tri);
  if (!to_uv.valid()) return false;
  Vec3f dp = d - ng * dot(d, ng);  // projection of the ray direction on the plane
  float lp = length(dp);
  Vec3f ta = lp > 1e-6f ? dp / lp : tri.e1 / std::sqrt(to_uv.g11);  // head-on: any tangent
  Vec3f tb = cross(ng, ta);
  *axis_a = to_uv(ta * (cone_width / cos_theta));
  *axis_b = to_uv(tb * cone_width);
  return std::isfinite(axis_a->x) && std::isfinite(axis_a->y) && std::isfinite(axis_b->x) &&
         std::isfinite(axis_b->y);
}
inline bool ray_cone_uv_ellipse(const InstanceRecord& inst, uint32_t prim, const Vec3f& ng, const Vec3f& d,
                                float cone_width, Vec2f* axis_a, Vec2f* axis_b) {
  return ray_cone_uv_ellipse(cone_triangle(inst, prim), ng, d, cone_width, axis_a, axis_b);
}

/// Sets the texture footprint of `si` (hit of triangle `prim` of `inst` along unit
/// direction `d`) for a cone of width `cone_width` there: the isotropic width of eq. (34)
/// and the anisotropic ellipse.
inline void set_ray_cone_footprint(SurfaceInteraction* si, const InstanceRecord& inst, uint32_t prim, const Vec3f& d,
                                   float cone_width) {
  ConeTriangle tri = cone_triangle(inst, prim);
  si->uv_footprint = ray_cone_uv_footprint(cone_width, si->ng, d, uv_per_world_length(tri));
  if (!ray_cone_uv_ellipse(tri, si->ng, d, cone_width, &si->uv_axis_a, &si->uv_axis_b))
    si->uv_axis_a = si->uv_axis_b = Vec2f(0.f, 0.f);
}

/// Spread angle beta added by a BSDF-sampled bounce.
/// NOTE: the chapter (sec. 20.3.4) only treats perfect reflection, where beta comes from
/// the surface curvature; triangles are flat, so a Dirac (delta) bounce adds nothing here
/// (exact for planar mirrors and glass, too narrow on curved ones: the curvature term is
/// not implemented). For a non-delta lobe the sampled direction stands for a solid angle
/// of about 1/pdf (the footprint of a sampled direction in Suykens & Willems, "Path
/// Differentials and Applications", EGWR 2001, sec. 4); the full angle of a cone of that
/// solid angle is 2 / sqrt(pi pdf) (small-angle cone, Omega = pi (alpha/2)^2). It is
/// clamped to pi/8, the spread a fully rough (diffuse) bounce adds in Unity HDRP's path
/// tracer (roughnessToSpreadAngle = roughness pi/8): diffuse bounces get a wide cone, so
/// textures seen only indirectly are filtered strongly (little variance, slight blur);
/// sharp glossy lobes (pdf >> 1) keep narrow cones.
inline float bsdf_spread_angle(const BsdfSample& bs) {
  constexpr float k_max_spread = k_pi / 8.f;
  if (bs.flags & k_bsdf_delta) return 0.f;
  if (!(bs.pdf > 0.f)) return k_max_spread;
  return std::min(k_max_spread, 2.f / std::sqrt(k_pi * bs.pdf));
}

/// NOTE: with spp samples per pixel each camera sample stands for a sub-pixel of width
/// 1/sqrt(spp); pbrt-v4 scales its camera ray differentials the same way, by
/// max(1/8, 1/sqrt(spp)) (Pharr, Jakob, Humphreys 2023, RayIntegrator::EvaluatePixelSample).
/// The pixel box filter then does the rest of the antialiasing.
inline float camera_sample_spread_scale(uint32_t spp) {
  return std::max(0.125f, 1.f / std::sqrt(float(std::max<uint32_t>(spp, 1))));
}

/// Isotropic filter width on the surface for a ray cone of width `cone_width`, for 3D
/// procedural textures (which have no anisotropic lookup).
/// NOTE: a cone hitting a plane at angle theta to the normal leaves an ellipse with axes
/// width and width / |cos theta| (Akenine-Moeller et al. 2021, "Improved Shader and Texture
/// Level of Detail Using Ray Cones", sec. 3). The major axis removes detail still resolved
/// along the minor one (over-blurring grazing surfaces), the minor axis lets the major
/// direction alias; their geometric mean width / sqrt|cos theta| (the radius of the circle
/// of equal area, as isotropic mip-mapping uses) balances the two. |cos| is clamped at 1e-4.
inline float surface_footprint(float cone_width, const Vec3f& dir, const Vec3f& ng) {
  return cone_width / std::sqrt(std::max(std::fabs(dot(dir, ng)), 1e-4f));
}

}  // namespace sg
