// Shapes of user extensions (ext/extension.h): geometric primitives given by a bounds and an
// intersection function in C, traced as Embree user geometry (geometry/accel.cpp).
#include <cmath>

#include "ext/extension.h"

namespace sg {

ExtensionShape::ExtensionShape(const sg_ext_shape& decl, std::vector<float> args, const std::string& source)
    : m_decl(decl), m_args(std::move(args)), m_name(decl.name),
      m_host("extension shape '" + std::string(decl.name) + "' (" + source + ")") {
  float lo[3] = {0.f, 0.f, 0.f}, hi[3] = {0.f, 0.f, 0.f};
  m_decl.bounds(m_args.data(), lo, hi);
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(lo[i]) || !std::isfinite(hi[i]) || !(lo[i] <= hi[i]))
      throw Error("extension shape '" + m_name + "' (" + source + "): bounds() gave an empty or non-finite box (" +
                  format_number(lo[0]) + ", " + format_number(lo[1]) + ", " + format_number(lo[2]) + ") - (" +
                  format_number(hi[0]) + ", " + format_number(hi[1]) + ", " + format_number(hi[2]) + ")");
  m_bounds.lo = Vec3f(lo[0], lo[1], lo[2]);
  m_bounds.hi = Vec3f(hi[0], hi[1], hi[2]);
}

bool ExtensionShape::intersect(const Vec3f& o, const Vec3f& d, float t_min, float t_max, float* t, Vec3f* n,
                               Vec2f* uv) const {
  sg_ext_ray r{{o.x, o.y, o.z}, {d.x, d.y, d.z}, t_min, t_max};
  sg_ext_hit h{0.f, {0.f, 0.f, 0.f}, {0.f, 0.f}};
  if (!m_decl.intersect(m_args.data(), &r, &h)) return false;
  float v[6] = {h.t, h.n[0], h.n[1], h.n[2], h.uv[0], h.uv[1]};
  float p[3] = {o.x + h.t * d.x, o.y + h.t * d.y, o.z + h.t * d.z};
  if (!m_host.check(v, 6, p)) return false;
  float l2 = h.n[0] * h.n[0] + h.n[1] * h.n[1] + h.n[2] * h.n[2];
  if (!(h.t > t_min && h.t < t_max) || !(l2 > 0.f)) {
    m_host.fail(!(l2 > 0.f) ? "intersect() returned a hit without a normal"
                            : "intersect() returned t = " + format_number(h.t) + " outside (" + format_number(t_min) +
                                  ", " + format_number(t_max) + ")");
    return false;
  }
  *t = h.t;
  *n = Vec3f(h.n[0], h.n[1], h.n[2]);
  *uv = Vec2f(h.uv[0], h.uv[1]);
  return true;
}

std::shared_ptr<ExtensionShape> create_extension_shape(const Params& params, const PluginContext&) {
  std::string source;
  const sg_ext_shape& decl = extension_shape(params.info().name, &source);
  ExtensionArgs args = extension_args(decl.params, decl.param_count, params, nullptr);
  return std::make_shared<ExtensionShape>(decl, std::move(args.block), source);
}

}  // namespace sg
