// surface_distances (geometry/accel.h): Embree point queries against brute force over every
// triangle, and analytic distances to a square.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"
#include "geometry/accel.h"

namespace sg {
namespace {

// Distance from p to triangle (a, b, c) by brute force: the face when the projection lies
// inside, else the closest of the three edges (clamped segment projections).
float brute_distance(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  auto seg = [&](const Vec3f& u, const Vec3f& v) {
    const Vec3f d = v - u;
    const float t = std::clamp(dot(p - u, d) / dot(d, d), 0.f, 1.f);
    return length(p - (u + d * t));
  };
  float best = std::min({seg(a, b), seg(b, c), seg(c, a)});
  const Vec3f n = normalize(cross(b - a, c - a));
  const Vec3f q = p - n * dot(p - a, n);
  const bool inside = dot(cross(b - a, q - a), n) >= 0.f && dot(cross(c - b, q - b), n) >= 0.f &&
                      dot(cross(a - c, q - c), n) >= 0.f;
  if (inside) best = std::min(best, std::abs(dot(p - a, n)));
  return best;
}

TEST(SurfaceDistances, MatchBruteForceOnARandomMesh) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  TriangleMesh mesh;
  mesh.name = "random";
  for (int i = 0; i < 600; ++i) mesh.positions.emplace_back(u(rng), u(rng), u(rng));
  for (uint32_t i = 0; i < 200; ++i) mesh.indices.insert(mesh.indices.end(), {3 * i, 3 * i + 1, 3 * i + 2});
  std::vector<Vec3f> points;
  for (int i = 0; i < 500; ++i) points.emplace_back(2.f * u(rng), 2.f * u(rng), 2.f * u(rng));
  std::vector<uint32_t> closest;
  const std::vector<float> d = surface_distances(mesh, points, &closest);
  ASSERT_EQ(d.size(), points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    float best = k_inf;
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
      const uint32_t* f = &mesh.indices[3 * t];
      best = std::min(best, brute_distance(points[i], mesh.positions[f[0]], mesh.positions[f[1]], mesh.positions[f[2]]));
    }
    EXPECT_NEAR(d[i], best, 1e-5f) << "point " << i;
    const uint32_t* f = &mesh.indices[3 * closest[i]];
    EXPECT_NEAR(brute_distance(points[i], mesh.positions[f[0]], mesh.positions[f[1]], mesh.positions[f[2]]), d[i],
                1e-5f);
  }
}

TEST(SurfaceDistances, AnalyticSquareAndErrors) {
  TriangleMesh sq;
  sq.name = "square";
  sq.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  sq.indices = {0, 1, 2, 0, 2, 3};
  const auto d = surface_distances(sq, {{0.5f, 0.5f, 2.f}, {2.f, 0.5f, 0.f}, {2.f, 2.f, 1.f}});
  EXPECT_NEAR(d[0], 2.f, 1e-6f);
  EXPECT_NEAR(d[1], 1.f, 1e-6f);
  EXPECT_NEAR(d[2], std::sqrt(3.f), 1e-6f);
  EXPECT_THROW(surface_distances(TriangleMesh{}, {{0, 0, 0}}), Error);
  EXPECT_THROW(surface_distances(sq, {{std::nanf(""), 0, 0}}), Error);
  sq.indices[5] = 9;
  EXPECT_THROW(surface_distances(sq, {{0, 0, 0}}), Error);
}

}  // namespace
}  // namespace sg
