// Test meshes shared by the scene tests (test_scene_api.cpp, test_all_hits.cpp).
#pragma once

#include <cstdint>

#include "geometry/mesh.h"

namespace sgtest {

/// The closed axis-aligned box [lo, hi]: 8 vertices, 12 triangles.
inline sg::TriangleMesh box(const sg::Vec3f& lo, const sg::Vec3f& hi) {
  sg::TriangleMesh m;
  m.name = "box";
  for (int i = 0; i < 8; ++i)
    m.positions.push_back(sg::Vec3f((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z));
  const uint32_t f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (auto& t : f) m.indices.insert(m.indices.end(), {t[0], t[1], t[2]});
  return m;
}

}  // namespace sgtest
