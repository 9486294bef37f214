// Light "sun": a distant disc light. `direction` points from the scene towards the sun,
// `irradiance` is W/m^2 per channel on a surface facing the sun, `angular_diameter`
// in degrees (0.53 for the real sun; 0 makes it a delta directional light).
#include "core/sampling.h"
#include "light/light.h"

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

namespace {

PluginInfo info() {
  return PluginInfo("light", "sun",
                    "A distant disc light: the sun, from a direction or an elevation and azimuth (the sky's "
                    "convention); 0.53 degrees wide, or a delta directional light with angular_diameter 0.")
      .add(param::vec3("direction", Vec3f(0.f, 0.f, 1.f), "direction from the scene towards the sun"))
      .add(param::real("elevation", "sun elevation above the horizon in degrees (with azimuth, instead of "
                                    "direction)").in(-90, 90))
      .add(param::real("azimuth", "sun compass bearing in degrees: 0 = -z, 90 = +x, 180 = +z").default_is("0"))
      .add(param::color("irradiance", Color(1.f), "W/m^2 per channel on a surface facing the sun").at_least(0))
      .add(param::real("strength", 1.0, "multiplies irradiance").at_least(0))
      .add(param::real("angular_diameter", 0.53, "apparent diameter in degrees (0: hard shadows)").at_least(0).below(90))
      .exclusive_of({"direction"}, {"elevation", "azimuth"})
      .requires_all("azimuth", {"elevation"});
}

std::shared_ptr<Light> create(const Params& params, const PluginContext&) {
  Vec3f dir;
  if (params.has("elevation")) {
    // NOTE: the sky's convention (light/sky.cpp): (cos el sin az, sin el, -cos el cos az),
    // computed in double as there.
    constexpr double k_pi_d = 3.14159265358979323846;
    double el = double(params.get_float("elevation")) * k_pi_d / 180.0;
    double az = double(params.get_float_or("azimuth", 0.f)) * k_pi_d / 180.0;
    dir = Vec3f(float(std::cos(el) * std::sin(az)), float(std::sin(el)), float(-std::cos(el) * std::cos(az)));
  } else {
    dir = params.get_vec3("direction");
  }
  if (!(length(dir) > 0.f)) throw Error("parameter 'direction': must be a non-zero vector");
  Color e = params.get_color("irradiance") * params.get_float("strength");
  float diam = params.get_float("angular_diameter");
  return std::make_shared<SunLight>(dir, e, diam);
}

}  // namespace

SG_REGISTER_PLUGIN(Light, info(), create)

}  // namespace sg
