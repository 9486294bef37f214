// Internal: the Lambertian lobe shared by "diffuse" and "emissive".
#pragma once

#include "core/sampling.h"
#include "material/material.h"

namespace sg::lambert {

/// The two normals the lobe reads: geometric `ng` and shading `ns` (bump-mapped or not).
struct Normals {
  Vec3f ng, ns;
  Normals(const SurfaceInteraction& si) : ng(si.ng), ns(si.ns) {}  // NOLINT: implicit
  Normals(const Vec3f& g, const Vec3f& s) : ng(g), ns(s) {}
};

/// Shading normal flipped to the side of `wo`; returns false when wo lies in the
/// surface plane.
inline bool oriented_normal(const Normals& si, const Vec3f& wo, Vec3f* n, float* side) {
  float c = dot(si.ng, wo);
  if (c == 0.f) return false;
  *side = c > 0.f ? 1.f : -1.f;
  *n = si.ns * *side;
  return true;
}

inline Color eval(const Normals& si, const Vec3f& wo, const Vec3f& wi, const Color& albedo) {
  Vec3f n;
  float side;
  if (!oriented_normal(si, wo, &n, &side)) return Color(0.f);
  // NOTE: reflection only, judged on the geometric normal too, so shading normals
  // cannot leak light through a surface (Veach 1997, sec. 5.3).
  if (dot(si.ng, wi) * side <= 0.f) return Color(0.f);
  float cos_i = dot(n, wi);
  return cos_i > 0.f ? albedo * (cos_i * k_inv_pi) : Color(0.f);
}

inline float pdf(const Normals& si, const Vec3f& wo, const Vec3f& wi) {
  Vec3f n;
  float side;
  if (!oriented_normal(si, wo, &n, &side)) return 0.f;
  if (dot(si.ng, wi) * side <= 0.f) return 0.f;
  float cos_i = dot(n, wi);
  return cos_i > 0.f ? cos_i * k_inv_pi : 0.f;
}

/// eval and pdf in one pass (they share the orientation tests and the cosine).
inline Color eval_pdf(const Normals& si, const Vec3f& wo, const Vec3f& wi, const Color& albedo,
                      float* pdf_out) {
  *pdf_out = 0.f;
  Vec3f n;
  float side;
  if (!oriented_normal(si, wo, &n, &side)) return Color(0.f);
  if (dot(si.ng, wi) * side <= 0.f) return Color(0.f);
  float cos_i = dot(n, wi);
  if (!(cos_i > 0.f)) return Color(0.f);
  *pdf_out = cos_i * k_inv_pi;
  return albedo * (cos_i * k_inv_pi);
}

inline bool sample(const Normals& si, const Vec3f& wo, const Vec2f& u, const Color& albedo,
                   BsdfSample* out) {
  Vec3f n;
  float side;
  if (!oriented_normal(si, wo, &n, &side)) return false;
  Vec3f local = square_to_cosine_hemisphere(u);
  if (local.z <= 0.f) return false;
  Vec3f wi = Frame(n).to_world(local);
  if (dot(si.ng, wi) * side <= 0.f) return false;
  out->wi = wi;
  out->pdf = local.z * k_inv_pi;
  out->weight = albedo;
  out->flags = k_bsdf_diffuse | k_bsdf_reflection;
  return true;
}

}  // namespace sg::lambert
