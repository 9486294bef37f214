// GGX (Trowbridge-Reitz) microfacet distribution and Fresnel terms, shared by the
// microfacet materials (conductor, dielectric, coated, principled).
// All directions are in the local shading frame (z = shading normal).
#pragma once

#include <algorithm>
#include <cmath>

#include "core/math.h"
#include "core/sampling.h"
#include "material/material.h"

namespace sg {

/// Anisotropic GGX distribution with roughness alpha_x, alpha_y (alpha = roughness^2 in
/// the usual perceptual parameterization).
struct GGX {
  float ax, ay;

  GGX(float alpha_x, float alpha_y) : ax(std::max(alpha_x, 1e-4f)), ay(std::max(alpha_y, 1e-4f)) {}

  /// True when no axis is rougher than k_sharp_roughness (Material::specular_events).
  bool sharp() const { return std::max(ax, ay) <= k_sharp_roughness * k_sharp_roughness; }

  /// Normal distribution D(m).
  /// NOTE: Walter et al. 2007, "Microfacet Models for Refraction", eq. 33, anisotropic form
  /// D = 1 / (pi ax ay (x^2/ax^2 + y^2/ay^2 + z^2)^2) (Heitz 2014, eq. 85).
  float D(const Vec3f& m) const {
    if (m.z <= 0.f) return 0.f;
    float x = m.x / ax, y = m.y / ay;
    float d = x * x + y * y + m.z * m.z;
    return 1.f / (k_pi * ax * ay * d * d);
  }

  /// Smith Lambda for direction w. NOTE: Heitz 2014, "Understanding the Masking-Shadowing
  /// Function in Microfacet-Based BRDFs", eq. 86.
  float lambda(const Vec3f& w) const {
    float z2 = w.z * w.z;
    if (z2 == 0.f) return k_inf;
    float t = (ax * ax * w.x * w.x + ay * ay * w.y * w.y) / z2;
    return 0.5f * (-1.f + std::sqrt(1.f + t));
  }

  float G1(const Vec3f& w) const { return 1.f / (1.f + lambda(w)); }

  /// Height-correlated masking-shadowing G2 (Heitz 2014, eq. 99).
  float G2(const Vec3f& wo, const Vec3f& wi) const { return 1.f / (1.f + lambda(wo) + lambda(wi)); }

  /// Distribution of normals visible from wo: D_wo(m) = G1(wo) max(0, wo.m) D(m) / wo.z.
  float pdf_visible(const Vec3f& wo, const Vec3f& m) const {
    if (wo.z <= 0.f) return 0.f;
    float c = dot(wo, m);
    if (c <= 0.f) return 0.f;
    return G1(wo) * c * D(m) / wo.z;
  }

  /// Samples a visible normal for wo (wo.z > 0).
  /// NOTE: Heitz 2018, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4),
  /// Listing 1.
  Vec3f sample_visible(const Vec3f& wo, const Vec2f& u) const {
    // Section 3.2: transform the view direction to the hemisphere configuration.
    Vec3f vh = normalize(Vec3f(ax * wo.x, ay * wo.y, wo.z));
    // Section 4.1: orthonormal basis (with special case if cross product is zero).
    float lensq = vh.x * vh.x + vh.y * vh.y;
    Vec3f t1 = lensq > 0.f ? Vec3f(-vh.y, vh.x, 0.f) / std::sqrt(lensq) : Vec3f(1.f, 0.f, 0.f);
    Vec3f t2 = cross(vh, t1);
    // Section 4.2: parameterization of the projected area.
    float r = std::sqrt(u.x), sin_phi, cos_phi;
    sincos_2pi(u.y, &sin_phi, &cos_phi);
    float p1 = r * cos_phi;
    float p2 = r * sin_phi;
    float s = 0.5f * (1.f + vh.z);
    p2 = (1.f - s) * std::sqrt(std::max(0.f, 1.f - p1 * p1)) + s * p2;
    // Section 4.3: reprojection onto the hemisphere.
    Vec3f nh = t1 * p1 + t2 * p2 + vh * std::sqrt(std::max(0.f, 1.f - p1 * p1 - p2 * p2));
    // Section 3.4: transform the normal back to the ellipsoid configuration.
    return normalize(Vec3f(ax * nh.x, ay * nh.y, std::max(1e-6f, nh.z)));
  }
};

/// Perceptual roughness in [0, 1] to GGX alpha (alpha = roughness^2, Burley 2012).
inline float roughness_to_alpha(float roughness) { return roughness * roughness; }

/// Unpolarized Fresnel reflectance of a dielectric interface.
/// `cos_i` is the cosine on the incident side, `eta` = eta_transmitted / eta_incident.
/// Returns 1 for total internal reflection; `cos_t` receives the (positive) cosine of the
/// refracted direction. NOTE: exact Fresnel equations (e.g. pbrt-v4 eq. 9.5).
inline float fresnel_dielectric(float cos_i, float eta, float* cos_t = nullptr) {
  cos_i = std::min(std::max(cos_i, -1.f), 1.f);
  if (cos_i < 0.f) {
    eta = 1.f / eta;
    cos_i = -cos_i;
  }
  float sin2_t = (1.f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.f) {
    if (cos_t) *cos_t = 0.f;
    return 1.f;
  }
  float ct = std::sqrt(std::max(0.f, 1.f - sin2_t));
  if (cos_t) *cos_t = ct;
  float r_parl = (eta * cos_i - ct) / (eta * cos_i + ct);
  float r_perp = (cos_i - eta * ct) / (cos_i + eta * ct);
  return 0.5f * (r_parl * r_parl + r_perp * r_perp);
}

/// Unpolarized Fresnel reflectance of a conductor with complex IOR eta + i k (relative to
/// the outside medium), for one wavelength band.
/// NOTE: exact expression for a complex index, pbrt-v4 eq. 9.8 / sec. 9.4.2 (FrComplex).
inline float fresnel_conductor(float cos_i, float eta, float k) {
  cos_i = std::min(std::max(cos_i, 0.f), 1.f);
  float c2 = cos_i * cos_i, s2 = 1.f - c2;
  float eta2 = eta * eta, k2 = k * k;
  float t0 = eta2 - k2 - s2;
  float a2b2 = std::sqrt(std::max(0.f, t0 * t0 + 4.f * eta2 * k2));
  float a = std::sqrt(std::max(0.f, 0.5f * (a2b2 + t0)));
  float t1 = a2b2 + c2;
  float t2 = 2.f * cos_i * a;
  float rs = (t1 - t2) / (t1 + t2);
  float t3 = c2 * a2b2 + s2 * s2;
  float t4 = t2 * s2;
  float rp = rs * (t3 - t4) / (t3 + t4);
  return 0.5f * (rp + rs);
}

/// The three bands at once: a loop over 4 lanes (the fourth a copy of the third) of the
/// inlined one-band function, so that the compiler can evaluate the bands in one vector.
inline Color fresnel_conductor(float cos_i, const Color& eta, const Color& k) {
  const float e[4] = {eta.x, eta.y, eta.z, eta.z}, kk[4] = {k.x, k.y, k.z, k.z};
  float r[4];
  for (int i = 0; i < 4; ++i) r[i] = fresnel_conductor(cos_i, e[i], kk[i]);
  return {r[0], r[1], r[2]};
}

/// Shading frame (s = dpdu, t = ns x dpdu, n = ns) of a two-sided microfacet BSDF and the
/// side of wo relative to the geometric normal; false when wo lies in the geometric plane.
inline bool sided_frame(const SurfaceInteraction& si, const Vec3f& wo, Frame* f, float* side) {
  float c = dot(si.ng, wo);
  if (!(c != 0.f)) return false;
  *side = c > 0.f ? 1.f : -1.f;
  *f = si.shading_frame();
  return true;
}
/// The frame is mirrored (z -> -z) for wo below the surface: GGX is symmetric in x and y,
/// so anisotropy axes keep following dpdu on both faces.
inline Vec3f sided_to_local(const Frame& f, float side, const Vec3f& v) {
  Vec3f l = f.to_local(v);
  l.z *= side;
  return l;
}
inline Vec3f sided_to_world(const Frame& f, float side, const Vec3f& l) {
  return f.to_world(Vec3f(l.x, l.y, l.z * side));
}

/// Mirror reflection of w about n.
inline Vec3f reflect(const Vec3f& w, const Vec3f& n) { return n * (2.f * dot(w, n)) - w; }

/// Refraction of w (pointing away from the surface, on the side n points to) through a
/// surface with relative index eta (= eta_t / eta_i). Returns false on total internal
/// reflection.
inline bool refract(const Vec3f& w, const Vec3f& n, float eta, Vec3f* wt) {
  float cos_i = dot(n, w);
  float sin2_i = std::max(0.f, 1.f - cos_i * cos_i);
  float sin2_t = sin2_i / (eta * eta);
  if (sin2_t >= 1.f) return false;
  float cos_t = std::sqrt(1.f - sin2_t);
  *wt = -w / eta + n * (cos_i / eta - cos_t);
  return true;
}

}  // namespace sg
