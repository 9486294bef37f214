// Light "headlamp": a vehicle's headlamp beam -- a point light whose luminous intensity
// follows a low-beam pattern (a wide, flat beam below a sharp cut-off) or a high-beam pattern
// (a narrow beam on the axis) around the lamp's forward direction.
//
// Parameters:
//   position   the lamp (0, 0, 0)
//   direction  the vehicle's forward direction, non-zero (0, 0, 1)
//   up         the vehicle's up direction, not parallel to direction (0, 1, 0)
//   intensity  W/sr per channel at the beam's maximum, >= 0 (1)
//   strength   multiplies intensity (1)
//   beam       "low" (default) or "high"
//   cutoff     low beam: degrees below the horizontal plane of the lamp where its cut-off lies
//              (0.57: headlamps are aimed 1% down)
//
// Pattern, in the lamp's angles: H to the side (degrees, atan2 along right / forward), V up
// (degrees, elevation above the plane of forward and right); nothing behind the lamp.
//   low:  I = I_max h(H) v(V), h = 0.7 N(H; 5) + 0.3 N(H; 22) (N(x; s) = exp(-x^2 / 2 s^2)),
//         v = 1 from the cut-off down to V = -cutoff - 1 (the hot spot), N(V + cutoff + 1; 3.5)
//         below it, 1% above the cut-off, a smoothstep across 0.6 degrees between.
//   high: I = I_max (0.75 N(H; 4) + 0.25 N(H; 15)) N(V; 3).
// NOTE: shaped after the photometric test points of UN ECE Regulation 112 for low beams
// (e.g. at most 350 cd at B50L, 0.57 degrees above the horizontal, at least 10 kcd at 75R,
// 0.57 below; 1.7 kcd at 25L / 25R, 9 degrees aside) with I_max of 10-20 kcd, and of high
// beams on the axis (R112 / R113); a pattern for images, not a homologated photometry.
#include <cmath>

#include "light/light.h"

namespace sg {

namespace {

constexpr double k_pi_d = 3.14159265358979323846;

double gauss(double x, double s) { return std::exp(-0.5 * (x / s) * (x / s)); }

double smoothstep(double a, double b, double v) {
  double t = std::min(1.0, std::max(0.0, (v - a) / (b - a)));
  return t * t * (3.0 - 2.0 * t);
}

}  // namespace

class HeadlampLight final : public Light {
 public:
  HeadlampLight(const Vec3f& pos, const Vec3f& forward, const Vec3f& up, const Color& intensity, bool low,
                float cutoff_deg)
      : m_pos(pos), m_intensity(intensity), m_low(low), m_cutoff(cutoff_deg) {
    m_forward = normalize(forward);
    m_up = normalize(up - m_forward * dot(up, m_forward));
    m_right = cross(m_forward, m_up);
  }
  bool sample(const LightSampleContext& ctx, const Vec2f&, LightSample* out) const override {
    return sample_point_emitter(ctx, m_pos, m_intensity, [this](const Vec3f& w) { return relative_intensity(w); },
                                out);
  }
  /// For the power-only light choice (RenderScene::group_pick, when a scene has very many
  /// lights): an isotropic lamp of the beam's peak intensity, 4 pi I_max, as pbrt-v4's
  /// SpotLight::Bounds. Weighed choices use selection_intensity().
  float power() const override { return 4.f * k_pi * luminance(m_intensity); }
  bool is_delta() const override { return true; }
  bool bounding_sphere(Vec3f* centre, float* radius) const override {
    *centre = m_pos;
    *radius = 0.f;
    return true;
  }
  bool has_selection_intensity() const override { return true; }
  float selection_intensity(const Vec3f& p) const override {
    Vec3f d = p - m_pos;
    float len = length(d);
    return len > 0.f ? luminance(m_intensity) * relative_intensity(d / len) : luminance(m_intensity);
  }
  /// It lights the half-space in front of the lamp only.
  bool normal_cone(Vec3f* axis, float* half_angle) const override {
    *axis = m_forward;
    *half_angle = 0.5f * k_pi;
    return true;
  }

  /// Intensity along the unit direction w (from the lamp) over the maximum.
  float relative_intensity(const Vec3f& w) const {
    double f = dot(w, m_forward);
    if (!(f > 0.0)) return 0.f;
    double h = std::atan2(double(dot(w, m_right)), f) * 180.0 / k_pi_d;
    double v = std::asin(std::min(1.0, std::max(-1.0, double(dot(w, m_up))))) * 180.0 / k_pi_d;
    return float(horizontal(h) * vertical(v));
  }

 private:
  double horizontal(double h) const {
    return m_low ? 0.7 * gauss(h, 5.0) + 0.3 * gauss(h, 22.0) : 0.75 * gauss(h, 4.0) + 0.25 * gauss(h, 15.0);
  }
  double vertical(double v) const {
    if (!m_low) return gauss(v, 3.0);
    const double c = -double(m_cutoff), hot = c - 1.0;
    double below = v >= hot ? 1.0 : gauss(v - hot, 3.5);
    // NOTE: 1% above the cut-off: 150 cd for a 15 kcd lamp (R112's B50L: at most 350 cd).
    double t = smoothstep(c - 0.3, c + 0.3, v);
    return below * (1.0 - t) + 0.01 * t;
  }

  Vec3f m_pos, m_forward, m_up, m_right;
  Color m_intensity;
  bool m_low;
  float m_cutoff;
};

namespace {

PluginInfo info() {
  return PluginInfo("light", "headlamp",
                    "A vehicle headlamp: a point light with a low-beam (wide, below a sharp cut-off) or high-beam "
                    "intensity pattern around the forward direction.")
      .add(param::vec3("position", Vec3f(0.f), "the lamp's position"))
      .add(param::vec3("direction", Vec3f(0.f, 0.f, 1.f), "the vehicle's forward direction"))
      .add(param::vec3("up", Vec3f(0.f, 1.f, 0.f), "the vehicle's up direction"))
      .add(param::color("intensity", Color(1.f), "radiant intensity at the beam's maximum, W/sr per channel")
               .at_least(0))
      .add(param::real("strength", 1.0, "multiplies intensity").at_least(0))
      .add(param::choice("beam", "low", {"low", "high"}, "low beam (cut-off) or high beam"))
      .add(param::real("cutoff", 0.57, "low beam: degrees below the horizontal where the cut-off lies").in(-5, 10));
}

std::shared_ptr<Light> create(const Params& params, const PluginContext&) {
  Vec3f dir = params.get_vec3("direction"), up = params.get_vec3("up");
  if (!(length(dir) > 0.f)) throw Error("parameter 'direction': must be a finite non-zero vector");
  if (!(length(cross(normalize(dir), up)) > 1e-3f))
    throw Error("parameter 'up': must not be parallel to direction (nor zero)");
  Color intensity = params.get_color("intensity") * params.get_float("strength");
  return std::make_shared<HeadlampLight>(params.get_vec3("position"), dir, up, intensity,
                                         params.get_string("beam") == "low", params.get_float("cutoff"));
}

}  // namespace

SG_REGISTER_PLUGIN(Light, info(), create)

}  // namespace sg
