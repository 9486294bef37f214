// Procedural noise (core/noise.h) and the "noise" / "cellular" texture plugins.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/noise.h"
#include "core/params.h"
#include "core/rng.h"
#include "material/normal_mapping.h"
#include "texture/texture.h"

using namespace sg;

namespace {

Vec3f random_point(Pcg32& rng, float extent = 50.f) {
  return Vec3f(rng.next_float(), rng.next_float(), rng.next_float()) * extent - Vec3f(0.5f * extent);
}

struct Stats {
  double mean = 0, var = 0, min = 1e30, max = -1e30;
};
template <class F>
Stats stats(F f, int n = 100000, uint64_t seed = 1) {
  Pcg32 rng(seed);
  double s = 0, s2 = 0;
  Stats st;
  for (int i = 0; i < n; ++i) {
    double v = f(random_point(rng));
    s += v;
    s2 += v * v;
    st.min = std::min(st.min, v);
    st.max = std::max(st.max, v);
  }
  st.mean = s / n;
  st.var = s2 / n - st.mean * st.mean;
  return st;
}

}  // namespace

TEST(noise, deterministic_per_seed) {
  NoiseBasis a(7), b(7), c(8);
  Pcg32 rng(3);
  int differ = 0;
  for (int i = 0; i < 1000; ++i) {
    Vec3f p = random_point(rng);
    ASSERT_EQ(a.perlin(p), b.perlin(p));
    ASSERT_EQ(a.value(p), b.value(p));
    differ += a.perlin(p) != c.perlin(p);
  }
  EXPECT_GT(differ, 900) << "another seed gives another noise";
}

TEST(noise, perlin_statistics) {
  NoiseBasis b(1);
  Stats s = stats([&](const Vec3f& p) { return b.perlin(p); });
  EXPECT_NEAR(s.mean, 0.0, 0.01);
  EXPECT_GE(s.min, -1.0);
  EXPECT_LE(s.max, 1.0);
  EXPECT_GT(s.max, 0.6);
  EXPECT_LT(s.min, -0.6);
  // Zero at lattice points (a gradient noise property).
  for (int i = -3; i <= 3; ++i) EXPECT_EQ(b.perlin(Vec3f(float(i), float(2 * i), float(-i))), 0.f);
  Stats m = stats([&](const Vec3f& p) { return std::fabs(b.perlin(p)); });
  EXPECT_NEAR(m.mean, mean_abs_noise(NoiseKind::Perlin), 0.02 * mean_abs_noise(NoiseKind::Perlin));
  Stats v = stats([&](const Vec3f& p) { return std::fabs(b.value(p)); });
  EXPECT_NEAR(v.mean, mean_abs_noise(NoiseKind::Value), 0.02 * mean_abs_noise(NoiseKind::Value));
  Stats s2 = stats([&](const Vec3f& p) { return b.perlin2(p.x, p.y); });
  EXPECT_NEAR(s2.mean, 0.0, 0.01);
  EXPECT_GE(s2.min, -1.0);
  EXPECT_LE(s2.max, 1.0);
}

// Isotropy: the variance of directional differences is the same along the axes and along
// random directions (within 5%), and the autocorrelation at a fixed lag too.
TEST(noise, perlin_is_isotropic) {
  NoiseBasis b(2);
  const float h = 0.3f;
  std::vector<Vec3f> dirs = {Vec3f(1, 0, 0), Vec3f(0, 1, 0), Vec3f(0, 0, 1), normalize(Vec3f(1, 1, 0)),
                             normalize(Vec3f(1, 1, 1)), normalize(Vec3f(-0.3f, 0.8f, 0.5f))};
  std::vector<double> var;
  for (const Vec3f& d : dirs) {
    Stats s = stats([&](const Vec3f& p) { return b.perlin(p + d * h) - b.perlin(p); }, 200000, 9);
    var.push_back(s.var);
  }
  double ref = 0;
  for (double v : var) ref += v / var.size();
  for (size_t i = 0; i < var.size(); ++i) EXPECT_NEAR(var[i] / ref, 1.0, 0.05) << "direction " << i;
}

TEST(noise, fbm_matches_the_fractal_sum_and_is_band_limited) {
  NoiseBasis b(3);
  FractalParams f;
  f.octaves = 1;
  Pcg32 rng(4);
  for (int i = 0; i < 100; ++i) {
    Vec3f p = random_point(rng);
    EXPECT_EQ(fbm(b, NoiseKind::Perlin, p, f), b.perlin(p)) << "one octave is the basis";
  }
  // Unnormalized: sum of w_i noise(s_i p + o_i) with s_i = l^i, w_i = l^(-H i).
  f.octaves = 4;
  f.lacunarity = 2.5f;
  f.H = 0.7f;
  f.normalize = false;
  for (int i = 0; i < 100; ++i) {
    Vec3f p = random_point(rng);
    double expect = 0, s = 1, w = 1;
    for (int k = 0; k < 4; ++k) {
      expect += w * b.perlin(p * float(s) + Vec3f(17.3f, -41.7f, 29.1f) * float(k));
      s *= 2.5;
      w *= std::pow(2.5, -0.7);
    }
    EXPECT_NEAR(fbm(b, NoiseKind::Perlin, p, f), expect, 1e-5);
  }
  f.normalize = true;
  f.octaves = 6;
  Stats s = stats([&](const Vec3f& p) { return fbm(b, NoiseKind::Perlin, p, f); });
  EXPECT_GE(s.min, -1.0);
  EXPECT_LE(s.max, 1.0);
  // Band-limiting: the variance falls as the footprint grows; beyond the base period the
  // result is the mean (0) exactly.
  double prev = 1e9;
  for (float w : {0.f, 0.05f, 0.2f, 0.8f}) {
    Stats sw = stats([&](const Vec3f& p) { return fbm(b, NoiseKind::Perlin, p, f, w); }, 20000);
    EXPECT_LT(sw.var, prev) << "footprint " << w;
    prev = sw.var;
  }
  Stats wide = stats([&](const Vec3f& p) { return fbm(b, NoiseKind::Perlin, p, f, 1.5f); }, 2000);
  EXPECT_EQ(wide.min, 0.0);
  EXPECT_EQ(wide.max, 0.0);
  EXPECT_EQ(octave_fade(1.f, 0.f), 1.f);
  EXPECT_EQ(octave_fade(1.f, 0.5f), 1.f);
  EXPECT_NEAR(octave_fade(1.f, 0.75f), 0.5f, 1e-6);
  EXPECT_EQ(octave_fade(1.f, 1.f), 0.f);
  EXPECT_EQ(octave_fade(8.f, 0.2f), 0.f);
}

TEST(noise, turbulence_range_and_faded_mean) {
  NoiseBasis b(5);
  FractalParams f;
  Stats s = stats([&](const Vec3f& p) { return turbulence(b, NoiseKind::Perlin, p, f); });
  EXPECT_GE(s.min, 0.0);
  EXPECT_LE(s.max, 1.0);
  Stats wide = stats([&](const Vec3f& p) { return turbulence(b, NoiseKind::Perlin, p, f, 10.f); }, 1000);
  EXPECT_NEAR(wide.mean, mean_abs_noise(NoiseKind::Perlin), 1e-6) << "faded octaves keep the mean brightness";
}

TEST(noise, cellular_distances_are_exact) {
  NoiseBasis b(6);
  // Regular grid (jitter 0): feature points at cell centres.
  CellularResult r = cellular(b, Vec3f(0.5f, 0.5f, 0.5f), 0.f);
  EXPECT_NEAR(r.f1, 0.f, 1e-6);
  EXPECT_NEAR(r.f2, 1.f, 1e-6);
  EXPECT_NEAR(cellular(b, Vec3f(0.8f, 0.5f, 0.5f), 0.f).edge, 0.2f, 1e-5);
  // Jittered: the edge distance is exact: every point closer than it lies in the same cell
  // (same nearest feature point), and the cell changes just beyond it in some direction.
  Pcg32 rng(7);
  auto dir = [&]() {
    Vec3f d;
    do {
      d = Vec3f(rng.next_float(), rng.next_float(), rng.next_float()) * 2.f - Vec3f(1.f);
    } while (length_squared(d) > 1.f || length_squared(d) < 1e-4f);
    return normalize(d);
  };
  for (int i = 0; i < 200; ++i) {
    Vec3f p = random_point(rng, 20.f);
    CellularResult c = cellular(b, p, 1.f);
    ASSERT_LE(c.f1, c.f2);
    ASSERT_GT(c.edge, 0.f);
    for (int k = 0; k < 32; ++k)
      ASSERT_EQ(cellular(b, p + dir() * (0.98f * c.edge), 1.f).cell_hash, c.cell_hash) << "inside the edge distance";
    int changed = 0;
    for (int k = 0; k < 2000 && !changed; ++k) changed += cellular(b, p + dir() * (1.1f * c.edge), 1.f).cell_hash != c.cell_hash;
    ASSERT_TRUE(changed) << "no cell boundary within 1.1 x the edge distance";
  }
}

TEST(noise, color_ramp) {
  ColorRamp r({0.2f, 0.6f, 1.f}, {Color(0, 0, 0), Color(1, 0.5f, 0), Color(1, 1, 1)});
  EXPECT_EQ(r.eval(-1.f), Color(0, 0, 0));
  EXPECT_EQ(r.eval(0.2f), Color(0, 0, 0));
  Color m = r.eval(0.4f);
  EXPECT_NEAR(m.x, 0.5f, 1e-6);
  EXPECT_NEAR(m.y, 0.25f, 1e-6);
  EXPECT_EQ(r.eval(2.f), Color(1, 1, 1));
  EXPECT_THROW(ColorRamp({0.5f, 0.2f}, {Color(0), Color(1)}), Error);
  EXPECT_THROW(ColorRamp({0.5f}, {Color(0), Color(1)}), Error);
}

namespace {
std::shared_ptr<Texture> make(const std::string& type, ParamSet p) { return create_texture(type, p, "test"); }
}  // namespace

// Relative-local mapping: scaling and translating an object (its vertices and bounds) does
// not change the texture at corresponding points.
TEST(noise, relative_local_mapping_is_invariant_to_scale_and_translation) {
  ParamSet p;
  p.set("mapping", std::string("relative"));
  p.set("scale", 3.0);
  auto t = make("noise", p);
  ASSERT_TRUE(t->needs_position());
  Pcg32 rng(8);
  Vec3f lo(-1.f, 0.f, -2.f), hi(1.f, 1.5f, 2.f);
  for (int i = 0; i < 500; ++i) {
    Vec3f f(rng.next_float(), rng.next_float(), rng.next_float());
    TexturePoint a, b;
    a.p_object = lo + (hi - lo) * f;
    a.object_lo = lo;
    a.object_hi = hi;
    const float s = 7.5f;
    const Vec3f t0(100.f, -20.f, 3.f);
    b.p_object = a.p_object * s + t0;
    b.object_lo = lo * s + t0;
    b.object_hi = hi * s + t0;
    Color ca = t->eval_point(a), cb = t->eval_point(b);
    ASSERT_NEAR(ca.x, cb.x, 2e-4f) << i;
  }
}

TEST(noise, plugins_validate_parameters) {
  ParamSet bad;
  bad.set("octavs", int64_t(3));
  try {
    make("noise", bad);
    FAIL() << "unknown key accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("octaves"), std::string::npos) << e.what();
  }
  ParamSet m;
  m.set("mapping", std::string("objct"));
  try {
    make("cellular", m);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'object'"), std::string::npos) << e.what();
  }
  ParamSet ramp;
  ramp.set("ramp_positions", std::vector<double>{0.0, 1.0});
  ramp.set("ramp_colors", std::vector<double>{1, 0, 0});
  EXPECT_THROW(make("noise", ramp), Error);
  ParamSet ok;
  ok.set("output", std::string("edge"));
  ok.set("ramp_positions", std::vector<double>{0.0, 0.1});
  ok.set("ramp_colors", std::vector<double>{0.1, 0.05, 0.0, 0.8, 0.4, 0.1});
  auto t = make("cellular", ok);
  Color avg = t->average();
  EXPECT_GT(avg.x, 0.1f);
  EXPECT_LT(avg.x, 0.8f);
}

// Analytic gradients (bump mapping) against central differences of the values.
TEST(noise, analytic_gradients_match_finite_differences) {
  NoiseBasis b(12);
  Pcg32 rng(13);
  const float h = 1e-3f;
  auto fd = [&](auto f, const Vec3f& p) {
    return Vec3f((f(p + Vec3f(h, 0, 0)) - f(p - Vec3f(h, 0, 0))) / (2 * h),
                 (f(p + Vec3f(0, h, 0)) - f(p - Vec3f(0, h, 0))) / (2 * h),
                 (f(p + Vec3f(0, 0, h)) - f(p - Vec3f(0, 0, h))) / (2 * h));
  };
  FractalParams fp;
  fp.octaves = 4;
  int checked = 0;
  for (int i = 0; i < 500; ++i) {
    Vec3f p = random_point(rng, 10.f);
    Vec3f g;
    float v = b.perlin_grad(p, &g);
    if (std::fabs(v) > 0.99f) continue;  // perlin() clamps there
    Vec3f e = fd([&](const Vec3f& q) { return b.perlin(q); }, p);
    ASSERT_LT(length(g - e), 2e-2f * std::max(1.f, length(e))) << i;
    Vec3f gf;
    fbm_grad(b, p, fp, 0.f, &gf);
    Vec3f ef = fd([&](const Vec3f& q) { return fbm(b, NoiseKind::Perlin, q, fp); }, p);
    ASSERT_LT(length(gf - ef), 5e-2f * std::max(1.f, length(ef))) << i;
    ++checked;
  }
  EXPECT_GT(checked, 400);
  // Through a texture with a relative-local mapping and a remap.
  ParamSet p;
  p.set("mapping", std::string("relative"));
  p.set("scale", 3.0);
  p.set("pattern", std::string("fbm"));
  p.set("remap", std::vector<double>{-0.8, 0.8});
  auto t = create_texture("noise", p, "test");
  int ok = 0;
  for (int i = 0; i < 300; ++i) {
    TexturePoint q;
    q.object_lo = Vec3f(-1.f, 0.f, -2.f);
    q.object_hi = Vec3f(1.f, 3.f, 2.f);
    q.p_object = q.object_lo + (q.object_hi - q.object_lo) * Vec3f(rng.next_float(), rng.next_float(), rng.next_float());
    Vec3f g;
    bool ws;
    ASSERT_TRUE(t->eval_gradient(q, &g, &ws));
    ASSERT_FALSE(ws);
    Vec3f e = fd([&](const Vec3f& x) {
      TexturePoint r = q;
      r.p_object = x;
      return t->eval_point(r).x;
    }, q.p_object);
    // The remap clamps (kinks) at its ends: points next to them may differ.
    if (length(g - e) < 5e-2f * std::max(1.f, length(e))) ++ok;
  }
  EXPECT_GT(ok, 294);
}

// bump_normal (no uv tangent, no copy of the interaction) gives the normal apply_bump_map
// computes in the uv tangent frame: the tangent-plane gradient does not depend on the frame.
TEST(noise, bump_normal_equals_apply_bump_map_for_3d_heights) {
  ParamSet p;
  p.set("mapping", std::string("object"));
  p.set("scale", 7.0);
  p.set("pattern", std::string("turbulence"));
  p.set("octaves", int64_t(3));
  auto height = create_texture("noise", p, "test");
  // A rotated and scaled instance: the gradient goes through the inverse transform.
  float m[16] = {0.f, -2.f, 0.f, 1.f, 2.f, 0.f, 0.f, -3.f, 0.f, 0.f, 2.f, 0.5f, 0.f, 0.f, 0.f, 1.f};
  Transform world_from_object = Transform::from_row_major(m, "test");
  Pcg32 rng(14);
  int tilted = 0;
  for (int i = 0; i < 300; ++i) {
    SurfaceInteraction si;
    Vec3f n = normalize(Vec3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() + 0.2f));
    si.ng = si.ns = n;
    Vec3f t = normalize(cross(n, Vec3f(0.3f, 1.f, 0.1f)));
    si.dpdu = t;  // the uv tangent apply_bump_map uses
    si.p_object = Vec3f(rng.next_float(), rng.next_float(), rng.next_float()) * 3.f;
    si.p = world_from_object.apply_point(si.p_object);
    si.world_from_object = &world_from_object;
    SurfaceInteraction a = si;
    apply_bump_map(&a, *height, 0.02f);
    SurfaceInteraction b = si;
    b.dpdu = Vec3f(0.f);  // bump_normal's case: no tangent
    Vec3f nb = bump_normal(b, *height, 0.02f);
    ASSERT_LT(length(nb - a.ns), 1e-4f) << i;
    ASSERT_NEAR(length(nb), 1.f, 1e-5f);
    Color cached;
    int tag;
    const char* key = bump_cache_key(*height, 0.02f, &tag);
    ASSERT_TRUE(b.tex_cache.find(key + 1, tag, &cached) && cached == nb) << "kept for the hit's other calls";
    tilted += dot(nb, n) < 0.9999f;
  }
  EXPECT_GT(tilted, 250) << "the bump changes the normal";
}
