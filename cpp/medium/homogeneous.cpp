// Medium "homogeneous": constant density between two heights, the layer bottom <= y <= top
// (by default everything below `top`): global fog and haze over a scene standing on y = 0.
// Extinction sigma_t from the meteorological visibility V (sigma_t = 3.912 / V) or given
// directly; single-scattering albedo (RGB) and Henyey-Greenstein asymmetry g.
//
// Transmittance is exact, T = exp(-sigma_t * length inside the layer); free flights are
// sampled exactly by inverting it (the distance inside the layer is exponential with rate
// sigma_t), so an estimator's weight is the albedo at a scattering event and 1 when the
// flight passes: no tracking, no majorant.
// NOTE: Koschmieder's law (1924): the contrast of a black object against the horizon sky falls
// as exp(-sigma_t d), and the meteorological visibility is where it reaches the 2% threshold
// of the eye: V = -ln(0.02) / sigma_t = 3.912 / sigma_t (WMO Guide to Meteorological
// Instruments, ch. 9; Sakaridis, Dai, Van Gool 2018, "Semantic Foggy Scene Understanding with
// Synthetic Data", eq. (2)-(3), Foggy Cityscapes' beta from 0.005 to 0.06 m^-1).
#include <algorithm>
#include <limits>

#include "core/error.h"
#include "core/plugin.h"
#include "medium/medium.h"

namespace sg {

namespace {

constexpr float k_koschmieder = 3.912f;  // -ln(0.02)

class HomogeneousLayer final : public Medium {
 public:
  HomogeneousLayer(float sigma_t, const Color& albedo, float g, float bottom, float top)
      : m_sigma_t(sigma_t), m_albedo(albedo), m_g(g), m_bottom(bottom), m_top(top) {}

  float transmittance(const Vec3f& o, const Vec3f& d, float t_max) const override {
    float t0, t1;
    if (!(m_sigma_t > 0.f) || !inside(o, d, t_max, &t0, &t1)) return 1.f;
    const float len = (t1 - t0) * length(d);
    return std::isfinite(len) ? std::exp(-m_sigma_t * len) : 0.f;
  }

  bool sample_distance(const Vec3f& o, const Vec3f& d, float t_max, MediumRng& rng, float* t) const override {
    float t0, t1;
    if (!(m_sigma_t > 0.f) || !inside(o, d, t_max, &t0, &t1)) return false;
    const float u = rng.next();
    // The path length inside the layer to the event: exponential with rate sigma_t.
    const float s = -std::log1p(-std::min(u, 0x1.fffffep-1f)) / m_sigma_t;
    const float dt = s / length(d);
    if (!(dt < t1 - t0)) return false;
    *t = t0 + dt;
    return true;
  }

  bool sample_in_segment(const Vec3f& o, const Vec3f& d, float t_max, MediumRng& rng, float* t,
                         float* p_scatter) const override {
    float t0, t1;
    if (!(m_sigma_t > 0.f) || !inside(o, d, t_max, &t0, &t1)) return false;
    const float u = rng.next();
    const float len = length(d);
    // NOTE: inverting the exponential truncated to the segment's length L inside the layer:
    // s = -ln(1 - u (1 - exp(-sigma L))) / sigma; -expm1 keeps 1 - exp accurate for thin media.
    const float p = std::isfinite(t1) ? -std::expm1(-m_sigma_t * (t1 - t0) * len) : 1.f;
    if (!(p > 0.f)) return false;
    const float s = -std::log1p(-std::min(u, 0x1.fffffep-1f) * p) / m_sigma_t;
    *t = std::isfinite(t1) ? std::min(t0 + s / len, t1) : t0 + s / len;
    *p_scatter = p;
    return true;
  }

  Color albedo() const override { return m_albedo; }
  HenyeyGreenstein phase() const override { return HenyeyGreenstein{m_g}; }

 private:
  /// The part [t0, t1] of [0, t_max) inside the layer; false when empty.
  bool inside(const Vec3f& o, const Vec3f& d, float t_max, float* t0, float* t1) const {
    float lo = 0.f, hi = t_max;
    if (d.y == 0.f) {
      if (o.y < m_bottom || o.y > m_top) return false;
    } else {
      const float inv = 1.f / d.y;
      float ta = (m_bottom - o.y) * inv, tb = (m_top - o.y) * inv;
      if (ta > tb) std::swap(ta, tb);
      lo = std::max(lo, ta);
      hi = std::min(hi, tb);
    }
    *t0 = lo;
    *t1 = hi;
    return lo < hi;
  }

  float m_sigma_t;
  Color m_albedo;
  float m_g, m_bottom, m_top;
};

PluginInfo info() {
  return PluginInfo("medium", "homogeneous",
                    "Fog or haze of constant density in the layer bottom <= y <= top (metres): extinction from "
                    "the meteorological visibility (3.912 / visibility, Koschmieder) or given, an RGB "
                    "single-scattering albedo and a Henyey-Greenstein phase function. Exact transmittance and "
                    "free-flight sampling.")
      .add(param::real("visibility", "meteorological visibility in metres (where a black object's contrast "
                                     "falls to 2%): extinction = 3.912 / visibility; fog < 1000, mist 1000-5000, "
                                     "haze 2000-10000")
               .above(0))
      .add(param::real("extinction", "extinction coefficient sigma_t in 1/m (instead of visibility)").at_least(0))
      .exactly_one_of({"visibility", "extinction"})
      .add(param::color("albedo", Color(0.95f), "single-scattering albedo sigma_s / sigma_t per channel "
                                                "(water droplets of fog about 1, haze about 0.9)")
               .in(0, 1))
      .add(param::real("g", 0.75, "Henyey-Greenstein asymmetry: 0 isotropic, > 0 forward (fog droplets "
                                  "0.75-0.85)")
               .above(-1)
               .below(1))
      .add(param::real("top", 200.0, "height of the layer's top in metres: clear air above (the sun and the "
                                     "sky reach the layer through it)"))
      .add(param::real("bottom", "height of the layer's bottom in metres").default_is("none: all the way down"));
}

std::shared_ptr<Medium> create(const Params& params, const PluginContext&) {
  const float sigma_t = params.has("visibility") ? k_koschmieder / params.get_float("visibility")
                                                 : params.get_float("extinction");
  const float top = params.get_float("top");
  const float bottom = params.has("bottom") ? params.get_float("bottom") : -std::numeric_limits<float>::infinity();
  if (!(bottom < top))
    throw Error("medium 'homogeneous': bottom (" + std::to_string(bottom) + ") must be below top (" +
                std::to_string(top) + ")");
  return std::make_shared<HomogeneousLayer>(sigma_t, params.get_color("albedo"), params.get_float("g"), bottom, top);
}

}  // namespace

SG_REGISTER_PLUGIN(Medium, info(), create)

}  // namespace sg
