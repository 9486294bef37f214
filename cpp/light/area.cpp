// Area lights from emissive triangles, sampled by area x radiance luminance.
#include <algorithm>

#include "core/error.h"
#include "core/sampling.h"
#include "light/light.h"

namespace sg {

AreaLight::AreaLight(uint32_t inst, uint32_t prim_count, std::vector<EmissiveTriangle> tris)
    : m_inst(inst), m_tris(std::move(tris)), m_area_pdf(prim_count, 0.f) {
  std::vector<double> w(m_tris.size());
  double total = 0.0;
  for (size_t i = 0; i < m_tris.size(); ++i) {
    const auto& t = m_tris[i];
    double area = 0.5 * length(cross(t.p1 - t.p0, t.p2 - t.p0));
    float lum = std::max(luminance(t.material->average_emission()), 1e-6f);
    w[i] = area * lum;
    total += w[i];
    double sides = t.material->two_sided_emission() ? 2.0 : 1.0;
    m_tris[i].uniform = t.material->uniform_emission();
    m_tris[i].two_sided = t.material->two_sided_emission();
    m_tris[i].uniform_le = t.material->average_emission();
    m_power += float(k_pi * sides * area * lum);
  }
  if (!(total > 0.0)) throw Error("area light of instance " + std::to_string(inst) + " has zero area");
  m_cdf.resize(m_tris.size());
  double acc = 0.0;
  for (size_t i = 0; i < m_tris.size(); ++i) {
    acc += w[i];
    m_cdf[i] = float(acc / total);
    double area = 0.5 * length(cross(m_tris[i].p1 - m_tris[i].p0, m_tris[i].p2 - m_tris[i].p0));
    // pmf(tri) / area(tri) = luminance / total
    m_area_pdf[m_tris[i].prim] = float((w[i] / total) / area);
  }
  m_cdf.back() = 1.f;
}

bool AreaLight::bounding_sphere(Vec3f* centre, float* radius) const {
  Bounds3 b;
  for (const auto& t : m_tris) {
    b.expand(t.p0);
    b.expand(t.p1);
    b.expand(t.p2);
  }
  *centre = 0.5f * (b.lo + b.hi);
  *radius = b.radius();
  return true;
}

bool AreaLight::normal_cone(Vec3f* axis, float* half_angle) const {
  Vec3f sum(0.f);
  for (const auto& t : m_tris) {
    if (t.two_sided) return false;
    sum += t.n;
  }
  if (!(dot(sum, sum) > 0.f)) return false;
  *axis = normalize(sum);
  float cos_min = 1.f;
  for (const auto& t : m_tris) cos_min = std::min(cos_min, dot(*axis, t.n));
  *half_angle = std::acos(std::max(-1.f, std::min(1.f, cos_min)));
  return true;
}

bool AreaLight::sample(const LightSampleContext& ctx, const Vec2f& u_in, LightSample* out) const {
  // Pick a triangle, reusing the remapped first coordinate for the point.
  float ux = u_in.x;
  size_t i = size_t(std::upper_bound(m_cdf.begin(), m_cdf.end(), ux) - m_cdf.begin());
  i = std::min(i, m_tris.size() - 1);
  float lo = i ? m_cdf[i - 1] : 0.f, hi = m_cdf[i];
  ux = hi > lo ? std::min((ux - lo) / (hi - lo), k_one_minus_epsilon) : 0.f;
  const EmissiveTriangle& t = m_tris[i];
  Vec2f b = square_to_uniform_triangle({ux, u_in.y});
  float b0 = 1.f - b.x - b.y;
  Vec3f p = t.p0 * b0 + t.p1 * b.x + t.p2 * b.y;
  Vec3f d = p - ctx.p;
  float dist2 = length_squared(d);
  if (!(dist2 > 0.f)) return false;
  float dist = std::sqrt(dist2);
  Vec3f wi = d / dist;
  float cos_l = -dot(t.n, wi);
  Color le(0.f);
  if (t.uniform) {
    if (t.two_sided || cos_l > 0.f) le = t.uniform_le;
  } else {
    SurfaceInteraction si;
    si.p = p;
    si.ng = t.n;
    si.ns = t.n;
    si.uv = t.uv0 * b0 + t.uv1 * b.x + t.uv2 * b.y;
    si.inst = m_inst;
    si.prim = t.prim;
    le = t.material->emission(si, -wi);
  }
  if (is_black(le) || cos_l == 0.f) return false;
  out->wi = wi;
  out->li = le;
  out->pdf = m_area_pdf[t.prim] * dist2 / std::fabs(cos_l);
  out->p_light = p;
  out->p_light_error = Vec3f(t.p_error);
  out->n_light = t.n;
  out->delta = false;
  out->infinite = false;
  return std::isfinite(out->pdf) && out->pdf > 0.f;
}

}  // namespace sg
