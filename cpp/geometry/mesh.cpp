#include "geometry/mesh.h"

#include <sstream>

#include "core/error.h"

namespace sg {

static bool degenerate(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  Vec3f n = cross(b - a, c - a);
  // Exact zero or an area below float resolution of the edge lengths.
  float l = std::max(length_squared(b - a), length_squared(c - a));
  return !(length_squared(n) > 1e-14f * l * l) || l == 0.f;
}

float TriangleMesh::triangle_area(size_t tri) const {
  const Vec3f& a = positions[indices[3 * tri]];
  const Vec3f& b = positions[indices[3 * tri + 1]];
  const Vec3f& c = positions[indices[3 * tri + 2]];
  return 0.5f * length(cross(b - a, c - a));
}

void TriangleMesh::validate(const std::string& context) const {
  auto fail = [&](const std::string& why) { throw Error(context + ": " + why); };
  if (positions.empty()) fail("mesh has no vertices");
  if (indices.empty()) fail("mesh has no triangles");
  if (indices.size() % 3 != 0) fail("index count " + std::to_string(indices.size()) + " is not a multiple of 3");
  if (!normals.empty() && normals.size() != positions.size())
    fail("normals has " + std::to_string(normals.size()) + " entries, expected one per vertex (" +
         std::to_string(positions.size()) + ")");
  if (!uvs.empty() && uvs.size() != positions.size())
    fail("uvs has " + std::to_string(uvs.size()) + " entries, expected one per vertex (" +
         std::to_string(positions.size()) + ")");
  if (!material_ids.empty() && material_ids.size() != triangle_count())
    fail("material_ids has " + std::to_string(material_ids.size()) + " entries, expected one per triangle (" +
         std::to_string(triangle_count()) + ")");
  for (size_t i = 0; i < positions.size(); ++i)
    if (!is_finite(positions[i])) fail("vertex " + std::to_string(i) + " has a non-finite (NaN or inf) position");
  for (size_t i = 0; i < normals.size(); ++i)
    if (!is_finite(normals[i]) || length_squared(normals[i]) == 0.f)
      fail("normal " + std::to_string(i) + " is zero or not finite");
  for (size_t i = 0; i < uvs.size(); ++i)
    if (!std::isfinite(uvs[i].x) || !std::isfinite(uvs[i].y)) fail("uv " + std::to_string(i) + " is not finite");
  for (size_t i = 0; i < indices.size(); ++i)
    if (indices[i] >= positions.size())
      fail("triangle " + std::to_string(i / 3) + " references vertex " + std::to_string(indices[i]) +
           " but the mesh has " + std::to_string(positions.size()) + " vertices");
  size_t n_degenerate = 0, first = 0;
  for (size_t t = 0; t < triangle_count(); ++t) {
    if (degenerate(positions[indices[3 * t]], positions[indices[3 * t + 1]], positions[indices[3 * t + 2]])) {
      if (n_degenerate++ == 0) first = t;
    }
  }
  if (n_degenerate)
    fail(std::to_string(n_degenerate) + " degenerate (zero-area) triangle(s), the first is triangle " +
         std::to_string(first));
}

size_t TriangleMesh::remove_degenerate_triangles() {
  size_t removed = 0, out = 0;
  for (size_t t = 0; t < triangle_count(); ++t) {
    uint32_t a = indices[3 * t], b = indices[3 * t + 1], c = indices[3 * t + 2];
    bool bad = a >= positions.size() || b >= positions.size() || c >= positions.size() ||
               degenerate(positions[a], positions[b], positions[c]);
    if (bad) {
      ++removed;
      continue;
    }
    indices[3 * out] = a;
    indices[3 * out + 1] = b;
    indices[3 * out + 2] = c;
    if (!material_ids.empty()) material_ids[out] = material_ids[t];
    ++out;
  }
  indices.resize(3 * out);
  if (!material_ids.empty()) material_ids.resize(out);
  return removed;
}

}  // namespace sg
