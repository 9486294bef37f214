// Furnace test of the whole renderer (sg::Scene + path tracer): inside a closed
// enclosure whose walls all emit radiance Le and reflect diffusely with albedo rho, the
// radiance is the same everywhere and in every direction, L = Le + rho L, so every
// pixel converges to Le / (1 - rho). This holds for any closed enclosure (the flat
// facets of the icosphere are fine) and exercises light sampling, BSDF sampling, MIS,
// Russian roulette and ray spawning together.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "api/scene.h"
#include "core/params.h"

using namespace sg;

namespace {

/// Icosphere of radius r (subdivided icosahedron). `inward` flips the winding so that
/// the geometric normals point into the sphere.
TriangleMesh icosphere(int subdivisions, float r, bool inward) {
  const float t = (1.f + std::sqrt(5.f)) / 2.f;
  std::vector<Vec3f> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p = normalize(p);
  std::vector<std::array<uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(normalize(v[a] + v[b]));
      return mid[key] = uint32_t(v.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> nf;
    for (auto& tri : f) {
      uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      nf.push_back({tri[0], a, c});
      nf.push_back({tri[1], b, a});
      nf.push_back({tri[2], c, b});
      nf.push_back({a, b, c});
    }
    f = nf;
  }
  TriangleMesh m;
  m.name = "icosphere";
  for (auto& p : v) m.positions.push_back(p * r);
  for (auto& tri : f) {
    // The icosahedron above winds counter-clockwise seen from outside (outward normals).
    m.indices.push_back(tri[0]);
    m.indices.push_back(inward ? tri[2] : tri[1]);
    m.indices.push_back(inward ? tri[1] : tri[2]);
  }
  return m;
}

/// Renders the inside of an emitting, reflecting icosphere; returns the mean pixel value.
Color furnace_mean(const Color& le, const Color& rho, bool two_sided, bool inward, uint32_t spp, uint64_t seed,
                   Film* film_out = nullptr) {
  Scene scene;
  TriangleMesh sphere = icosphere(2, 3.f, inward);
  // Winding sanity: the first triangle's normal points inwards iff `inward`.
  Vec3f p0 = sphere.positions[sphere.indices[0]], p1 = sphere.positions[sphere.indices[1]],
        p2 = sphere.positions[sphere.indices[2]];
  EXPECT_EQ(dot(cross(p1 - p0, p2 - p0), p0) < 0.f, inward);
  uint32_t mesh = scene.add_mesh(std::move(sphere));
  ParamSet p;
  p.set("radiance", std::vector<double>{le.x, le.y, le.z});
  p.set("albedo", std::vector<double>{rho.x, rho.y, rho.z});
  p.set("two_sided", two_sided);
  uint32_t mat = scene.add_material("emissive", p);
  scene.add_instance(mesh, Transform::translate(Vec3f(0.5f, -1.f, 2.f)), 1, std::nullopt, mat);
  scene.set_camera(PinholeCamera::from_fov(
      70.f, 32, 32, PinholeCamera::look_at(Vec3f(1.2f, -0.5f, 1.5f), Vec3f(3.f, 0.f, 3.f), Vec3f(0.f, 0.f, 1.f))));
  RenderSettings s;
  s.spp = spp;
  s.max_depth = 64;  // rho^63 < 1e-6 for rho <= 0.8: truncation is negligible
  s.rr_depth = 5;
  s.seed = seed;
  Film film;
  scene.render(s, &film);
  EXPECT_EQ(film.stats.nan_samples, 0u);
  double sum[3] = {0, 0, 0};
  for (size_t i = 0; i < film.rgb.size(); i += 3)
    for (int k = 0; k < 3; ++k) sum[k] += film.rgb[i + k];
  double n = double(film.width) * film.height;
  for (float a : film.alpha) EXPECT_EQ(a, 1.f) << "a camera ray escaped the closed sphere";
  if (film_out) *film_out = film;
  return Color(float(sum[0] / n), float(sum[1] / n), float(sum[2] / n));
}

void expect_furnace(const Color& mean, const Color& le, const Color& rho, const char* what) {
  for (int k = 0; k < 3; ++k) {
    double expected = le[k] / (1.0 - rho[k]);
    EXPECT_NEAR(mean[k] / expected, 1.0, 5e-3)
        << what << ", channel " << k << ": mean " << mean[k] << ", expected Le / (1 - rho) = " << expected;
  }
}

}  // namespace

// One-sided emitter with inward normals; per-channel albedos 0.5, 0.8 and 0.3.
TEST(furnace, one_sided_inward_converges_to_le_over_one_minus_rho) {
  const Color le(1.f, 0.5f, 2.f), rho(0.5f, 0.8f, 0.3f);
  expect_furnace(furnace_mean(le, rho, false, true, 256, 11), le, rho, "one-sided, inward normals");
}

// Two-sided emitter with outward normals: the inside sees the back faces.
TEST(furnace, two_sided_outward_converges_to_le_over_one_minus_rho) {
  const Color le(0.7f), rho(0.8f, 0.5f, 0.65f);
  expect_furnace(furnace_mean(le, rho, true, false, 256, 12), le, rho, "two-sided, outward normals");
}

// One-sided emitter whose front faces point outwards: seen from inside, no wall emits,
// so all that is left to reflect is darkness and the image is exactly black.
TEST(furnace, one_sided_facing_away_is_dark) {
  Color m = furnace_mean(Color(1.f), Color(0.8f), false, false, 4, 13);
  EXPECT_EQ(m, Color(0.f));
}
