// Light "sky": a physical clear daylight sky with its sun, after A. J. Preetham, P. Shirley,
// B. Smits, "A Practical Analytic Model for Daylight", SIGGRAPH 1999 (below: "Preetham").
//
// Parameters:
//   elevation      sun elevation above the horizon, degrees in [0, 90] (45)
//   azimuth        sun azimuth, degrees (0): a compass bearing, clockwise seen from above,
//                  with north = -z and east = +x (y up): azimuth 0 puts the sun towards -z,
//                  90 towards +x, 180 towards +z, 270 towards -x. The sun direction is
//                  (cos(el) sin(az), sin(el), -cos(el) cos(az)); in an "envmap" (rotation 0)
//                  the same direction lies at u = azimuth / 360.
//   turbidity      atmospheric turbidity T in [1.7, 10] (3): 2 very clear, 3 clear, 6 hazy
//   strength       scale of sky, sun and ground radiance, >= 0 (1)
//   ground_albedo  colour in [0, 1] (0.2): below the horizon the sky shows a Lambertian
//                  ground of this albedo lit by the sky and the sun (unshadowed), radiance
//                  albedo x E_h / pi with E_h the horizontal irradiance of sky + sun (the
//                  "ground glow" of Radiance's gensky, whose default reflectance is 0.2)
//   sun            add the sun disc (true): angular diameter 0.53 degrees, radiance of the
//                  extraterrestrial solar spectrum attenuated by the atmosphere (Preetham
//                  appendix A.1), not clipped by the horizon
//   visible        whether camera rays see sky and sun directly (true); they always light
//                  the scene
//
// Units: radiance in W/(m^2 sr) per linear sRGB channel such that its Rec. 709 luminance
// is the photometric luminance / 683 lm/W, for sky (Preetham's zenith luminance is in
// kcd/m^2) and sun (spectral radiance weighted by the CIE y-bar function) alike. A clear
// sky with a high sun gives 150-200 W/m^2 of such irradiance on the ground (100-130 klx);
// use `strength` to bring it to the range you want.
//
// Implementation: le() evaluates the analytic model; for importance sampling the sky is
// tabulated at pixel centres into a 256 x 128 equirectangular luminance map (light/equirect.h,
// shared with "envmap"), and the sun is a disc light (light/sun.cpp, by composition). A
// light sample picks the sun or the sky table with fixed probabilities; pdf_le() is the
// mixture density, so sample() and pdf_le() agree everywhere.
#include <cmath>

#include "core/sampling.h"
#include "light/cie.h"
#include "light/equirect.h"
#include "light/light.h"

namespace sg {

namespace {

constexpr double k_pi_d = 3.14159265358979323846;
constexpr int k_table_width = 256, k_table_height = 128;  // even height: the horizon is a row edge
constexpr double k_sun_diameter_deg = 0.53;
/// NOTE: luminous efficacy of 555 nm radiation, 683 lm/W (CIE); converts the photometric
/// quantities of the model to the radiometric units of the renderer.
constexpr double k_lm_per_w = 683.0;

struct PerezCoefficients {
  double a, b, c, d, e;
};
struct PerezCoefficientsF {
  float a, b, c, d, e;
  explicit PerezCoefficientsF(const PerezCoefficients& k = {0, 0, 0, 0, 0})
      : a(float(k.a)), b(float(k.b)), c(float(k.c)), d(float(k.d)), e(float(k.e)) {}
};

// NOTE: distribution coefficients for luminance Y and chromaticities x, y, linear in the
// turbidity T: Preetham appendix A.2.
PerezCoefficients perez_Y(double t) {
  return {0.1787 * t - 1.4630, -0.3554 * t + 0.4275, -0.0227 * t + 5.3251, 0.1206 * t - 2.5771, -0.0670 * t + 0.3703};
}
PerezCoefficients perez_x(double t) {
  return {-0.0193 * t - 0.2592, -0.0665 * t + 0.0008, -0.0004 * t + 0.2125, -0.0641 * t - 0.8989,
          -0.0033 * t + 0.0452};
}
PerezCoefficients perez_y(double t) {
  return {-0.0167 * t - 0.2608, -0.0950 * t + 0.0092, -0.0079 * t + 0.2102, -0.0441 * t - 1.6537,
          -0.0109 * t + 0.0529};
}

/// NOTE: the Perez et al. (1993) sky distribution used by Preetham (sec. 3):
/// F(theta, gamma) = (1 + A exp(B / cos theta)) (1 + C exp(D gamma) + E cos^2 gamma), theta the
/// view direction's zenith angle, gamma its angle to the sun. B < 0 for T >= 1.7, so the
/// first factor tends to 1 at the horizon (cos theta -> +0).
double perez(const PerezCoefficients& k, double cos_theta, double gamma) {
  double cg = std::cos(gamma);
  return (1.0 + k.a * std::exp(k.b / cos_theta)) * (1.0 + k.c * std::exp(k.d * gamma) + k.e * cg * cg);
}
/// perez() in float with 1 / cos(theta) and cos(gamma) given: the per-direction work the three
/// channels share (SkyLight::sky_radiance).
float perez(const PerezCoefficientsF& k, float inv_cos_theta, float gamma, float cos_gamma) {
  return (1.f + k.a * std::exp(k.b * inv_cos_theta)) *
         (1.f + k.c * std::exp(k.d * gamma) + k.e * cos_gamma * cos_gamma);
}

/// NOTE: zenith luminance in kcd/m^2, Preetham appendix A.2:
/// Y_z = (4.0453 T - 4.9710) tan(chi) - 0.2155 T + 2.4192, chi = (4/9 - T/120)(pi - 2 theta_s).
double zenith_luminance(double t, double theta_s) {
  double chi = (4.0 / 9.0 - t / 120.0) * (k_pi_d - 2.0 * theta_s);
  return (4.0453 * t - 4.9710) * std::tan(chi) - 0.2155 * t + 2.4192;
}

/// NOTE: zenith chromaticity, Preetham appendix A.2: x_z, y_z = [T^2 T 1] M [theta_s^3 theta_s^2 theta_s 1]^T.
double zenith_chromaticity(const double m[3][4], double t, double theta_s) {
  double th[4] = {theta_s * theta_s * theta_s, theta_s * theta_s, theta_s, 1.0};
  double tt[3] = {t * t, t, 1.0};
  double s = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) s += tt[i] * m[i][j] * th[j];
  return s;
}
const double k_zenith_x[3][4] = {{0.00166, -0.00375, 0.00209, 0.0},
                                 {-0.02903, 0.06377, -0.03202, 0.00394},
                                 {0.11693, -0.21196, 0.06052, 0.25886}};
const double k_zenith_y[3][4] = {{0.00275, -0.00610, 0.00317, 0.0},
                                 {-0.04214, 0.08970, -0.04153, 0.00516},
                                 {0.15346, -0.26756, 0.06670, 0.26688}};

// ---- The sun: Preetham appendix A.1, data as in Mitsuba 0.5's sunsky plugin, from
// M. Iqbal, "An Introduction to Solar Radiation", Academic Press 1983 (absorption
// coefficients: ozone p. 127, mixed gases and water vapour p. 130).

/// Extraterrestrial solar spectral radiance, W/(m^2 sr nm), 380..750 nm every 10 nm.
const double k_sol_amplitudes[38] = {
    16559.0, 16233.7, 21127.5, 25888.2, 25829.1, 24232.3, 26760.5, 29658.3, 30545.4, 30057.5,
    30663.7, 28830.4, 28712.1, 27825.0, 27100.6, 27233.6, 26361.3, 25503.8, 25060.2, 25311.6,
    25355.9, 25134.2, 24631.5, 24173.2, 23685.3, 23212.1, 22827.7, 22339.8, 21970.2, 21526.7,
    21097.9, 20728.3, 20240.4, 19870.8, 19427.2, 19072.4, 18628.9, 18259.2};
/// Ozone absorption coefficient k_o, 1/cm.
const double k_o_wavelengths[64] = {300, 305, 310, 315, 320, 325, 330, 335, 340, 345, 350, 355, 445,
                                    450, 455, 460, 465, 470, 475, 480, 485, 490, 495, 500, 505, 510,
                                    515, 520, 525, 530, 535, 540, 545, 550, 555, 560, 565, 570, 575,
                                    580, 585, 590, 595, 600, 605, 610, 620, 630, 640, 650, 660, 670,
                                    680, 690, 700, 710, 720, 730, 740, 750, 760, 770, 780, 790};
const double k_o_amplitudes[64] = {10.0,  4.8,   2.7,   1.35,  .8,    .380,  .160,  .075,  .04,   .019,  .007,
                                   .0,    .003,  .003,  .004,  .006,  .008,  .009,  .012,  .014,  .017,  .021,
                                   .025,  .03,   .035,  .04,   .045,  .048,  .057,  .063,  .07,   .075,  .08,
                                   .085,  .095,  .103,  .110,  .12,   .122,  .12,   .118,  .115,  .12,   .125,
                                   .130,  .12,   .105,  .09,   .079,  .067,  .057,  .048,  .036,  .028,  .023,
                                   .018,  .014,  .011,  .010,  .009,  .007,  .004,  .0,    .0};
/// Mixed-gas absorption coefficient k_g, 1/km.
const double k_g_wavelengths[4] = {759, 760, 770, 771};
const double k_g_amplitudes[4] = {0.0, 3.0, 0.210, 0.0};
/// Water-vapour absorption coefficient k_wa, 1/cm.
const double k_wa_wavelengths[13] = {689, 690, 700, 710, 720, 730, 740, 750, 760, 770, 780, 790, 800};
const double k_wa_amplitudes[13] = {0,     0.160e-1, 0.240e-1, 0.125e-1, 0.100e+1, 0.870, 0.610e-1,
                                    0.100e-2, 0.100e-4, 0.100e-4, 0.600e-3, 0.175e-1, 0.360e-1};

/// Piecewise-linear table lookup, 0 outside the table.
double interpolate(const double* wl, const double* val, int n, double lambda) {
  if (lambda < wl[0] || lambda > wl[n - 1]) return 0.0;
  for (int i = 0; i + 1 < n; ++i)
    if (lambda <= wl[i + 1]) {
      double t = (lambda - wl[i]) / (wl[i + 1] - wl[i]);
      return val[i] * (1.0 - t) + val[i + 1] * t;
    }
  return val[n - 1];
}

/// NOTE: CIE 1931 colour matching functions by the multi-lobe Gaussian fit of C. Wyman,
/// P.-P. Sloan, P. Shirley, "Simple Analytic Approximations to the CIE XYZ Color Matching
/// Functions", JCGT 2(2), 2013, eq. 2 (error well below the 10 nm sampling of the data).
double lobe(double lambda, double mu, double s1, double s2) {
  double t = (lambda - mu) / (lambda < mu ? s1 : s2);
  return std::exp(-0.5 * t * t);
}
void cie_xyz_bar(double l, double* x, double* y, double* z) {
  *x = 1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7) - 0.065 * lobe(l, 501.1, 20.4, 26.2);
  *y = 0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1);
  *z = 1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8);
}

/// Radiance of the sun's disc (linear sRGB, W/(m^2 sr), luminance = cd/m^2 / 683) for the
/// sun's zenith angle theta_s and turbidity t.
/// NOTE: Preetham appendix A.1: the solar spectrum times the transmittances of Rayleigh
/// scattering exp(-0.008735 lambda^-4.08 m), aerosols (Angstrom) exp(-beta lambda^-alpha m)
/// with alpha = 1.3, beta = 0.04608365822050 T - 0.04586025928522, ozone (l = 0.35 cm),
/// mixed gases and water vapour (w = 2 cm), lambda in micrometres; relative optical mass
/// m = 1 / (cos theta_s + 0.15 (93.885 - theta_s[deg])^-1.253) (Kasten 1966). Integrated
/// against the CIE functions from 380 to 750 nm (trapezoid rule, 1 nm steps).
Color preetham_sun_radiance(double theta_s, double t) {
  double beta = 0.04608365822050 * t - 0.04586025928522;
  double theta_deg = theta_s * 180.0 / k_pi_d;
  double m = 1.0 / (std::cos(theta_s) + 0.15 * std::pow(93.885 - theta_deg, -1.253));
  double acc[3] = {0, 0, 0};
  for (int l = 380; l <= 750; ++l) {
    double lambda = l, um = lambda / 1000.0;
    double tau_r = std::exp(-m * 0.008735 * std::pow(um, -4.08));
    double tau_a = std::exp(-m * beta * std::pow(um, -1.3));
    double tau_o = std::exp(-m * interpolate(k_o_wavelengths, k_o_amplitudes, 64, lambda) * 0.35);
    double kg = interpolate(k_g_wavelengths, k_g_amplitudes, 4, lambda);
    double tau_g = std::exp(-1.41 * kg * m / std::pow(1.0 + 118.93 * kg * m, 0.45));
    double kwa = interpolate(k_wa_wavelengths, k_wa_amplitudes, 13, lambda);
    double tau_wa = std::exp(-0.2385 * kwa * 2.0 * m / std::pow(1.0 + 20.07 * kwa * 2.0 * m, 0.45));
    int i = std::min((l - 380) / 10, 36);
    double frac = (lambda - 380.0 - 10.0 * i) / 10.0;
    double sol = k_sol_amplitudes[i] * (1.0 - frac) + k_sol_amplitudes[i + 1] * frac;
    double spectral = sol * tau_r * tau_a * tau_o * tau_g * tau_wa;
    double w = (l == 380 || l == 750) ? 0.5 : 1.0;
    double xb, yb, zb;
    cie_xyz_bar(lambda, &xb, &yb, &zb);
    acc[0] += w * spectral * xb;
    acc[1] += w * spectral * yb;
    acc[2] += w * spectral * zb;
  }
  return xyz_to_linear_srgb(acc[0], acc[1], acc[2]);
}

}  // namespace

class SkyLight final : public Light {
 public:
  SkyLight(double elevation_deg, double azimuth_deg, double turbidity, float strength, const Color& ground_albedo,
           bool sun, bool visible)
      : m_visible(visible) {
    double el = elevation_deg * k_pi_d / 180.0, az = azimuth_deg * k_pi_d / 180.0;
    m_sun_dir_d[0] = std::cos(el) * std::sin(az);
    m_sun_dir_d[1] = std::sin(el);
    m_sun_dir_d[2] = -std::cos(el) * std::cos(az);
    double theta_s = k_pi_d / 2.0 - el;
    const PerezCoefficients coef[3] = {perez_Y(turbidity), perez_x(turbidity), perez_y(turbidity)};
    // Zenith values Y_z (kcd/m^2), x_z, y_z; the sky is zenith value x F(theta, gamma) / F(0, theta_s).
    double zenith[3] = {zenith_luminance(turbidity, theta_s), zenith_chromaticity(k_zenith_x, turbidity, theta_s),
                        zenith_chromaticity(k_zenith_y, turbidity, theta_s)};
    for (int k = 0; k < 3; ++k) {
      m_coef[k] = PerezCoefficientsF(coef[k]);
      m_zenith_over_f0[k] = float(zenith[k] / perez(coef[k], 1.0, theta_s));
    }
    m_sun_dir = Vec3f(float(m_sun_dir_d[0]), float(m_sun_dir_d[1]), float(m_sun_dir_d[2]));
    // kcd/m^2 -> cd/m^2 -> W/(m^2 sr) (luminance / 683).
    m_scale = float(double(strength) * 1000.0 / k_lm_per_w);

    // The sun disc, through the "sun" plugin: irradiance = radiance x pi sin^2(half-angle).
    Color sun_irradiance(0.f);
    if (sun) {
      Color l_sun = preetham_sun_radiance(theta_s, turbidity) * strength;
      double half = 0.5 * k_sun_diameter_deg * k_pi_d / 180.0;
      sun_irradiance = l_sun * float(k_pi_d * std::sin(half) * std::sin(half));
      ParamSet p;
      p.set("direction", std::vector<double>{m_sun_dir_d[0], m_sun_dir_d[1], m_sun_dir_d[2]});
      p.set("irradiance", std::vector<double>{sun_irradiance.x, sun_irradiance.y, sun_irradiance.z});
      p.set("angular_diameter", k_sun_diameter_deg);
      m_sun = create_light("sun", p, "sky: sun");
    }

    // Ground: albedo x horizontal irradiance of sky and sun / pi (midpoint rule in
    // (cos theta, phi) over the upper hemisphere, 256 x 512 cells).
    double e_h[3] = {0, 0, 0};
    const int nz = 256, nphi = 512;
    for (int i = 0; i < nz; ++i) {
      double cos_t = (i + 0.5) / nz, sin_t = std::sqrt(1.0 - cos_t * cos_t);
      for (int j = 0; j < nphi; ++j) {
        double phi = 2.0 * k_pi_d * (j + 0.5) / nphi;
        Color l = sky_radiance(Vec3f(float(sin_t * std::sin(phi)), float(cos_t), float(-sin_t * std::cos(phi))));
        for (int k = 0; k < 3; ++k) e_h[k] += double(l[k]) * cos_t;
      }
    }
    for (int k = 0; k < 3; ++k)
      e_h[k] = e_h[k] * (2.0 * k_pi_d / (double(nz) * nphi)) + double(sun_irradiance[k]) * std::sin(el);
    m_ground = Color(float(e_h[0] / k_pi_d), float(e_h[1] / k_pi_d), float(e_h[2] / k_pi_d)) * ground_albedo;

    // Sampling table: luminance at the pixel centres.
    m_sampler = EquirectSampler::of_radiance(k_table_width, k_table_height,
                                             [this](const Vec3f& d) { return sky_radiance(d); });

    // NOTE: a one-sample mixture of the two strategies (Veach 1997, sec. 9.2.4, with the
    // balance heuristic: the density is the mixture density), sun vs sky table in proportion
    // to their power (disc irradiance vs 4 pi x mean sky luminance), kept within [0.1, 0.9]
    // so that neither strategy starves.
    m_sky_power = 4.f * k_pi * m_sampler.mean();
    m_sun_power = luminance(sun_irradiance);
    if (m_sun) {
      float total = m_sky_power + m_sun_power;
      m_sun_prob = total > 0.f ? std::min(0.9f, std::max(0.1f, m_sun_power / total)) : 0.5f;
    }
  }

  bool sample(const LightSampleContext& ctx, const Vec2f& u, LightSample* out) const override {
    Vec3f wi;
    if (m_sun && u.x < m_sun_prob) {
      LightSample ls;
      if (!m_sun->sample(ctx, Vec2f(std::min(u.x / m_sun_prob, k_one_minus_epsilon), u.y), &ls)) return false;
      wi = ls.wi;
    } else {
      float ux = m_sun ? std::min((u.x - m_sun_prob) / (1.f - m_sun_prob), k_one_minus_epsilon) : u.x;
      wi = normalize(m_sampler.sample(Vec2f(ux, u.y)));
    }
    // Radiance and density of the direction itself (one-sample mixture), exactly as le()
    // and pdf_le() report them.
    float pdf = pdf_le(wi);
    if (!(pdf > 0.f)) return false;
    set_infinite_sample(out, wi, le(wi), pdf);
    return true;
  }
  /// NOTE: as "environment" and "sun": pi r^2 x (4 pi x mean sky luminance + sun irradiance).
  float power() const override { return k_pi * m_radius * m_radius * (m_sky_power + m_sun_power); }
  bool is_infinite() const override { return true; }
  bool visible_to_camera() const override { return m_visible; }
  Color le(const Vec3f& dir) const override {
    Color l = sky_radiance(dir);
    if (m_sun) l += m_sun->le(dir);
    return l;
  }
  float pdf_le(const Vec3f& dir) const override {
    float p = m_sampler.pdf(dir);
    if (!m_sun) return p;
    return (1.f - m_sun_prob) * p + m_sun_prob * m_sun->pdf_le(dir);
  }
  void preprocess(const Bounds3& b) override {
    m_radius = std::max(b.radius(), 1e-3f);
    if (m_sun) m_sun->preprocess(b);
  }
  bool is_dome() const override { return true; }
  /// With its sun: the dome and the sun, sampled apart by the renderer (each at every vertex,
  /// RenderScene's light groups); sample() / le() / pdf_le() above are their mixture.
  std::vector<const Light*> parts() const override {
    if (!m_sun) return {this};
    return {&m_dome_part, &m_sun_part};
  }

 private:
  /// The sky and ground without the sun, sampled by the table.
  class DomePart final : public Light {
   public:
    explicit DomePart(const SkyLight& sky) : m_sky(sky) {}
    bool sample(const LightSampleContext&, const Vec2f& u, LightSample* out) const override {
      float pdf;
      Vec3f wi = m_sky.m_sampler.sample_with_pdf(u, &pdf);
      if (!(pdf > 0.f)) return false;
      set_infinite_sample(out, wi, m_sky.sky_radiance(wi), pdf);
      return true;
    }
    float power() const override { return k_pi * m_sky.m_radius * m_sky.m_radius * m_sky.m_sky_power; }
    bool is_infinite() const override { return true; }
    bool is_dome() const override { return true; }
    bool visible_to_camera() const override { return m_sky.m_visible; }
    Color le(const Vec3f& dir) const override { return m_sky.sky_radiance(dir); }
    float pdf_le(const Vec3f& dir) const override { return m_sky.m_sampler.pdf(dir); }

   private:
    const SkyLight& m_sky;
  };
  /// The sun disc, seen by the camera as the sky is.
  class SunPart final : public Light {
   public:
    explicit SunPart(const SkyLight& sky) : m_sky(sky) {}
    bool sample(const LightSampleContext& ctx, const Vec2f& u, LightSample* out) const override {
      return m_sky.m_sun->sample(ctx, u, out);
    }
    float power() const override { return m_sky.m_sun->power(); }
    bool is_infinite() const override { return true; }
    bool visible_to_camera() const override { return m_sky.m_visible; }
    Color le(const Vec3f& dir) const override { return m_sky.m_sun->le(dir); }
    float pdf_le(const Vec3f& dir) const override { return m_sky.m_sun->pdf_le(dir); }

   private:
    const SkyLight& m_sky;
  };

  /// Sky (above the horizon) or ground (below) radiance along the unit direction d.
  /// NOTE: in float: the model's own accuracy is a few percent (Preetham sec. 3), and in float the
  /// radiance stays within 5.35e-07 relative luminance and 1.25e-07 chromaticity of the paper's
  /// model in double (the largest errors sky.radiance_matches_preetham_model_in_double printed
  /// over 16,000 directions); the double version's divisions and square roots were among the
  /// sky's largest costs in `perf annotate` of a daylight frame. Out of line: with
  /// FMA contraction (GCC's default -ffp-contract=fast) copies inlined into sample() and le()
  /// rounded differently, and a sample's radiance must equal le() of its direction bit for bit.
  [[gnu::noinline]] Color sky_radiance(const Vec3f& dir) const {
    if (!(dir.y > 0.f)) return m_ground;
    const Vec3f d = dir * (1.f / length(dir));
    // Angle to the sun from atan2(|d x s|, d . s): accurate also near the sun; cos(gamma) is the
    // dot product over the hypotenuse, and the angle from fast_atan2 (exp(D gamma), |D| < 2).
    const Vec3f c = cross(d, m_sun_dir);
    const float sin_g = length(c), cos_g = dot(d, m_sun_dir);
    const float gamma = fast_atan2(sin_g, cos_g);
    const float cos_gamma = cos_g / std::sqrt(sin_g * sin_g + cos_g * cos_g), inv_cos_theta = 1.f / d.y;
    float v[3];
    for (int k = 0; k < 3; ++k) v[k] = m_zenith_over_f0[k] * perez(m_coef[k], inv_cos_theta, gamma, cos_gamma);
    // xyY -> XYZ (X = x Y / y, Z = (1 - x - y) Y / y) -> linear sRGB, in float.
    const float big_y = v[0] * m_scale, x = v[1], y = v[2];
    if (!(y > 0.f) || !(big_y > 0.f)) return Color(0.f);
    const float y_over = big_y / y;
    return xyz_to_linear_srgb(x * y_over, big_y, (1.f - x - y) * y_over);
  }

  double m_sun_dir_d[3];
  Vec3f m_sun_dir;
  PerezCoefficientsF m_coef[3];  // Y, x, y
  float m_zenith_over_f0[3];     // zenith value / F(0, theta_s) for Y, x, y
  float m_scale;                 // kcd/m^2 -> renderer units, times strength
  Color m_ground;
  std::shared_ptr<Light> m_sun;
  float m_sun_prob = 0.f;
  EquirectSampler m_sampler;
  float m_sky_power = 0.f, m_sun_power = 0.f;
  float m_radius = 1.f;
  bool m_visible;
  DomePart m_dome_part{*this};
  SunPart m_sun_part{*this};
};

namespace {

PluginInfo info() {
  return PluginInfo("light", "sky",
                    "A physical clear daylight sky with its sun (Preetham, Shirley, Smits 1999); radiance = "
                    "luminance / 683 lm/W.")
      .add(param::real("elevation", 45.0, "sun elevation above the horizon, degrees").in(0, 90))
      .add(param::real("azimuth", 0.0, "sun compass bearing in degrees: 0 = -z, 90 = +x, 180 = +z"))
      .add(param::real("turbidity", 3.0, "atmospheric turbidity (2 very clear, 3 clear, 6 hazy)").in(1.7, 10))
      .add(param::real("strength", 1.0, "multiplies sky and sun (0.02 maps a clear day to display range)")
               .at_least(0))
      .add(param::color("ground_albedo", Color(0.2f), "reflectance of the ground below the horizon").in(0, 1))
      .add(param::boolean("sun", true, "add the 0.53 degree sun disc with Preetham's attenuated radiance"))
      .add(param::boolean("visible", true, "whether camera rays see the sky directly"));
}

std::shared_ptr<Light> create(const Params& params, const PluginContext&) {
  float elevation = params.get_float("elevation");
  float azimuth = params.get_float("azimuth");
  float turbidity = params.get_float("turbidity");
  float strength = params.get_float("strength");
  Color albedo = params.get_color("ground_albedo");
  bool sun = params.get_bool("sun");
  bool visible = params.get_bool("visible");
  return std::make_shared<SkyLight>(elevation, azimuth, turbidity, strength, albedo, sun, visible);
}

}  // namespace

SG_REGISTER_PLUGIN(Light, info(), create)

}  // namespace sg
