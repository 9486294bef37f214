// Ray-traversal acceleration: one Embree BVH per mesh, instanced into a
// top-level BVH. accel.cpp is the only file of synthgen that includes Embree.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/math.h"
#include "geometry/mesh.h"

namespace sg {

/// Result of a closest-hit query. `inst` is the instance slot, `prim` the triangle index,
/// (u, v) the barycentric coordinates of vertices 1 and 2.
/// For user shapes (TriangleMesh::shape), (u, v) are the shape's surface coordinates and
/// `ng` its object-space unit normal (for triangles, Embree's unnormalized geometric normal).
struct RayHit {
  float t = k_inf;
  float u = 0.f, v = 0.f;
  Vec3f ng{0.f};
  uint32_t prim = 0;
  uint32_t inst = 0;
};

/// Number of rays traced together with Embree's packet traversal.
constexpr int k_packet_size = 16;

/// Up to k_packet_size rays traced together. Lanes with valid[i] == 0 are ignored.
struct RayPacket {
  float ox[k_packet_size], oy[k_packet_size], oz[k_packet_size], dx[k_packet_size], dy[k_packet_size],
      dz[k_packet_size], t_max[k_packet_size];
  int valid[k_packet_size];
  void set(int i, const Ray& r) {
    ox[i] = r.o.x; oy[i] = r.o.y; oz[i] = r.o.z;
    dx[i] = r.d.x; dy[i] = r.d.y; dz[i] = r.d.z;
    t_max[i] = r.t_max;
    valid[i] = -1;
  }
  Ray get(int i) const {
    Ray r;
    r.o = Vec3f(ox[i], oy[i], oz[i]);
    r.d = Vec3f(dx[i], dy[i], dz[i]);
    r.t_max = t_max[i];
    return r;
  }
};

struct HitPacket {
  RayHit hit[k_packet_size];
  bool found[k_packet_size];
};

/// Which instances a query sees. Every instance belongs to the full scene; catcher instances
/// (stand-ins of a photo's world: its ground, proxy geometry; see Scene::set_instance_catcher)
/// also to the catcher layer, which differential rendering traces as "the scene without the
/// inserted objects". NOTE: Embree ray masks (rtcSetGeometryMask; Debian's Embree has
/// RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED): an instance is seen when ray mask & geometry mask != 0.
enum class RayLayer : uint32_t { all = 0xffffffffu, catchers = 0x2u };

/// Alpha test of a candidate hit (cut-outs): instance slot, triangle, barycentrics (u, v)
/// of vertices 1 and 2. Returns false when the hit is to be ignored (no surface there).
/// Called from inside Embree traversal, for meshes built with needs_alpha_test only, by
/// every query (closest hit, occlusion, single and packet); must be thread-safe and
/// deterministic. The geometry layer knows nothing of materials: the integration layer
/// installs the test (Accel::set_alpha_test).
using AlphaTest = bool (*)(const void* user, uint32_t inst, uint32_t prim, float u, float v);

/// Accel::all_hits' callback: one accepted hit of the ray on instance slot `inst`.
using HitVisitor = void (*)(void* user, uint32_t inst);

/// Distance from each point to the closest point of the mesh's surface: exact (closest point
/// on each candidate triangle), with Embree point queries over a BVH of the triangles built for
/// the call. Measures how far a model's level of detail strays from its finest level
/// (synthgen.scene.lod). With `closest`, also the index of each point's closest triangle.
/// Throws sg::Error on an empty mesh, out-of-range indices or non-finite points.
std::vector<float> surface_distances(const TriangleMesh& mesh, const std::vector<Vec3f>& points,
                                     std::vector<uint32_t>* closest = nullptr);

class Accel {
 public:
  Accel();
  ~Accel();
  Accel(const Accel&) = delete;
  Accel& operator=(const Accel&) = delete;

  /// Builds (or rebuilds) the bottom-level BVH of mesh slot `mesh_slot` (a user shape's: one
  /// Embree user primitive calling UserShape::intersect; the mesh keeps the shape alive). With
  /// `needs_alpha_test`, hits on it are filtered by the alpha test (Embree filter functions).
  /// Switching a mesh's alpha test on or off takes a rebuild (Embree re-commits the scene).
  void build_mesh(uint32_t mesh_slot, const TriangleMesh& mesh, bool needs_alpha_test = false);
  /// Whether mesh `mesh_slot` was built with the alpha test (false for unknown slots).
  bool mesh_alpha_tested(uint32_t mesh_slot) const;
  /// Installs the alpha test used for meshes built with needs_alpha_test (null: accept all).
  void set_alpha_test(AlphaTest test, const void* user);
  void release_mesh(uint32_t mesh_slot);
  /// Adds or updates the top-level instance `inst_slot` of mesh `mesh_slot`; a `catcher`
  /// instance is also seen by RayLayer::catchers queries.
  void set_instance(uint32_t inst_slot, uint32_t mesh_slot, const Transform& world_from_object, bool catcher = false);
  void remove_instance(uint32_t inst_slot);
  /// Rebuilds the top-level BVH (cheap: one leaf per instance).
  void commit();

  bool intersect(const Ray& ray, RayHit* hit, RayLayer layer = RayLayer::all) const;
  bool occluded(const Ray& ray, RayLayer layer = RayLayer::all) const;
  /// Packet versions: identical results per lane to intersect() / occluded(). Sparse
  /// packets (at most 3 active lanes) are traced as single rays.
  void intersect_packet(const RayPacket& rays, HitPacket* hits, RayLayer layer = RayLayer::all) const;
  void occluded_packet(const RayPacket& rays, bool occluded[k_packet_size], RayLayer layer = RayLayer::all) const;
  /// Every hit along the ray in [0, t_max], not only the closest: `visit` is called for each
  /// candidate hit that passes the alpha test (a triangle, or a user shape's closest hit), with
  /// its instance slot; an instance may be reported more than once, in no particular order.
  /// An instance is reported exactly when intersect() would find a hit on it were it the only
  /// instance in the scene (same ray, same triangle tests, same cut-outs): amodal masks of
  /// every object from one ray per pixel (Scene::instance_coverage). Deterministic.
  void all_hits(const Ray& ray, HitVisitor visit, void* user, RayLayer layer = RayLayer::all) const;

  /// Number of bottom-level (per-mesh) BVH builds since construction.
  uint64_t mesh_builds() const { return m_mesh_builds; }
  uint64_t top_level_builds() const { return m_top_builds; }
  /// Number of candidate hits alpha-tested so far (0 while no mesh needs the test).
  uint64_t alpha_test_calls() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  uint64_t m_mesh_builds = 0;
  uint64_t m_top_builds = 0;
};

}  // namespace sg
