// Light "spot": a point light at `position` emitting into a cone around `direction`.
//
// Parameters:
//   position       (0, 0, 0)
//   direction      axis the light shines along, non-zero (0, -1, 0): downwards in a y-up world
//   intensity      W/sr per channel on the axis, >= 0 (1)
//   strength       scale of the intensity, >= 0 (1)
//   cone_angle     degrees from the axis where the falloff ends (no light beyond), in (0, 180] (30)
//   falloff_start  degrees from the axis where the falloff begins (full intensity inside), in
//                  [0, cone_angle] (25); equal to cone_angle gives a hard edge
// Both angles are half-angles measured from the axis (as pbrt-v4's coneangle).
#include <cmath>

#include "light/light.h"

namespace sg {

class SpotLight final : public Light {
 public:
  SpotLight(const Vec3f& pos, const Vec3f& dir, const Color& intensity, float cone_deg, float start_deg)
      : m_pos(pos), m_axis(normalize(dir)), m_intensity(intensity) {
    m_cos_end = std::cos(cone_deg * k_pi / 180.f);
    m_cos_start = std::cos(start_deg * k_pi / 180.f);
  }
  bool sample(const LightSampleContext& ctx, const Vec2f&, LightSample* out) const override {
    return sample_point_emitter(ctx, m_pos, m_intensity, [this](const Vec3f& w) { return falloff(dot(w, m_axis)); },
                                out);
  }
  /// NOTE: pbrt-v4 SpotLight::Phi: the smoothstep in cos(theta) integrates to half the
  /// falloff band, so Phi = I 2 pi (1 - (cos_start + cos_end) / 2).
  float power() const override {
    return luminance(m_intensity) * 2.f * k_pi * (1.f - 0.5f * (m_cos_start + m_cos_end));
  }
  bool is_delta() const override { return true; }

  /// Fraction of the axial intensity emitted at cos(theta) from the axis.
  /// NOTE: pbrt-v4 SpotLight::I: SmoothStep(cos_end, cos_start, cos theta), with
  /// smoothstep(t) = t^2 (3 - 2 t) and a step when the two angles coincide.
  float falloff(float cos_theta) const {
    if (m_cos_start <= m_cos_end) return cos_theta >= m_cos_end ? 1.f : 0.f;
    float t = std::min(1.f, std::max(0.f, (cos_theta - m_cos_end) / (m_cos_start - m_cos_end)));
    return t * t * (3.f - 2.f * t);
  }

  bool bounding_sphere(Vec3f* centre, float* radius) const override {
    *centre = m_pos;
    *radius = 0.f;
    return true;
  }
  bool has_selection_intensity() const override { return true; }
  float selection_intensity(const Vec3f& p) const override {
    Vec3f d = p - m_pos;
    float len = length(d);
    return len > 0.f ? luminance(m_intensity) * falloff(dot(d, m_axis) / len) : luminance(m_intensity);
  }

 private:
  Vec3f m_pos, m_axis;
  Color m_intensity;
  float m_cos_end, m_cos_start;
};

namespace {

PluginInfo info() {
  return PluginInfo("light", "spot", "A spot light: a point light limited to a cone, with a smoothstep falloff.")
      .add(param::vec3("position", Vec3f(0.f), "light position"))
      .add(param::vec3("direction", Vec3f(0.f, -1.f, 0.f), "cone axis"))
      .add(param::color("intensity", Color(1.f), "radiant intensity on the axis, W/sr per channel").at_least(0))
      .add(param::real("strength", 1.0, "multiplies intensity").at_least(0))
      .add(param::real("cone_angle", 30.0, "half-angle where the light ends, degrees").above(0).at_most(180))
      .add(param::real("falloff_start", "half-angle where the smooth falloff starts, degrees, in [0, cone_angle]")
               .at_least(0)
               .default_is("min(25, cone_angle)"));
}

std::shared_ptr<Light> create(const Params& params, const PluginContext&) {
  Vec3f pos = params.get_vec3("position");
  Vec3f dir = params.get_vec3("direction");
  Color intensity = params.get_color("intensity");
  float strength = params.get_float("strength");
  float cone = params.get_float("cone_angle");
  float start = params.get_float_or("falloff_start", std::min(25.f, cone));
  if (!(length(dir) > 0.f)) throw Error("parameter 'direction': must be a finite non-zero vector");
  if (!(start >= 0.f && start <= cone))
    throw Error("parameter 'falloff_start': must lie in [0, cone_angle] = [0, " + format_number(cone) +
                "] degrees, got " + format_number(start));
  return std::make_shared<SpotLight>(pos, dir, intensity * strength, cone, start);
}

}  // namespace

SG_REGISTER_PLUGIN(Light, info(), create)

}  // namespace sg
