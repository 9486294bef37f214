// Light "twilight": the sky with the sun below the horizon -- dusk, twilight and night -- in the
// units of the "sky" light (luminance / 683 lm/W per linear sRGB channel, times `strength`), so
// that lamps given the same strength keep their proportion to it.
//
// Parameters:
//   elevation      sun elevation in degrees, <= 0 (-6): 0 sunset, -6 the end of civil twilight,
//                  -12 of nautical, -18 of astronomical twilight (then night)
//   azimuth        the sun's compass bearing in degrees (0), the sky's convention: 0 = -z, 90 = +x
//   turbidity      the day sky's turbidity at the handover (3), see below
//   strength       scale of the radiance, as the sky's (1)
//   ground_albedo  below the horizon a Lambertian ground of this albedo lit by this sky (0.2)
//   night_sky      natural night-sky luminance at the zenith, cd/m^2 (1.7e-4: airglow and stars)
//   sky_glow       artificial sky glow at the zenith (light pollution), cd/m^2 (0)
//   glow_color     colour of the sky glow (linear RGB, its luminance normalised): sodium orange
//   visible        whether camera rays see it (true)
//
// The level: illuminance on a horizontal plane E(h) follows the U.S. Naval Observatory's fit of
// measured clear-sky twilight illuminance (Circular 171, below): 759 lx at h = 0, 3.4 lx at -6,
// 0.008 lx at -12; below -18 only the night sky is left (about 0.001 lx with the default
// night_sky, the floor of moonless nights). The day sky ("sky", Preetham et al. 1999) at
// elevation 0 is brighter than measured (8.8 klx of sky light at turbidity 3): over the first
// 2 degrees below the horizon the sky hands over from it (at h = 0 this light is the "sky" at
// elevation 0 without its sun, radiance for radiance) to the measured level, its logarithm
// blended with a smoothstep, so that nothing jumps at sunset.
//
// The distribution (relative radiance; scaled to E(h)): a blue sky brightening towards the
// horizon (its chromaticity that of the day sky's zenith at sunset, turning deep blue within 5
// degrees: the Chappuis bands of ozone absorb the orange and red of the light that reaches the
// zenith through the long grazing path, E. O. Hulburt, "Explanation of the brightness and
// color of the sky, particularly the twilight sky", JOSA 43(2), 1953), the Earth's shadow on
// the anti-solar side with the pink anti-twilight arch above it (up to -8 degrees), and the
// twilight glow over the sun: orange at the horizon, yellow above, in a band that narrows and
// reddens as the sun sinks and outshines the zenith more (x 3 at sunset to x 50). The shape
// is a qualitative model after the descriptions and photometry of G. V. Rozenberg, "Twilight:
// A Study in Atmospheric Optics" (Plenum 1966), not a fit; the level is the measured one.
//
// Sampling: the radiance is tabulated at pixel centres into a 256 x 128 equirectangular
// luminance map (light/equirect.h, as "sky" and "envmap"); sample() and pdf_le() agree.
#include <cmath>
#include <memory>

#include "core/sampling.h"
#include "light/cie.h"
#include "light/equirect.h"
#include "light/light.h"

namespace sg {

namespace {

constexpr double k_pi_d = 3.14159265358979323846;
constexpr int k_table_width = 256, k_table_height = 128;
/// NOTE: luminous efficacy of 555 nm radiation, 683 lm/W (CIE), as in light/sky.cpp.
constexpr double k_lm_per_w = 683.0;
/// Depression (degrees) over which the day sky at sunset hands over to the measured level.
constexpr double k_handover_deg = 2.0;
/// Depression (degrees) by which the blue sky's chromaticity has left the day sky's zenith's.
constexpr double k_blue_deg = 5.0;
/// Depression (degrees) at which twilight ends (astronomical twilight).
constexpr double k_night_deg = 18.0;

/// NOTE: log10 of the illuminance (lx) on a horizontal plane from the sun and the sky at sun
/// altitude h (degrees), clear sky: P. M. Janiczek, J. A. DeYoung, "Computer Programs for Sun
/// and Moon Illuminance With Contingent Tables and Diagrams", U.S. Naval Observatory Circular
/// 171 (1987): L0 + L1 x + L2 x^2 + L3 x^3 with x = h / 90, coefficients per range of h (stated
/// error 0.01-0.02 in the logarithm of the fit; its tables agree with Bond & Henderson, "The
/// Conquest of Darkness", 1963). Only the ranges below 5 degrees are used here.
double usno_log10_illuminance(double h) {
  double x = h / 90.0;
  const double* c;
  static const double k_low_sun[4] = {2.88, 22.26, -207.64, 1034.30};   // -0.8 < h <= 5
  static const double k_sunset[4] = {2.88, 21.81, -258.11, -858.36};    // -5 < h <= -0.8
  static const double k_civil[4] = {2.70, 12.17, -431.69, -1899.83};    // -12 < h <= -5
  static const double k_nautical[4] = {13.84, 262.72, 1447.42, 2797.93};  // -18 <= h <= -12
  if (h > -0.8)
    c = k_low_sun;
  else if (h > -5.0)
    c = k_sunset;
  else if (h > -12.0)
    c = k_civil;
  else
    c = k_nautical;
  return c[0] + x * (c[1] + x * (c[2] + x * c[3]));
}

/// Illuminance (lx) on a horizontal plane from the sun below the horizon at depression
/// dep >= 0, the night sky's share left out: USNO's fit less its value at -18 degrees (where
/// twilight ends and only the night sky's light remains), 0 below.
double twilight_illuminance(double dep) {
  if (dep >= k_night_deg) return 0.0;
  return std::pow(10.0, usno_log10_illuminance(-dep)) - std::pow(10.0, usno_log10_illuminance(-k_night_deg));
}

double smoothstep(double a, double b, double v) {
  double t = std::min(1.0, std::max(0.0, (v - a) / (b - a)));
  return t * t * (3.0 - 2.0 * t);
}
double lerp(double a, double b, double t) { return a + (b - a) * t; }

/// xyY -> XYZ, accumulated.
void add_xyY(double x, double y, double big_y, double* xyz) {
  xyz[0] += x * big_y / y;
  xyz[1] += big_y;
  xyz[2] += (1.0 - x - y) * big_y / y;
}

/// NOTE: the relative optical air mass of a sky position at zenith angle z, X = (1 - 0.96
/// sin^2 z)^(-1/2), and the night sky's brightening towards the horizon,
/// B(z) / B(0) = X 10^(-0.4 k (X - 1)) (more airglow along a longer path, less of it through
/// extinction), k = 0.172 mag per air mass in V: K. Krisciunas, B. E. Schaefer, "A model of
/// the brightness of moonlight", PASP 103 (1991), eqs. 2-3.
double night_gradation(double sin_alt) {
  double cos2 = std::max(0.0, 1.0 - sin_alt * sin_alt);  // sin^2 of the zenith angle
  double x = 1.0 / std::sqrt(1.0 - 0.96 * cos2);
  return x * std::pow(10.0, -0.4 * 0.172 * (x - 1.0));
}

/// The twilight sky's relative distribution at depression dep (see the file comment).
struct TwilightShape {
  double dep;
  double base_x, base_y;      // chromaticity of the blue sky
  double shadow_top, shadow;  // the Earth's shadow: top altitude (degrees), depth
  double glow, glow_alt, glow_width;  // glow: peak over the zenith, altitude scale, azimuth width (degrees)
  double yellow_x, yellow_y, red_x, red_y;
  double arch, arch_alt;  // anti-twilight arch: peak, altitude (degrees)

  TwilightShape(double d, double zenith_x, double zenith_y) : dep(d) {
    double blue = smoothstep(0.0, k_blue_deg, d);
    base_x = lerp(zenith_x, 0.205, blue);
    base_y = lerp(zenith_y, 0.215, blue);
    shadow_top = d + 1.0;
    shadow = 0.5 * (1.0 - smoothstep(6.0, 10.0, d));
    glow = std::min(3.0 * std::pow(10.0, d / 8.0), 50.0);
    glow_alt = std::max(10.0 * (1.0 - d / 24.0), 3.0);
    glow_width = std::max(50.0 - 2.0 * d, 25.0);
    double u = smoothstep(0.0, 8.0, d);
    yellow_x = lerp(0.45, 0.47, u), yellow_y = lerp(0.45, 0.44, u);
    red_x = lerp(0.54, 0.58, u), red_y = lerp(0.425, 0.405, u);
    arch = 0.6 * (1.0 - smoothstep(3.0, 8.0, d));
    arch_alt = d + 6.0;
  }
  /// CIE XYZ (relative) at altitude alt (degrees, >= 0) and azimuth cos_dphi from the sun.
  void eval(double alt, double cos_dphi, double* xyz) const {
    xyz[0] = xyz[1] = xyz[2] = 0.0;
    double dphi = std::acos(std::min(1.0, std::max(-1.0, cos_dphi))) * 180.0 / k_pi_d;
    double anti = std::max(0.0, -cos_dphi);
    // The blue sky, brighter towards the horizon, darker in the Earth's shadow.
    double in_shadow = shadow * anti * (1.0 - smoothstep(shadow_top - 2.0, shadow_top + 2.0, alt));
    add_xyY(base_x, base_y, (1.0 + 1.5 * std::exp(-alt / 15.0)) * (1.0 - in_shadow), xyz);
    // The glow over the sun, wider along the horizon, red at the bottom and yellow above.
    double t = std::exp(-alt / glow_alt);
    double w = glow_width * (1.0 + 0.6 * t);
    double g = glow * t * std::exp(-0.5 * (dphi / w) * (dphi / w));
    if (g > 0.0) add_xyY(lerp(yellow_x, red_x, t), lerp(yellow_y, red_y, t), g, xyz);
    // The anti-twilight arch (the Belt of Venus) above the Earth's shadow.
    if (arch > 0.0 && anti > 0.0) {
      double a = (alt - arch_alt) / 5.0;
      add_xyY(0.37, 0.33, arch * std::exp(-0.5 * a * a) * anti * std::sqrt(anti), xyz);
    }
  }
};

/// Integrates f(dir) x cos(theta) over the upper hemisphere (midpoint rule in (cos theta, phi),
/// 256 x 512 cells), per channel.
struct Rgb {
  double x, y, z;
};

template <typename F>
Rgb hemisphere_irradiance(const F& f) {
  const int nz = 256, nphi = 512;
  double e[3] = {0, 0, 0};
  for (int i = 0; i < nz; ++i) {
    double cos_t = (i + 0.5) / nz, sin_t = std::sqrt(1.0 - cos_t * cos_t);
    for (int j = 0; j < nphi; ++j) {
      double phi = 2.0 * k_pi_d * (j + 0.5) / nphi;
      Color l = f(Vec3f(float(sin_t * std::sin(phi)), float(cos_t), float(-sin_t * std::cos(phi))));
      for (int k = 0; k < 3; ++k) e[k] += double(l[k]) * cos_t;
    }
  }
  double w = 2.0 * k_pi_d / (double(nz) * nphi);
  return {e[0] * w, e[1] * w, e[2] * w};
}

}  // namespace

class TwilightLight final : public Light {
 public:
  TwilightLight(double elevation_deg, double azimuth_deg, double turbidity, float strength, const Color& ground_albedo,
                double night_sky, double sky_glow, const Color& glow_color, bool visible)
      : m_shape(0.0, 0.0, 0.0), m_visible(visible) {
    const double dep = std::max(0.0, -elevation_deg);
    const double az = azimuth_deg * k_pi_d / 180.0;
    m_sun_h[0] = std::sin(az);
    m_sun_h[1] = -std::cos(az);
    m_scale = double(strength) / k_lm_per_w;

    // NOTE: the handover from the day sky: log E = w log E_day + (1 - w) log E_twilight,
    // w = smoothstep over the first k_handover_deg degrees of depression (1 at sunset).
    const double w = dep < k_handover_deg ? smoothstep(0.0, 1.0, 1.0 - dep / k_handover_deg) : 0.0;
    const double e_tw = twilight_illuminance(dep);
    // The day sky at sunset, without its sun, in cd/m^2 / 683 (its units at strength 1): its
    // radiance during the handover, its zenith's chromaticity where the blue sky starts from.
    double zenith_x = 0.0, zenith_y = 0.0;
    if (dep < k_blue_deg) {
      ParamSet p;
      p.set("elevation", 0.0);
      p.set("azimuth", azimuth_deg);
      p.set("turbidity", turbidity);
      p.set("sun", false);
      p.set("ground_albedo", 0.0);
      m_day = create_light("sky", p, "twilight: the day sky at sunset");
      linear_srgb_to_xy(m_day->le(Vec3f(0.f, 1.f, 0.f)), &zenith_x, &zenith_y);
    }
    m_shape = TwilightShape(dep, zenith_x, zenith_y);

    // Levels (horizontal illuminance in lx at strength 1, per channel) of the parts.
    Rgb e_day{0, 0, 0}, e_shape{0, 0, 0};
    if (w > 0.0) {
      e_day = hemisphere_irradiance([&](const Vec3f& d) { return m_day->le(d); });
      e_day = {e_day.x * k_lm_per_w, e_day.y * k_lm_per_w, e_day.z * k_lm_per_w};
    }
    if (w < 1.0 && e_tw > 0.0) e_shape = hemisphere_irradiance([&](const Vec3f& d) { return twilight_rgb(d); });
    double level = e_tw;
    if (w > 0.0) level = std::exp(w * std::log(luminance(to_color(e_day))) + (1.0 - w) * std::log(e_tw));
    if (w > 0.0) m_day_weight = w * level / luminance(to_color(e_day)) * k_lm_per_w;  // day le() is cd / 683
    if (w < 1.0 && e_tw > 0.0) m_shape_weight = (1.0 - w) * level / luminance(to_color(e_shape));
    if (!m_day_weight) m_day.reset();

    // The night sky: natural and artificial, in cd/m^2 at the zenith; its horizontal
    // illuminance 2 pi int_0^1 g(mu) mu dmu (mu = sin altitude; midpoint rule, 4096 steps).
    m_night = std::max(0.0, night_sky);
    m_glow = std::max(0.0, sky_glow);
    float gl = luminance(glow_color);
    m_glow_color = gl > 0.f ? glow_color / gl : Color(0.f);
    double g_int = 0.0;
    for (int i = 0; i < 4096; ++i) {
      double mu = (i + 0.5) / 4096.0;
      g_int += night_gradation(mu) * mu;
    }
    g_int *= 2.0 * k_pi_d / 4096.0;
    Color night_rgb = night_color(m_night) + m_glow_color * float(m_glow);

    // The ground below the horizon: albedo x horizontal illuminance / pi.
    Rgb e_h{m_day_weight / k_lm_per_w * e_day.x + m_shape_weight * e_shape.x + g_int * night_rgb.x,
            m_day_weight / k_lm_per_w * e_day.y + m_shape_weight * e_shape.y + g_int * night_rgb.y,
            m_day_weight / k_lm_per_w * e_day.z + m_shape_weight * e_shape.z + g_int * night_rgb.z};
    m_ground = Color(float(e_h.x / k_pi_d), float(e_h.y / k_pi_d), float(e_h.z / k_pi_d)) * ground_albedo *
               float(m_scale);

    m_sampler = EquirectSampler::of_radiance(k_table_width, k_table_height, [this](const Vec3f& d) { return le(d); });
    m_power = 4.f * k_pi * m_sampler.mean();
  }

  bool sample(const LightSampleContext&, const Vec2f& u, LightSample* out) const override {
    float pdf;
    Vec3f wi = m_sampler.sample_with_pdf(u, &pdf);
    if (!(pdf > 0.f)) return false;
    set_infinite_sample(out, wi, le(wi), pdf);
    return true;
  }
  /// NOTE: as "environment" and "sky": pi r^2 x 4 pi x mean luminance.
  float power() const override { return k_pi * m_radius * m_radius * m_power; }
  bool is_infinite() const override { return true; }
  bool is_dome() const override { return true; }
  bool visible_to_camera() const override { return m_visible; }
  Color le(const Vec3f& dir) const override {
    if (!(dir.y > 0.f)) return m_ground;
    return sky_cd(dir) * float(m_scale);
  }
  float pdf_le(const Vec3f& dir) const override { return m_sampler.pdf(dir); }
  void preprocess(const Bounds3& b) override { m_radius = std::max(b.radius(), 1e-3f); }

 private:
  static Color to_color(const Rgb& v) { return Color(float(v.x), float(v.y), float(v.z)); }
  /// NOTE: the natural night sky's colour: airglow and starlight, near neutral (x 0.31, y 0.33).
  static Color night_color(double cd) { return xyY_to_linear_srgb(0.31, 0.33, cd); }

  /// The twilight shape's radiance (relative) along the unit direction d above the horizon.
  Color twilight_rgb(const Vec3f& d) const {
    double dx = d.x, dy = d.y, dz = d.z;
    double len = std::sqrt(dx * dx + dy * dy + dz * dz);
    dx /= len, dy /= len, dz /= len;
    double h = std::sqrt(dx * dx + dz * dz);
    double cos_dphi = h > 1e-12 ? (dx * m_sun_h[0] + dz * m_sun_h[1]) / h : 0.0;
    double alt = std::asin(std::min(1.0, std::max(0.0, dy))) * 180.0 / k_pi_d;
    double xyz[3];
    m_shape.eval(alt, cos_dphi, xyz);
    return xyz_to_linear_srgb(xyz[0], xyz[1], xyz[2]);
  }
  /// Sky radiance in cd/m^2 (luminance) along d above the horizon.
  Color sky_cd(const Vec3f& d) const {
    Color l(0.f);
    if (m_day_weight > 0.0) l += m_day->le(d) * float(m_day_weight);
    if (m_shape_weight > 0.0) l += twilight_rgb(d) * float(m_shape_weight);
    if (m_night > 0.0 || m_glow > 0.0) {
      double sin_alt = double(d.y) / double(length(d));
      double g = night_gradation(sin_alt);
      l += night_color(m_night * g) + m_glow_color * float(m_glow * g);
    }
    return l;
  }

  TwilightShape m_shape;
  double m_sun_h[2];  // the sun's azimuth as a horizontal unit vector (x, z)
  double m_scale;     // cd/m^2 -> renderer units, times strength
  std::shared_ptr<Light> m_day;
  double m_day_weight = 0.0, m_shape_weight = 0.0;
  double m_night = 0.0, m_glow = 0.0;
  Color m_glow_color{0.f};
  Color m_ground{0.f};
  EquirectSampler m_sampler;
  float m_power = 0.f, m_radius = 1.f;
  bool m_visible;
};

namespace {

PluginInfo info() {
  return PluginInfo("light", "twilight",
                    "The sky with the sun below the horizon: dusk, twilight (USNO's measured illuminance, a glow over "
                    "the sun, a blue zenith) and night (airglow, sky glow); the sky's units.")
      .add(param::real("elevation", -6.0, "sun elevation in degrees (0 sunset, -6 / -12 / -18 the ends of civil, "
                                          "nautical and astronomical twilight)")
               .in(-90, 0))
      .add(param::real("azimuth", 0.0, "sun compass bearing in degrees: 0 = -z, 90 = +x, 180 = +z"))
      .add(param::real("turbidity", 3.0, "the day sky's turbidity at sunset, where twilight takes over from it")
               .in(1.7, 10))
      .add(param::real("strength", 1.0, "multiplies the radiance, as the sky's strength").at_least(0))
      .add(param::color("ground_albedo", Color(0.2f), "reflectance of the ground below the horizon").in(0, 1))
      .add(param::real("night_sky", 1.7e-4, "natural night-sky luminance at the zenith, cd/m^2 (airglow, stars)")
               .at_least(0))
      .add(param::real("sky_glow", 0.0, "artificial sky glow (light pollution) at the zenith, cd/m^2").at_least(0))
      .add(param::color("glow_color", Color(1.f, 0.55f, 0.25f), "colour of the sky glow (its luminance is "
                                                                   "normalised)")
               .at_least(0))
      .add(param::boolean("visible", true, "whether camera rays see the sky directly"));
}

std::shared_ptr<Light> create(const Params& params, const PluginContext&) {
  Color glow = params.get_color("glow_color");
  if (params.get_float("sky_glow") > 0.f && !(luminance(glow) > 0.f))
    throw Error("parameter 'glow_color': must not be black when sky_glow > 0");
  return std::make_shared<TwilightLight>(params.get_float("elevation"), params.get_float("azimuth"),
                                         params.get_float("turbidity"), params.get_float("strength"),
                                         params.get_color("ground_albedo"), params.get_float("night_sky"),
                                         params.get_float("sky_glow"), glow, params.get_bool("visible"));
}

}  // namespace

SG_REGISTER_PLUGIN(Light, info(), create)

}  // namespace sg
