// Light "sun": a distant disc light. `direction` points from the scene towards the sun,
// `irradiance` is W/m^2 per channel on a surface facing the sun, `angular_diameter`
// in degrees (0.53 for the real sun; 0 makes it a delta directional light).
#include "core/sampling.h"
#include "light/light_registry.h"

namespace sg {

class SunLight final : public Light {
 public:
  SunLight(const Vec3f& dir, const Color& irradiance, float angular_diameter_deg)
      : m_dir(normalize(dir)), m_frame(m_dir), m_irradiance(irradiance) {
    float half = 0.5f * angular_diameter_deg * k_pi / 180.f;
    m_delta = half <= 0.f;
    if (!m_delta) {
      m_one_minus_cos = one_minus_cos(half);
      m_solid_angle = 2.f * k_pi * m_one_minus_cos;
      // NOTE: a disc of uniform radiance L subtending half-angle a gives normal
      // irradiance E = pi L sin^2(a); so L = E / (pi sin^2 a).
      float s = std::sin(half);
      m_radiance = irradiance / (k_pi * s * s);
    }
  }
  bool sample(const LightSampleContext&, const Vec2f& u, LightSample* out) const override {
    out->infinite = true;
    out->p_light_error = Vec3f(0.f);
    out->n_light = Vec3f(0.f);
    if (m_delta) {
      out->wi = m_dir;
      out->li = m_irradiance;
      out->pdf = 1.f;
      out->delta = true;
      return true;
    }
    Vec3f local = square_to_uniform_cone_omc(u, m_one_minus_cos);
    out->wi = normalize(m_frame.to_world(local));
    out->li = m_radiance;
    out->pdf = 1.f / m_solid_angle;
    out->delta = false;
    return true;
  }
  float power() const override { return k_pi * m_radius * m_radius * luminance(m_irradiance); }
  bool is_delta() const override { return m_delta; }
  bool is_infinite() const override { return true; }
  Color le(const Vec3f& dir) const override { return inside(dir) ? m_radiance : Color(0.f); }
  float pdf_le(const Vec3f& dir) const override { return inside(dir) ? 1.f / m_solid_angle : 0.f; }
  void preprocess(const Bounds3& b) override { m_radius = std::max(b.radius(), 1e-3f); }

 private:
  /// NOTE: for unit vectors |a - b|^2 / 2 = 1 - cos(angle), which keeps full precision for
  /// tiny angles, unlike comparing dot(a, b) with a float cos_max (0.5% of the sun's disc
  /// is decided by the last bit of dot).
  bool inside(const Vec3f& dir) const {
    return !m_delta && 0.5f * length_squared(dir - m_dir) <= m_one_minus_cos;
  }

  Vec3f m_dir;
  Frame m_frame;
  Color m_irradiance, m_radiance;
  float m_one_minus_cos = 0.f, m_solid_angle = 0.f, m_radius = 1.f;
  bool m_delta;
};

std::shared_ptr<Light> create_sun_light(const ParamSet& params) {
  Vec3f dir = params.get_vec3("direction", Vec3f(0.f, 0.f, 1.f));
  if (!(length(dir) > 0.f)) throw Error("parameter 'direction': must be a non-zero vector");
  Color e = params.get_color("irradiance", Color(1.f)) * params.get_float("strength", 1.f);
  if (e.x < 0 || e.y < 0 || e.z < 0) throw Error("parameter 'irradiance': components must be non-negative");
  float diam = params.get_float("angular_diameter", 0.53f);
  if (!(diam >= 0.f && diam < 90.f)) throw Error("parameter 'angular_diameter': must lie in [0, 90) degrees");
  return std::make_shared<SunLight>(dir, e, diam);
}

}  // namespace sg
