// Light "envmap": an HDR equirectangular (latitude-longitude) environment map at infinity.
//
// Parameters:
//   filename  image file (EXR or HDR: linear; 8/16-bit formats are decoded from sRGB);
//             1 channel is grey, 3 or more are RGB (alpha is ignored). Negative pixels
//             are clamped to 0; NaN/Inf pixels are an error.
//   strength  scale of the radiance, >= 0 (1)
//   rotation  degrees, right-handed rotation of the map about its up axis (0)
//   up        world direction of the map's zenith (top row), (0, 1, 0); e.g. (0, 0, 1)
//             for z-up scenes. The map is first rotated by `rotation` about its own +y,
//             then +y is turned onto `up` by the smallest rotation (180 degrees about +x
//             when up = -y).
//   visible   whether camera rays see the map directly (true). Hidden maps still light the
//             scene and appear in reflections and refractions.
//
// Orientation (light/equirect.h): with rotation 0 and up +y, the top row is +y, the image
// centre (u = 1/2) is +z, u = 1/4 is +x, u = 3/4 is -x and the left/right edges are -z.
// A positive rotation turns the map counter-clockwise seen from above (+z towards +x).
// Blender/Cycles' orientation in a z-up scene (image centre +X, u = 1/4 on +Y) is
// up = (0, 0, 1), rotation = 90.
//
// Radiance is the nearest pixel (as pbrt-v4's ImageInfiniteLight), so le() is exactly the
// piecewise-constant function that sample() importance-samples.
#include <cmath>

#include "core/sampling.h"
#include "io/image_io.h"
#include "light/equirect.h"
#include "light/light.h"

namespace sg {

namespace {

/// Rotation (row-major 3x3, in a Transform) taking map space to world space.
Transform world_from_map(float rotation_deg, const Vec3f& up_in) {
  double a = double(rotation_deg) * M_PI / 180.0;
  double ca = std::cos(a), sa = std::sin(a);
  // Right-handed rotation about +y: +z -> (sin a, 0, cos a).
  double ry[3][3] = {{ca, 0, sa}, {0, 1, 0}, {-sa, 0, ca}};
  double len = std::sqrt(double(up_in.x) * up_in.x + double(up_in.y) * up_in.y + double(up_in.z) * up_in.z);
  double n[3] = {up_in.x / len, up_in.y / len, up_in.z / len};
  // Smallest rotation taking +y to n.
  // NOTE: Rodrigues' formula for unit vectors a -> b: R = I + [v]x + [v]x^2 / (1 + c) with
  // v = a x b, c = a . b (Moller & Hughes, "Efficiently Building a Matrix to Rotate One
  // Vector to Another", JGT 4(4), 1999); c = -1 needs an explicit half turn.
  double align[3][3];
  if (n[1] < -1.0 + 1e-12) {
    double half_turn[3][3] = {{1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
    std::copy(&half_turn[0][0], &half_turn[0][0] + 9, &align[0][0]);
  } else {
    double v[3] = {n[2], 0.0, -n[0]};  // (0, 1, 0) x n
    double c = n[1];
    double k[3][3] = {{0, -v[2], v[1]}, {v[2], 0, -v[0]}, {-v[1], v[0], 0}};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double k2 = 0.0;
        for (int m = 0; m < 3; ++m) k2 += k[i][m] * k[m][j];
        align[i][j] = (i == j ? 1.0 : 0.0) + k[i][j] + k2 / (1.0 + c);
      }
  }
  float m[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0.0;
      for (int k = 0; k < 3; ++k) s += align[i][k] * ry[k][j];
      m[4 * i + j] = float(s);
    }
  return Transform::from_row_major(m, "envmap orientation");
}

}  // namespace

class EnvMapLight final : public Light {
 public:
  EnvMapLight(std::vector<Color> pixels, int width, int height, const Transform& world_from_map, bool visible)
      : m_pixels(std::move(pixels)), m_world_from_map(world_from_map), m_visible(visible) {
    std::vector<float> lum(m_pixels.size());
    for (size_t i = 0; i < m_pixels.size(); ++i) lum[i] = luminance(m_pixels[i]);
    m_sampler = EquirectSampler(lum, width, height);
  }
  bool sample(const LightSampleContext&, const Vec2f& u, LightSample* out) const override {
    Vec3f wi = normalize(m_world_from_map.apply_vector(m_sampler.sample(u)));
    // Radiance and density come from the direction itself (the same code as le() and
    // pdf_le()), so that MIS sees exactly the same values from both strategies. A direction
    // that float rounding carried across a pixel edge into a black pixel (about 1e-6 of
    // the samples next to black pixels) has density 0 and is dropped.
    Vec3f d = to_map(wi);
    float pdf = m_sampler.pdf(d);
    if (!(pdf > 0.f)) return false;
    set_infinite_sample(out, wi, m_pixels[m_sampler.pixel(d)], pdf);
    return true;
  }
  /// NOTE: like "environment", power = pi r^2 (disc of the scene's bounding sphere) x 4 pi x
  /// the solid-angle mean luminance: the flux a uniform environment of that luminance sends
  /// through the scene's cross-section, integrated over all directions.
  float power() const override { return 4.f * k_pi * k_pi * m_radius * m_radius * m_sampler.mean(); }
  bool is_infinite() const override { return true; }
  bool is_dome() const override { return true; }
  bool visible_to_camera() const override { return m_visible; }
  bool reflection_only() const override { return m_reflection_only; }
  void set_reflection_only(bool r) { m_reflection_only = r; }
  Color le(const Vec3f& dir) const override { return m_pixels[m_sampler.pixel(to_map(dir))]; }
  float pdf_le(const Vec3f& dir) const override { return m_sampler.pdf(to_map(dir)); }
  void preprocess(const Bounds3& b) override { m_radius = std::max(b.radius(), 1e-3f); }

 private:
  Vec3f to_map(const Vec3f& world_dir) const { return normalize(m_world_from_map.apply_inverse_vector(world_dir)); }

  std::vector<Color> m_pixels;
  Transform m_world_from_map;
  EquirectSampler m_sampler;
  bool m_visible;
  bool m_reflection_only = false;
  float m_radius = 1.f;
};

namespace {

PluginInfo info() {
  return PluginInfo("light", "envmap",
                    "An importance-sampled equirectangular HDR environment: top row = up, image centre = +z, "
                    "u = 1/4 = +x.")
      .add(param::path("file", "equirectangular HDR image (EXR/HDR, linear; relative to the scene file in YAML)")
               .alias("filename"))
      .add(param::real("strength", 1.0, "multiplies the map").at_least(0))
      .add(param::real("rotation", 0.0, "rotation in degrees about the map's up axis (right-handed)"))
      .add(param::vec3("up", Vec3f(0.f, 1.f, 0.f), "world direction of the map's top row"))
      .add(param::boolean("visible", true, "whether camera rays see the map directly"))
      .add(param::boolean("reflection_only", false,
                          "seen only by glossy and specular bounces (what objects reflect), never lighting the "
                          "scene: a photo's surroundings on a dome"));
}

std::shared_ptr<Light> create(const Params& params, const PluginContext&) {
  std::string filename = params.get_string("file");
  float strength = params.get_float("strength");
  float rotation = params.get_float("rotation");
  Vec3f up = params.get_vec3("up");
  bool visible = params.get_bool("visible");
  if (!(length(up) > 0.f)) throw Error("parameter 'up': must be a finite non-zero vector");
  ImageData img = load_image(filename, ColorSpace::Auto);
  if (img.width < 1 || img.height < 1 || img.channels < 1)
    throw Error("parameter 'file': '" + filename + "' has no pixels");
  std::vector<Color> pixels(size_t(img.width) * img.height);
  for (size_t i = 0; i < pixels.size(); ++i) {
    const float* p = &img.pixels[i * img.channels];
    Color c = img.channels >= 3 ? Color(p[0], p[1], p[2]) : Color(p[0]);
    if (!is_finite(c))
      throw Error("parameter 'file': '" + filename + "' has a non-finite value at pixel (" +
                  std::to_string(i % img.width) + ", " + std::to_string(i / img.width) + ")");
    pixels[i] = vmax(c, Color(0.f)) * strength;
  }
  auto light = std::make_shared<EnvMapLight>(std::move(pixels), img.width, img.height, world_from_map(rotation, up),
                                             visible);
  light->set_reflection_only(params.get_bool("reflection_only"));
  return light;
}

}  // namespace

SG_REGISTER_PLUGIN(Light, info(), create)

}  // namespace sg
