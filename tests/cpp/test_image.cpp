// Texture "image" (texture/image.cpp) and its mip maps and cache (texture/mipmap.h,
// texture/image_cache.h): pyramid sizes and means, trilinear lookups against
// independent bilinear / average references, wrap modes, the uv transform, parameter
// errors and the shared per-scene cache.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "core/error.h"
#include "texture/image_cache.h"
#include "texture/mipmap.h"
#include "texture/texture.h"

#include "image_checks.h"

using namespace sg;

namespace {

/// Mean of level `l` in double precision.
Color level_mean(const MipMap& m, int l) {
  double acc[3] = {0, 0, 0};
  for (int y = 0; y < m.height(l); ++y)
    for (int x = 0; x < m.width(l); ++x) {
      Color c = m.texel(l, x, y, WrapMode::Clamp);
      for (int k = 0; k < 3; ++k) acc[k] += c[k];
    }
  double n = double(m.width(l)) * m.height(l);
  return Color(float(acc[0] / n), float(acc[1] / n), float(acc[2] / n));
}

Color image_mean(const ImageData& img) {
  double acc[3] = {0, 0, 0};
  size_t n = size_t(img.width) * img.height;
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) acc[k] += img.pixels[i * img.channels + (img.channels >= 3 ? k : 0)];
  return Color(float(acc[0] / n), float(acc[1] / n), float(acc[2] / n));
}

int wrap_ref(int i, int n, WrapMode w) {
  if (w == WrapMode::Clamp) return std::min(std::max(i, 0), n - 1);
  if (w == WrapMode::Repeat) return ((i % n) + n) % n;
  int p = ((i % (2 * n)) + 2 * n) % (2 * n);
  return p < n ? p : 2 * n - 1 - p;
}

/// Independent bilinear reference on the raw pixels (texel centres at (i + 0.5) / w).
Color bilinear_ref(const ImageData& img, double s, double t, WrapMode w) {
  double x = s * img.width - 0.5, y = t * img.height - 0.5;
  double fx = std::floor(x), fy = std::floor(y);
  double ax = x - fx, ay = y - fy;
  Color out(0.f);
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      int xi = wrap_ref(int(fx) + dx, img.width, w), yi = wrap_ref(int(fy) + dy, img.height, w);
      double wgt = (dx ? ax : 1 - ax) * (dy ? ay : 1 - ay);
      size_t p = (size_t(yi) * img.width + xi) * img.channels;
      for (int k = 0; k < 3; ++k) out[k] += float(wgt * img.pixels[p + (img.channels >= 3 ? k : 0)]);
    }
  return out;
}

void expect_near(const Color& a, const Color& b, float tol, const std::string& what) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], tol) << what << " channel " << k;
}

const WrapMode k_wraps[] = {WrapMode::Repeat, WrapMode::Clamp, WrapMode::Mirror};
const char* wrap_name(WrapMode w) { return w == WrapMode::Repeat ? "repeat" : w == WrapMode::Clamp ? "clamp" : "mirror"; }

std::shared_ptr<Texture> texture(const ImageData& img, WrapMode wrap, Vec2f uv_scale = {1.f, 1.f},
                                 Vec2f uv_offset = {0.f, 0.f}, float rotation = 0.f) {
  ImageTextureOptions o;
  o.wrap = wrap;
  o.uv_scale = uv_scale;
  o.uv_offset = uv_offset;
  o.uv_rotation_degrees = rotation;
  return make_image_texture(std::make_shared<const MipMap>(img), o);
}

std::string error_of(const ParamSet& p) {
  try {
    create_texture("image", p, "texture 3");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(image, mip_level_sizes_halve_rounding_down) {
  MipMap npot(random_image(57, 43, 3, 1));
  const int expect[][2] = {{57, 43}, {28, 21}, {14, 10}, {7, 5}, {3, 2}, {1, 1}};
  ASSERT_EQ(npot.levels(), 6);
  for (int l = 0; l < 6; ++l) {
    EXPECT_EQ(npot.width(l), expect[l][0]) << "level " << l;
    EXPECT_EQ(npot.height(l), expect[l][1]) << "level " << l;
  }
  MipMap pot(random_image(64, 16, 1, 2));
  ASSERT_EQ(pot.levels(), 7);  // 64x16 ... 4x1, 2x1, 1x1
  EXPECT_EQ(pot.width(4), 4);
  EXPECT_EQ(pot.height(4), 1);
  EXPECT_EQ(pot.width(6), 1);
  EXPECT_EQ(pot.height(6), 1);
}

TEST(image, box_levels_preserve_the_mean_and_average_2x2_blocks) {
  ImageData img = random_image(64, 32, 3, 7);
  MipMap m(img);
  Color mean0 = level_mean(m, 0);
  expect_near(mean0, image_mean(img), 1e-6f, "level 0");
  for (int l = 1; l < m.levels(); ++l) expect_near(level_mean(m, l), mean0, 1e-5f, "level " + std::to_string(l));
  // Power-of-two: level 1 texels are exactly the 2x2 box averages of level 0.
  for (int y = 0; y < m.height(1); ++y)
    for (int x = 0; x < m.width(1); ++x) {
      Color box = (m.texel(0, 2 * x, 2 * y, WrapMode::Clamp) + m.texel(0, 2 * x + 1, 2 * y, WrapMode::Clamp) +
                   m.texel(0, 2 * x, 2 * y + 1, WrapMode::Clamp) + m.texel(0, 2 * x + 1, 2 * y + 1, WrapMode::Clamp)) *
                  0.25f;
      expect_near(m.texel(1, x, y, WrapMode::Clamp), box, 1e-6f, "level 1 texel");
    }
}

TEST(image, non_power_of_two_levels_preserve_the_mean) {
  ImageData img = random_image(57, 43, 4, 11);  // RGBA: alpha ignored
  MipMap m(img);
  Color mean0 = image_mean(img);
  for (int l = 0; l < m.levels(); ++l) expect_near(level_mean(m, l), mean0, 1e-5f, "level " + std::to_string(l));
  expect_near(m.average(), mean0, 1e-6f, "average()");
}

TEST(image, odd_sizes_use_the_polyphase_box_weights) {
  // 5 -> 2 texels: output 0 covers [0, 2.5): weights 0.4, 0.4, 0.2 (Guthe & Heckbert).
  ImageData img;
  img.width = 5;
  img.height = 1;
  img.channels = 1;
  img.pixels = {1.f, 2.f, 4.f, 8.f, 16.f};
  MipMap m(img);
  ASSERT_EQ(m.width(1), 2);
  EXPECT_NEAR(m.texel(1, 0, 0, WrapMode::Clamp).x, 0.4f * 1 + 0.4f * 2 + 0.2f * 4, 1e-6f);
  EXPECT_NEAR(m.texel(1, 1, 0, WrapMode::Clamp).x, 0.2f * 4 + 0.4f * 8 + 0.4f * 16, 1e-6f);
  EXPECT_NEAR(m.texel(2, 0, 0, WrapMode::Clamp).x, (1 + 2 + 4 + 8 + 16) / 5.f, 1e-5f);
}

TEST(image, footprint_zero_is_bilinear) {
  ImageData img = random_image(23, 17, 3, 5);
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> u(-1.5f, 2.5f);
  for (WrapMode w : k_wraps) {
    auto tex = texture(img, w);
    for (int i = 0; i < 200; ++i) {
      float s = u(rng), v = u(rng);
      // Texture space has v up: image t = 1 - v.
      expect_near(tex->eval(Vec2f(s, v), 0.f), bilinear_ref(img, s, 1.0 - double(v), w), 2e-5f,
                  std::string("wrap ") + wrap_name(w));
    }
  }
}

TEST(image, huge_footprint_is_the_image_average) {
  ImageData img = random_image(40, 24, 3, 8);
  Color mean = image_mean(img);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-3.f, 3.f);
  for (WrapMode w : k_wraps) {
    auto tex = texture(img, w);
    expect_near(tex->average(), mean, 1e-6f, "average()");
    for (int i = 0; i < 50; ++i)
      expect_near(tex->eval(Vec2f(u(rng), u(rng)), 1e3f), mean, 1e-5f, std::string("wrap ") + wrap_name(w));
  }
}

TEST(image, footprint_selects_and_blends_mip_levels) {
  ImageData img = random_image(64, 64, 3, 21);
  MipMap m(img);
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < 50; ++i) {
    float s = u(rng), t = u(rng);
    // A footprint of 2^k texels is level k; 2^(k + 0.25) blends levels k and k+1 3:1.
    for (int k = 0; k < 6; ++k) {
      float w = std::ldexp(1.f, k) / 64.f;
      expect_near(m.lookup(s, t, w, WrapMode::Repeat), m.bilinear(k, s, t, WrapMode::Repeat), 1e-5f,
                  "level " + std::to_string(k));
      Color blend = m.bilinear(k, s, t, WrapMode::Repeat) * 0.75f + m.bilinear(k + 1, s, t, WrapMode::Repeat) * 0.25f;
      expect_near(m.lookup(s, t, w * std::exp2(0.25f), WrapMode::Repeat), blend, 1e-5f,
                  "between levels " + std::to_string(k) + " and " + std::to_string(k + 1));
    }
  }
}

TEST(image, filtering_a_one_texel_checkerboard_gives_grey) {
  ImageData img;
  img.width = img.height = 32;
  img.channels = 1;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) img.pixels.push_back(float((x + y) & 1));
  auto tex = texture(img, WrapMode::Repeat);
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  double point_dev = 0;
  for (int i = 0; i < 100; ++i) {
    Vec2f uv(u(rng), u(rng));
    EXPECT_NEAR(tex->eval(uv, 2.f / 32.f).x, 0.5f, 1e-6f);  // 2 texels: level 1 is flat grey
    point_dev += std::fabs(tex->eval(uv, 0.f).x - 0.5f);
  }
  EXPECT_GT(point_dev / 100, 0.1) << "point samples must still see the checks";
}

TEST(image, elliptical_lookup_filters_along_the_major_axis_only) {
  // Vertical one-texel stripes: the value varies along s only.
  ImageData img;
  img.width = img.height = 64;
  img.channels = 1;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) img.pixels.push_back(float(x & 1));
  MipMap m(img);
  const float texel = 1.f / 64.f;
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < 50; ++i) {
    // Texel centres in s, anywhere in t.
    float s = (float(int(u(rng) * 64.f)) + 0.5f) * texel, t = u(rng);
    float point = m.bilinear(0, s, t, WrapMode::Repeat).x;
    // Long along t (8 texels), under a texel wide along s: the stripes survive...
    Color along = m.lookup_ellipse(s, t, Vec2f(0.f, 8.f * texel), Vec2f(0.5f * texel, 0.f), WrapMode::Repeat);
    EXPECT_NEAR(along.x, point, 1e-5f);
    // ...which the isotropic filter over the longer axis blurs to grey,
    EXPECT_NEAR(m.lookup(s, t, 8.f * texel, WrapMode::Repeat).x, 0.5f, 1e-5f);
    // and so does the same ellipse turned across the stripes.
    Color across = m.lookup_ellipse(s, t, Vec2f(8.f * texel, 0.f), Vec2f(0.f, 0.5f * texel), WrapMode::Repeat);
    EXPECT_NEAR(across.x, 0.5f, 0.07f);
  }
}

TEST(image, elliptical_lookup_of_a_circle_is_the_isotropic_lookup) {
  ImageData img = random_image(32, 32, 3, 41);
  MipMap m(img);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < 50; ++i) {
    float s = u(rng), t = u(rng), k = 0.02f + 0.1f * u(rng);
    // Conjugate (not principal) axes of a circle of diameter k sqrt(2).
    Color c = m.lookup_ellipse(s, t, Vec2f(k, k), Vec2f(k, -k), WrapMode::Repeat);
    expect_near(c, m.lookup(s, t, k * std::sqrt(2.f), WrapMode::Repeat), 1e-5f, "circle");
  }
  // Infinitely long ellipses return the average.
  expect_near(m.lookup_ellipse(0.3f, 0.4f, Vec2f(k_inf, 0.f), Vec2f(0.f, 0.01f), WrapMode::Repeat), image_mean(img),
              1e-5f, "infinite");
}

TEST(image, elliptical_lookup_goes_through_the_uv_transform) {
  ImageData img = random_image(32, 32, 3, 51);
  auto plain = texture(img, WrapMode::Repeat);
  const float deg = -40.f, a = deg * k_pi / 180.f, c = std::cos(a), s = std::sin(a);
  const Vec2f scale(3.f, 0.5f), offset(0.25f, 0.5f);
  auto tex = texture(img, WrapMode::Repeat, scale, offset, deg);
  auto M = [&](const Vec2f& v) {
    Vec2f sv(scale.x * v.x, scale.y * v.y);
    return Vec2f(c * sv.x - s * sv.y, s * sv.x + c * sv.y);
  };
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < 50; ++i) {
    Vec2f uv(u(rng), u(rng)), ax(0.05f * u(rng), 0.05f * u(rng)), bx(0.01f * u(rng), -0.01f * u(rng));
    expect_near(tex->eval_ellipse(uv, ax, bx), plain->eval_ellipse(M(uv) + offset, M(ax), M(bx)), 1e-4f, "ellipse");
  }
}

TEST(image, wrap_modes) {
  // A horizontal gradient makes the modes distinguishable.
  ImageData img;
  img.width = 8;
  img.height = 4;
  img.channels = 1;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x) img.pixels.push_back(float(x) + 0.1f * float(y));
  auto rep = texture(img, WrapMode::Repeat), cla = texture(img, WrapMode::Clamp), mir = texture(img, WrapMode::Mirror);
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (float footprint : {0.f, 1.f / 8.f * 1.5f}) {  // level 0 and between levels 0 and 1
    for (int i = 0; i < 50; ++i) {
      float s = u(rng), v = u(rng);
      EXPECT_NEAR(rep->eval(Vec2f(s + 3.f, v - 2.f), footprint).x, rep->eval(Vec2f(s, v), footprint).x, 1e-4f);
      EXPECT_NEAR(mir->eval(Vec2f(-s, v), footprint).x, mir->eval(Vec2f(s, v), footprint).x, 1e-4f);
      EXPECT_NEAR(mir->eval(Vec2f(2.f - s, v), footprint).x, mir->eval(Vec2f(s, v), footprint).x, 1e-4f);
      EXPECT_NEAR(mir->eval(Vec2f(s + 2.f, v), footprint).x, mir->eval(Vec2f(s, v), footprint).x, 1e-4f);
      // Clamp: everything left of the first texel centre is the first column.
      EXPECT_NEAR(cla->eval(Vec2f(-s - 0.5f, v), footprint).x, cla->eval(Vec2f(0.f, v), footprint).x, 1e-5f);
    }
  }
  // The modes really differ: left of the image, repeat sees the right edge, clamp the left.
  EXPECT_NEAR(rep->eval(Vec2f(-1.f / 16.f, 0.5f), 0.f).x, rep->eval(Vec2f(15.f / 16.f, 0.5f), 0.f).x, 1e-5f);
  EXPECT_GT(rep->eval(Vec2f(-1.f / 16.f, 0.5f), 0.f).x, 6.f);
  EXPECT_LT(cla->eval(Vec2f(-1.f / 16.f, 0.5f), 0.f).x, 1.f);
  EXPECT_LT(mir->eval(Vec2f(-1.f / 16.f, 0.5f), 0.f).x, 1.f);
}

TEST(image, uv_transform_is_rotation_after_scale_then_offset) {
  ImageData img = random_image(32, 32, 3, 31);
  auto plain = texture(img, WrapMode::Repeat);
  const Vec2f scale(2.f, 3.f), offset(0.1f, -0.2f);
  const float deg = 30.f, a = deg * k_pi / 180.f, c = std::cos(a), s = std::sin(a);
  auto tex = texture(img, WrapMode::Repeat, scale, offset, deg);
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (float footprint : {0.f, 0.01f, 0.05f}) {
    for (int i = 0; i < 50; ++i) {
      Vec2f uv(u(rng), u(rng));
      Vec2f su(scale.x * uv.x, scale.y * uv.y);                                 // S uv
      Vec2f p(c * su.x - s * su.y + offset.x, s * su.x + c * su.y + offset.y);  // R (S uv) + offset
      // The footprint scales with the larger uv_scale component.
      expect_near(tex->eval(uv, footprint), plain->eval(p, footprint * 3.f), 1e-4f,
                  "footprint " + std::to_string(footprint));
    }
  }
  // The order matters: offset before rotation would be a different map.
  Vec2f uv(0.3f, 0.6f);
  Vec2f wrong(c * (scale.x * uv.x + offset.x) - s * (scale.y * uv.y + offset.y),
              s * (scale.x * uv.x + offset.x) + c * (scale.y * uv.y + offset.y));
  EXPECT_GT(length(tex->eval(uv, 0.f) - plain->eval(wrong, 0.f)), 1e-3f);
}

TEST(image, bad_parameters_name_the_parameter) {
  ParamSet p;
  p.set("filename", std::string("/nonexistent/never/read.png"));
  p.set("uv_scale", std::vector<double>{0.0, 1.0});
  std::string e = error_of(p);
  EXPECT_NE(e.find("uv_scale"), std::string::npos) << e;
  EXPECT_NE(e.find("non-zero"), std::string::npos) << e;

  ParamSet q;
  q.set("filename", std::string("/nonexistent/never/read.png"));
  q.set("uv_scale", std::vector<double>{1.0, 2.0, 3.0});
  e = error_of(q);
  EXPECT_NE(e.find("uv_scale"), std::string::npos) << e;

  ParamSet r;
  r.set("filename", std::string("/nonexistent/never/read.png"));
  r.set("wrap", std::string("tile"));
  e = error_of(r);
  EXPECT_NE(e.find("'wrap'"), std::string::npos) << e;
  EXPECT_NE(e.find("repeat, clamp, mirror"), std::string::npos) << e;

  ParamSet t;
  t.set("filename", std::string("/nonexistent/never/read.png"));
  t.set("uv_offset", std::vector<double>{0.0, NAN});
  e = error_of(t);
  EXPECT_NE(e.find("uv_offset"), std::string::npos) << e;
  EXPECT_NE(e.find("not finite"), std::string::npos) << e;
}

TEST(image_cache, one_load_per_resolved_path_and_colorspace) {
  namespace fs = std::filesystem;
  fs::path dir = fs::temp_directory_path() / ("synthgen_image_cache_" + std::to_string(getpid()));
  fs::create_directories(dir / "sub");
  auto write = [](const fs::path& p, const std::string& content) { std::ofstream(p) << content; };
  write(dir / "a.png", "x");
  write(dir / "b.png", "y");
  fs::create_symlink(dir / "a.png", dir / "link.png");

  int calls = 0;
  ImageCache cache([&](const std::string& path, ColorSpace) {
    ++calls;
    return random_image(4, 4, 3, uint32_t(calls));
  });
  auto a1 = cache.get((dir / "a.png").string(), ColorSpace::SRGB);
  auto a2 = cache.get((dir / "sub" / ".." / "." / "a.png").string(), ColorSpace::SRGB);
  auto a3 = cache.get((dir / "link.png").string(), ColorSpace::SRGB);
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(a1.get(), a2.get());
  EXPECT_EQ(a1.get(), a3.get());
  EXPECT_EQ(cache.loads(), 1u);
  EXPECT_EQ(cache.hits(), 2u);

  auto lin = cache.get((dir / "a.png").string(), ColorSpace::Linear);  // other decoding: other data
  auto b = cache.get((dir / "b.png").string(), ColorSpace::SRGB);
  EXPECT_EQ(calls, 3);
  EXPECT_NE(lin.get(), a1.get());
  EXPECT_NE(b.get(), a1.get());

  // Textures made from the shared pyramid share it (no copy).
  ImageTextureOptions o;
  auto t1 = make_image_texture(a1, o);
  o.wrap = WrapMode::Clamp;
  auto t2 = make_image_texture(cache.get((dir / "a.png").string(), ColorSpace::SRGB), o);
  EXPECT_EQ(calls, 3);
  EXPECT_EQ(a1.use_count(), 5);  // a1, a2, a3, t1, t2

  // An edited file is read again.
  write(dir / "a.png", "longer content");
  auto a4 = cache.get((dir / "a.png").string(), ColorSpace::SRGB);
  EXPECT_EQ(calls, 4);
  EXPECT_NE(a4.get(), a1.get());
  fs::remove_all(dir);
}
