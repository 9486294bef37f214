// Triangle meshes: the geometry stored in the scene's mesh library.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"

namespace sg {

/// An indexed triangle mesh in object space.
struct TriangleMesh {
  std::string name;
  std::vector<Vec3f> positions;
  std::vector<Vec3f> normals;  ///< optional, one per vertex (shading normals)
  std::vector<Vec2f> uvs;      ///< optional, one per vertex
  std::vector<uint32_t> indices;  ///< three per triangle
  /// Optional, one per triangle: scene material id, or -1 for "use the instance's material".
  std::vector<int32_t> material_ids;

  size_t triangle_count() const { return indices.size() / 3; }
  size_t vertex_count() const { return positions.size(); }

  /// Throws sg::Error (prefixed by `context`) on empty meshes, non-finite values,
  /// out-of-range indices, mismatched attribute sizes and degenerate (zero-area) triangles.
  void validate(const std::string& context) const;

  /// Removes zero-area triangles; returns how many were removed (used by file import,
  /// where real-world meshes often contain a few slivers).
  size_t remove_degenerate_triangles();

  /// Object-space area of triangle `tri`.
  float triangle_area(size_t tri) const;
};

}  // namespace sg
