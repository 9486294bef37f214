// Triangle meshes: the geometry stored in the scene's mesh library.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/math.h"

namespace sg {

/// A primitive defined by its own intersection routine (user extensions' shapes,
/// ext/extension.h), traced as Embree user geometry (geometry/accel.cpp) and instanced like a
/// mesh. Implementations must be thread-safe and deterministic.
class UserShape {
 public:
  virtual ~UserShape() = default;
  /// Object-space bounds holding every hit.
  virtual Bounds3 bounds() const = 0;
  /// Closest hit of the object-space ray o + t d (d need not be unit length) with
  /// t_min < t < t_max: true and its t, outward unit normal and surface coordinates.
  virtual bool intersect(const Vec3f& o, const Vec3f& d, float t_min, float t_max, float* t, Vec3f* n,
                         Vec2f* uv) const = 0;
  /// What went wrong while tracing (invalid hits), "" when nothing did.
  virtual std::string failure() const { return {}; }
};

/// An indexed triangle mesh in object space, or (`shape` set, no triangles) a user shape.
struct TriangleMesh {
  std::string name;
  std::vector<Vec3f> positions;
  std::vector<Vec3f> normals;  ///< optional, one per vertex (shading normals)
  std::vector<Vec2f> uvs;      ///< optional, one per vertex
  std::vector<uint32_t> indices;  ///< three per triangle
  /// Optional, one per triangle: scene material id, or -1 for "use the instance's material".
  std::vector<int32_t> material_ids;
  /// A user shape instead of triangles (positions and indices then stay empty).
  std::shared_ptr<const UserShape> shape;

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
