// Light "envmap" (light/envmap.cpp, light/equirect.h): an equirectangular HDR map read from
// an EXR file written by the test, importance-sampled by luminance x sin(theta).
//
// The orientation is checked against the documented convention, implemented here
// independently in double precision: pixel (ix, iy) of a W x H map has its centre at
// theta = pi (iy + 1/2) / H from the map's +y and phi = 2 pi (ix + 1/2) / W, direction
// (sin theta sin phi, cos theta, -sin theta cos phi); the world direction is
// A(up) R_y(rotation) times it, with R_y right-handed about +y and A the smallest rotation
// taking +y to `up`.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <functional>

#include "chi2.h"
#include "core/error.h"
#include "core/params.h"
#include "core/rng.h"
#include "io/image_io.h"
#include "light/equirect.h"
#include "light/light.h"

using namespace sg;
using namespace sgtest;

namespace {

namespace fs = std::filesystem;

Vec3f to_f(const DVec3& v) { return Vec3f(float(v.x), float(v.y), float(v.z)); }
DVec3 to_d(const Vec3f& v) { return {v.x, v.y, v.z}; }

/// The image plugin is found through $SYNTHGEN_IMAGE_IO_PLUGIN (set by ctest); when the test
/// binary is run directly, point it at the plugin that the build puts next to the Python
/// module (or into the build directory).
void ensure_image_plugin() {
  if (std::getenv("SYNTHGEN_IMAGE_IO_PLUGIN")) return;
  fs::path root = fs::path(__FILE__).parent_path().parent_path().parent_path();
  for (fs::path p : {root / "python" / "synthgen" / "libsynthgen_oiio.so", root / "build" / "libsynthgen_oiio.so"})
    if (fs::exists(p)) {
      setenv("SYNTHGEN_IMAGE_IO_PLUGIN", p.c_str(), 1);
      return;
    }
}

/// A per-process directory for the test's maps, removed when the test program exits.
fs::path temp_dir() {
  struct TempDir {
    fs::path path = fs::temp_directory_path() / ("synthgen_envmap_" + std::to_string(getpid()));
    TempDir() { fs::create_directories(path); }
    ~TempDir() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  };
  static TempDir dir;
  return dir.path;
}

/// Writes a W x H float EXR whose pixel (ix, iy) is f(ix, iy); returns its path.
std::string write_map(const std::string& name, int w, int h, const std::function<Color(int, int)>& f) {
  ensure_image_plugin();
  ImageData img;
  img.width = w;
  img.height = h;
  img.channels = 3;
  img.pixels.resize(size_t(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      Color c = f(x, y);
      for (int k = 0; k < 3; ++k) img.pixels[(size_t(y) * w + x) * 3 + k] = c[k];
    }
  std::string path = (temp_dir() / (name + ".exr")).string();
  save_image(path, img, 0);
  return path;
}

struct Orientation {
  double rotation_deg;
  bool z_up;
};

std::shared_ptr<Light> make_envmap(const std::string& path, const Orientation& o = {0.0, false},
                                   double strength = 1.0, bool visible = true) {
  ParamSet p;
  p.set("filename", path);
  if (o.rotation_deg != 0.0) p.set("rotation", o.rotation_deg);
  if (o.z_up) p.set("up", std::vector<double>{0.0, 0.0, 1.0});
  if (strength != 1.0) p.set("strength", strength);
  if (!visible) p.set("visible", false);
  return create_light("envmap", p, "light 0");
}

/// World direction of the map-space direction d (the documented convention, in double).
DVec3 world_from_map(const Orientation& o, const DVec3& d) {
  double a = o.rotation_deg * k_pi_d / 180.0;
  DVec3 r{std::cos(a) * d.x + std::sin(a) * d.z, d.y, -std::sin(a) * d.x + std::cos(a) * d.z};
  if (!o.z_up) return r;
  return {r.x, -r.z, r.y};  // rotation by +90 degrees about +x takes +y to +z
}
DVec3 map_from_world(const Orientation& o, const DVec3& w) {
  DVec3 r = o.z_up ? DVec3{w.x, w.z, -w.y} : w;
  double a = o.rotation_deg * k_pi_d / 180.0;
  return {std::cos(a) * r.x - std::sin(a) * r.z, r.y, std::sin(a) * r.x + std::cos(a) * r.z};
}
DVec3 map_dir(double u, double v) {
  double th = k_pi_d * v, ph = 2.0 * k_pi_d * u;
  return {std::sin(th) * std::sin(ph), std::cos(th), -std::sin(th) * std::cos(ph)};
}
void map_uv(const DVec3& d, double* u, double* v) {
  *u = wrap_phi(std::atan2(d.x, -d.z)) / (2.0 * k_pi_d);
  *v = std::acos(std::max(-1.0, std::min(1.0, d.y))) / k_pi_d;
}

/// Irradiance on a surface with normal n: mean of li cos / pdf over light samples.
Color mc_irradiance(const Light& l, const DVec3& n, int samples, uint64_t seed) {
  Pcg32 rng(seed);
  double e[3] = {0, 0, 0};
  for (int i = 0; i < samples; ++i) {
    LightSample ls;
    if (!l.sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls)) continue;
    double c = ddot(n, to_d(ls.wi));
    if (c <= 0.0) continue;
    for (int k = 0; k < 3; ++k) e[k] += double(ls.li[k]) * c / double(ls.pdf);
  }
  return Color(float(e[0] / samples), float(e[1] / samples), float(e[2] / samples));
}

const Orientation k_orientations[] = {{0.0, false}, {30.0, false}, {90.0, false}, {0.0, true}, {-45.0, true}};

std::string name(const Orientation& o) {
  return "rotation " + std::to_string(o.rotation_deg) + (o.z_up ? ", up +z" : ", up +y");
}

/// A map with random values, zero pixels and a bright patch.
Color random_pixel(int x, int y) {
  uint32_t hsh = uint32_t(x * 73856093u) ^ uint32_t(y * 19349663u);
  hsh = (hsh ^ (hsh >> 13)) * 0x5bd1e995u;
  hsh ^= hsh >> 15;
  float r = float(hsh & 0xffff) / 65536.f;
  if (hsh % 7 == 0) return Color(0.f);
  Color c(r, 0.5f * r + 0.1f, 1.f - r);
  if (x >= 20 && x < 24 && y >= 4 && y < 7) c = c * 50.f;
  return c;
}

}  // namespace

// Every pixel centre, mapped to the world by the documented convention, reads that pixel.
TEST(envmap, orientation_of_every_pixel) {
  const int w = 16, h = 8;
  std::string path = write_map("ids", w, h, [](int x, int y) { return Color(float(x), float(y), 1.f); });
  for (const Orientation& o : k_orientations) {
    auto env = make_envmap(path, o);
    int bad = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        DVec3 d = world_from_map(o, map_dir((x + 0.5) / w, (y + 0.5) / h));
        bad += env->le(to_f(d)) != Color(float(x), float(y), 1.f);
      }
    EXPECT_EQ(bad, 0) << name(o) << ": pixel centres that read another pixel";
  }
  // Landmarks of the documented convention (rotation 0, up +y): top row = +y, image centre
  // = +z, u = 1/4 is +x, u = 3/4 is -x, left and right edges are -z.
  auto env = make_envmap(path);
  auto pixel_of = [&](const DVec3& d) {
    Color c = env->le(to_f(dnormalize(d)));
    return std::make_pair(int(c.x), int(c.y));
  };
  EXPECT_EQ(pixel_of({0.01, 1, 0.02}).second, 0);
  EXPECT_EQ(pixel_of({0.01, -1, 0.02}).second, h - 1);
  EXPECT_EQ(pixel_of({0.1, 0.1, 1}), std::make_pair(w / 2 - 1, h / 2 - 1));   // +z, towards +x and up
  EXPECT_EQ(pixel_of({1, -0.1, 0.1}), std::make_pair(w / 4, h / 2));         // +x
  EXPECT_EQ(pixel_of({-1, -0.1, 0.1}), std::make_pair(3 * w / 4 - 1, h / 2));  // -x
  EXPECT_EQ(pixel_of({0.1, 0.1, -1}).first, 0);                              // -z, towards +x
  EXPECT_EQ(pixel_of({-0.1, 0.1, -1}).first, w - 1);                         // -z, towards -x
  // Blender/Cycles' convention in a z-up world (u = 1/2 - atan2(y, x) / 2 pi, top row +z):
  // up = +z, rotation = 90 puts the image centre on +X and u = 1/4 on +Y.
  ParamSet blender;
  blender.set("filename", path);
  blender.set("up", std::vector<double>{0.0, 0.0, 1.0});
  blender.set("rotation", 90.0);
  auto cycles = create_light("envmap", blender, "light 1");
  EXPECT_EQ(cycles->le(to_f(dnormalize({1, -0.1, 0.1}))), Color(float(w / 2), float(h / 2 - 1), 1.f));
  EXPECT_EQ(cycles->le(to_f(dnormalize({0.1, 1, 0.1}))), Color(float(w / 4), float(h / 2 - 1), 1.f));
  EXPECT_EQ(cycles->le(to_f(dnormalize({0.1, 0.1, 1}))).y, 0.f);
  // up = -y: the map upside down (a half turn about +x).
  ParamSet down;
  down.set("filename", path);
  down.set("up", std::vector<double>{0.0, -1.0, 0.0});
  auto flipped = create_light("envmap", down, "light 2");
  EXPECT_EQ(flipped->le(to_f(dnormalize({0.01, -1, 0.02}))).y, 0.f);
  EXPECT_EQ(flipped->le(to_f(dnormalize({0.1, -0.1, -1}))), Color(float(w / 2 - 1), float(h / 2 - 1), 1.f));
}

// A map that is bright only in one patch lights a surface facing the patch's world
// direction, with the irradiance of the patch computed here by quadrature.
TEST(envmap, bright_patch_lights_the_expected_direction) {
  const int w = 64, h = 32;
  const Color k_l(2.f, 3.f, 4.f);
  // Patch A: columns 14..17, rows 14..17 (around u = 1/4, v = 1/2: +x at the horizon).
  // Patch B: rows 0..1 (the zenith cap).
  std::string path_a = write_map("patch_x", w, h, [&](int x, int y) {
    return (x >= 14 && x < 18 && y >= 14 && y < 18) ? k_l : Color(0.f);
  });
  std::string path_b = write_map("patch_top", w, h, [&](int, int y) { return y < 2 ? k_l : Color(0.f); });
  struct Case {
    std::string path;
    Orientation o;
    DVec3 expected;
    double u0, u1, v0, v1;  // patch in (u, v)
  };
  const Case cases[] = {
      {path_a, {0.0, false}, {1, 0, 0}, 14.0 / w, 18.0 / w, 14.0 / h, 18.0 / h},
      {path_a, {90.0, false}, {0, 0, -1}, 14.0 / w, 18.0 / w, 14.0 / h, 18.0 / h},  // +x turned by 90 deg about +y
      {path_a, {-90.0, false}, {0, 0, 1}, 14.0 / w, 18.0 / w, 14.0 / h, 18.0 / h},
      {path_b, {0.0, false}, {0, 1, 0}, 0.0, 1.0, 0.0, 2.0 / h},
      {path_b, {0.0, true}, {0, 0, 1}, 0.0, 1.0, 0.0, 2.0 / h},  // up = +z moves the zenith cap
  };
  const DVec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Case& c : cases) {
    auto env = make_envmap(c.path, c.o);
    // Expected irradiance on the facing surface: L x integral of cos over the patch, in
    // map space (u, v) with d(omega) = 2 pi^2 sin(pi v) du dv (midpoint rule).
    const int n = 400;
    double cosint = 0.0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        double u = c.u0 + (c.u1 - c.u0) * (i + 0.5) / n, v = c.v0 + (c.v1 - c.v0) * (j + 0.5) / n;
        DVec3 d = world_from_map(c.o, map_dir(u, v));
        cosint += std::max(0.0, ddot(d, c.expected)) * 2.0 * k_pi_d * k_pi_d * std::sin(k_pi_d * v);
      }
    cosint *= (c.u1 - c.u0) * (c.v1 - c.v0) / (double(n) * n);
    double best = -1.0;
    DVec3 best_axis{};
    for (const DVec3& a : axes) {
      double e = mc_irradiance(*env, a, 100000, 701).y;
      if (e > best) {
        best = e;
        best_axis = a;
      }
      if (ddot(a, c.expected) < -0.5) {
        EXPECT_EQ(e, 0.0) << name(c.o) << ": light from behind the patch";
      }
    }
    EXPECT_NEAR(ddot(best_axis, c.expected), 1.0, 1e-9) << name(c.o) << ": brightest face is not the expected one";
    Color e = mc_irradiance(*env, c.expected, 200000, 702);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(e[k] / (k_l[k] * cosint), 1.0, 1e-2) << name(c.o) << ", channel " << k;
  }
}

// Sampled directions against pdf_le(), binned in the map's own (u, v) coordinates (computed
// here from the world direction with the independent convention above) on a grid twice as
// fine as the pixels; expected counts integrate pdf_le x 2 pi^2 sin(theta) over each bin.
TEST(envmap, sample_direction_chi2) {
  const int w = 32, h = 16;
  std::string path = write_map("random", w, h, random_pixel);
  for (const Orientation& o : {Orientation{0.0, false}, Orientation{30.0, true}}) {
    auto env = make_envmap(path, o);
    Grid2D g{2 * w, 2 * h, 0.0, 1.0, 0.0, 1.0};
    const int n = 1000000;
    Pcg32 rng(703 + uint64_t(o.rotation_deg));
    std::vector<double> obs(g.size(), 0.0);
    int bad = 0;
    for (int i = 0; i < n; ++i) {
      LightSample ls;
      if (!env->sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls)) {
        ++bad;
        continue;
      }
      double u, v;
      map_uv(map_from_world(o, to_d(ls.wi)), &u, &v);
      obs[size_t(g.cell(u, v))] += 1.0;
    }
    EXPECT_LE(bad, 10) << "failed samples (a few may round across a pixel edge into a black pixel)";
    // The density in (u, v) is constant inside a pixel: a 4 x 4 midpoint rule per bin,
    // away from the bin edges (which are pixel edges, where float rounding may pick either
    // pixel).
    std::vector<double> exp(g.size());
    for (int iy = 0; iy < g.ny; ++iy)
      for (int ix = 0; ix < g.nx; ++ix) {
        double s = 0.0;
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b) {
            double u = g.cx0(ix) + (g.cx1(ix) - g.cx0(ix)) * (a + 0.5) / 4;
            double v = g.cy0(iy) + (g.cy1(iy) - g.cy0(iy)) * (b + 0.5) / 4;
            s += double(env->pdf_le(to_f(world_from_map(o, map_dir(u, v))))) * 2.0 * k_pi_d * k_pi_d *
                 std::sin(k_pi_d * v);
          }
        exp[size_t(iy) * g.nx + ix] = n * s / 16.0 * (g.cx1(ix) - g.cx0(ix)) * (g.cy1(iy) - g.cy0(iy));
      }
    EXPECT_NEAR(sum(exp) / n, 1.0, 1e-3) << name(o) << ": pdf_le does not integrate to 1";
    Chi2Result r = chi2_test(obs, exp);
    EXPECT_TRUE(r.ok) << name(o) << ": " << r.message;
  }
}

// le() and pdf_le() report exactly what sample() returned; pdf_le integrates to 1 over the
// sphere in world coordinates; samples never land on black pixels.
TEST(envmap, le_and_pdf_le_consistent_with_sample) {
  std::string path = write_map("random", 32, 16, random_pixel);
  Orientation o{30.0, true};
  auto env = make_envmap(path, o);
  EXPECT_TRUE(env->is_infinite());
  EXPECT_FALSE(env->is_delta());
  Pcg32 rng(704);
  int bad_le = 0, bad_pdf = 0, black = 0, failed = 0;
  for (int i = 0; i < 100000; ++i) {
    LightSample ls;
    if (!env->sample({Vec3f(0.f), Vec3f(0.f)}, rng.next_2d(), &ls)) {
      ++failed;  // rounded across a pixel edge into a black pixel: ~1e-6 of the samples
      continue;
    }
    ASSERT_TRUE(ls.infinite);
    ASSERT_FALSE(ls.delta);
    ASSERT_NEAR(length(ls.wi), 1.f, 1e-5f);
    bad_le += env->le(ls.wi) != ls.li;
    bad_pdf += env->pdf_le(ls.wi) != ls.pdf;
    black += is_black(ls.li);
  }
  EXPECT_EQ(bad_le, 0);
  EXPECT_EQ(bad_pdf, 0);
  EXPECT_EQ(black, 0) << "samples on black pixels";
  EXPECT_LE(failed, 2);
  // Midpoint rule in (z, phi) around a tilted axis, in world space.
  DFrame frame(dnormalize({0.3, 0.8, -0.2}));
  const int nz = 1000, nphi = 2000;
  double integral = 0.0;
  for (int i = 0; i < nz; ++i)
    for (int j = 0; j < nphi; ++j)
      integral += env->pdf_le(to_f(sphere_dir(frame, -1.0 + 2.0 * (i + 0.5) / nz, 2.0 * k_pi_d * (j + 0.5) / nphi)));
  integral *= 4.0 * k_pi_d / (double(nz) * nphi);
  // Quadrature error: O(1 / nz) from the pixel edges crossing the (z, phi) cells.
  EXPECT_NEAR(integral, 1.0, 5e-3);
}

// A constant map behaves like "environment": radiance L everywhere, irradiance pi L on any
// plane, and the same power.
TEST(envmap, constant_map_behaves_like_environment) {
  std::string path = write_map("constant", 8, 4, [](int, int) { return Color(0.25f, 0.5f, 1.f); });
  auto env = make_envmap(path, {20.0, false}, 2.0);
  const Color k_radiance(0.5f, 1.f, 2.f);
  Pcg32 rng(705);
  for (int i = 0; i < 1000; ++i) {
    Vec3f d = to_f(dnormalize({rng.next_float() - 0.5, rng.next_float() - 0.5, rng.next_float() - 0.5}));
    ASSERT_EQ(env->le(d), k_radiance);
  }
  for (const DVec3& n : {DVec3{0, 1, 0}, dnormalize({1, -2, 0.5})}) {
    Color e = mc_irradiance(*env, n, 1000000, 706);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(e[k] / (k_pi_d * k_radiance[k]), 1.0, 5e-3) << "channel " << k;
  }
  ParamSet p;
  p.set("radiance", std::vector<double>{0.5, 1.0, 2.0});
  auto reference = create_light("environment", p, "light 1");
  Bounds3 b;
  b.expand(Vec3f(0.f, 0.f, 0.f));
  b.expand(Vec3f(0.f, 0.f, 4.f));  // radius 2
  env->preprocess(b);
  reference->preprocess(b);
  EXPECT_NEAR(env->power() / reference->power(), 1.0, 1e-5);
  EXPECT_NEAR(env->power() / (4.0 * k_pi_d * k_pi_d * 4.0 * luminance(k_radiance)), 1.0, 1e-5);
}

TEST(envmap, visible_flag) {
  std::string path = write_map("constant", 8, 4, [](int, int) { return Color(1.f); });
  EXPECT_TRUE(make_envmap(path)->visible_to_camera());
  auto hidden = make_envmap(path, {0.0, false}, 1.0, false);
  EXPECT_FALSE(hidden->visible_to_camera());
  // Hidden from the camera only: it still has radiance and can be sampled.
  EXPECT_EQ(hidden->le(Vec3f(0.f, 1.f, 0.f)), Color(1.f));
  LightSample ls;
  EXPECT_TRUE(hidden->sample({Vec3f(0.f), Vec3f(0.f)}, Vec2f(0.3f, 0.4f), &ls));
}

TEST(envmap, parameter_errors) {
  auto message = [](const ParamSet& p) {
    try {
      create_light("envmap", p, "light 3");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string good = write_map("constant", 8, 4, [](int, int) { return Color(1.f); });
  ParamSet none;
  EXPECT_NE(message(none).find("'file'"), std::string::npos) << message(none);
  ParamSet missing;
  missing.set("filename", (temp_dir() / "does_not_exist.exr").string());
  EXPECT_NE(message(missing).find("does_not_exist.exr"), std::string::npos) << message(missing);
  ParamSet negative;
  negative.set("filename", good);
  negative.set("strength", -1.0);
  EXPECT_NE(message(negative).find("'strength'"), std::string::npos) << message(negative);
  EXPECT_NE(message(negative).find(">= 0"), std::string::npos) << message(negative);
  ParamSet zero_up;
  zero_up.set("filename", good);
  zero_up.set("up", std::vector<double>{0.0, 0.0, 0.0});
  EXPECT_NE(message(zero_up).find("'up'"), std::string::npos) << message(zero_up);
  ParamSet typo;
  typo.set("filename", good);
  typo.set("rotaton", 10.0);
  EXPECT_NE(message(typo).find("did you mean 'rotation'"), std::string::npos) << message(typo);
  ParamSet nan_map;
  nan_map.set("filename", write_map("nan", 4, 2, [](int x, int y) { return Color(x == 2 && y == 1 ? NAN : 1.f); }));
  EXPECT_NE(message(nan_map).find("nan.exr"), std::string::npos) << message(nan_map);
  EXPECT_NE(message(nan_map).find("non-finite"), std::string::npos) << message(nan_map);
}

// EquirectSampler::sample_with_pdf takes the sampled cell's density when the point is safely
// inside it: direction and density must equal normalize(sample(u)) and pdf() of it bit for
// bit, for every u -- random ones and ones whose points land next to cell edges and the poles.
TEST(envmap, sample_with_pdf_equals_pdf_of_the_sampled_direction) {
  for (int size : {8, 64, 256}) {
    const int w = size, h = size / 2;
    Pcg32 rng{uint64_t(size)};
    std::vector<float> values(size_t(w) * h);
    for (float& v : values) v = rng.next_float() < 0.2f ? 0.f : rng.next_float() * rng.next_float() * 10.f;
    EquirectSampler sampler(values, w, h);
    std::vector<Vec2f> us;
    for (int i = 0; i < 400000; ++i) us.push_back(rng.next_2d());
    for (int i = 0; i <= 4000; ++i) {  // fine steps: points at every cell's edges
      const float t = float(i) / 4000.f;
      us.push_back(Vec2f(std::min(t, k_one_minus_epsilon), rng.next_float()));
      us.push_back(Vec2f(rng.next_float(), std::min(t, k_one_minus_epsilon)));
    }
    auto same = [](float a, float b) { return std::memcmp(&a, &b, 4) == 0; };
    for (const Vec2f& u : us) {
      float pdf = -1.f;
      const Vec3f wi = sampler.sample_with_pdf(u, &pdf);
      const Vec3f ref = normalize(sampler.sample(u));
      ASSERT_TRUE(same(wi.x, ref.x) && same(wi.y, ref.y) && same(wi.z, ref.z)) << u.x << " " << u.y;
      ASSERT_TRUE(same(pdf, sampler.pdf(wi))) << size << ": u " << u.x << " " << u.y << " pdf " << pdf << " vs "
                                              << sampler.pdf(wi);
    }
  }
}
