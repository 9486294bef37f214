#include "geometry/accel.h"

#include <embree3/rtcore.h>

#include <atomic>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "core/error.h"

namespace sg {

struct Accel::Impl {
  RTCDevice device = nullptr;
  RTCScene top = nullptr;
  std::unordered_map<uint32_t, RTCScene> meshes;
  std::unordered_map<uint32_t, RTCGeometry> instances;
  std::unordered_map<uint32_t, uint32_t> instance_mesh;
  std::unordered_set<uint32_t> alpha_meshes;  ///< mesh slots built with the alpha test
  AlphaTest alpha_test = nullptr;
  const void* alpha_user = nullptr;
  mutable std::atomic<uint64_t> alpha_calls{0};
  std::string last_error;
};

namespace {

/// The intersect context of every query: Embree passes it unchanged to filter functions,
/// so the alpha test and its user pointer travel with the ray.
/// NOTE: Embree 3 allows a user struct that begins with RTCIntersectContext (API manual,
/// rtcInitIntersectContext: "the context can be extended with additional data").
struct QueryContext {
  RTCIntersectContext embree;  // must be first
  AlphaTest test;
  const void* user;
  uint32_t calls;  ///< candidate hits alpha-tested during this query
  HitVisitor visit;  ///< all_hits: receives every accepted hit, which is then rejected (null otherwise)
  void* visit_user;
};

inline void init_context(QueryContext* c, AlphaTest test, const void* user) {
  rtcInitIntersectContext(&c->embree);
  c->test = test;
  c->user = user;
  c->calls = 0;
  c->visit = nullptr;
  c->visit_user = nullptr;
}

// Intersection and occlusion filter of alpha-tested meshes (N-wide: N = 1 for single rays,
// 8 or 16 for packets). Rejecting a lane (valid = 0) makes Embree continue traversal as if
// the triangle were not there, for the closest hit and for occlusion alike.
void alpha_filter(const RTCFilterFunctionNArguments* args) {
  auto* c = reinterpret_cast<QueryContext*>(args->context);
  if (!c->test) return;
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] == 0) continue;
    ++c->calls;
    uint32_t inst = RTCHitN_instID(args->hit, n, i, 0);
    uint32_t prim = RTCHitN_primID(args->hit, n, i);
    if (!c->test(c->user, inst, prim, RTCHitN_u(args->hit, n, i), RTCHitN_v(args->hit, n, i))) args->valid[i] = 0;
  }
}

// The context filter of all_hits: runs after the geometry's own filter (the alpha test), on the
// hits that passed it (Embree API manual, rtcInitIntersectContext). Each is reported and then
// rejected, so traversal goes on with tfar unchanged and meets every other hit along the ray.
void visit_filter(const RTCFilterFunctionNArguments* args) {
  auto* c = reinterpret_cast<QueryContext*>(args->context);
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] == 0) continue;
    c->visit(c->visit_user, RTCHitN_instID(args->hit, n, i, 0));
    args->valid[i] = 0;
  }
}

// User shapes (TriangleMesh::shape): one user primitive whose callbacks call the shape.
// NOTE: Embree hands user geometry of an instanced scene the ray in the instance's object
// space (API manual, "User Geometry"): t is shared with the world ray since the transform is
// affine; the callback writes the hit (instID from the context) as Embree's triangles do.
void shape_bounds(const RTCBoundsFunctionArguments* args) {
  Bounds3 b = static_cast<const UserShape*>(args->geometryUserPtr)->bounds();
  args->bounds_o->lower_x = b.lo.x; args->bounds_o->lower_y = b.lo.y; args->bounds_o->lower_z = b.lo.z;
  args->bounds_o->upper_x = b.hi.x; args->bounds_o->upper_y = b.hi.y; args->bounds_o->upper_z = b.hi.z;
}

void shape_intersect(const RTCIntersectFunctionNArguments* args) {
  const auto* shape = static_cast<const UserShape*>(args->geometryUserPtr);
  const unsigned n = args->N;
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, n);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, n);
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] != -1) continue;
    Vec3f o(RTCRayN_org_x(ray, n, i), RTCRayN_org_y(ray, n, i), RTCRayN_org_z(ray, n, i));
    Vec3f d(RTCRayN_dir_x(ray, n, i), RTCRayN_dir_y(ray, n, i), RTCRayN_dir_z(ray, n, i));
    float t;
    Vec3f nrm;
    Vec2f uv;
    if (!shape->intersect(o, d, RTCRayN_tnear(ray, n, i), RTCRayN_tfar(ray, n, i), &t, &nrm, &uv)) continue;
    // NOTE: Embree calls no filter for user geometry (the callback would have to): all_hits'
    // hits on shapes are reported here, and not committed.
    if (const auto* c = reinterpret_cast<const QueryContext*>(args->context); c->visit) {
      c->visit(c->visit_user, args->context->instID[0]);
      continue;
    }
    RTCRayN_tfar(ray, n, i) = t;
    RTCHitN_Ng_x(hit, n, i) = nrm.x;
    RTCHitN_Ng_y(hit, n, i) = nrm.y;
    RTCHitN_Ng_z(hit, n, i) = nrm.z;
    RTCHitN_u(hit, n, i) = uv.x;
    RTCHitN_v(hit, n, i) = uv.y;
    RTCHitN_primID(hit, n, i) = args->primID;
    RTCHitN_geomID(hit, n, i) = args->geomID;
    RTCHitN_instID(hit, n, i, 0) = args->context->instID[0];
  }
}

void shape_occluded(const RTCOccludedFunctionNArguments* args) {
  const auto* shape = static_cast<const UserShape*>(args->geometryUserPtr);
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] != -1) continue;
    Vec3f o(RTCRayN_org_x(args->ray, n, i), RTCRayN_org_y(args->ray, n, i), RTCRayN_org_z(args->ray, n, i));
    Vec3f d(RTCRayN_dir_x(args->ray, n, i), RTCRayN_dir_y(args->ray, n, i), RTCRayN_dir_z(args->ray, n, i));
    float t;
    Vec3f nrm;
    Vec2f uv;
    if (shape->intersect(o, d, RTCRayN_tnear(args->ray, n, i), RTCRayN_tfar(args->ray, n, i), &t, &nrm, &uv))
      RTCRayN_tfar(args->ray, n, i) = -k_inf;
  }
}

}  // namespace

/// The flags of the top level and of every mesh's scene (see build_mesh).
constexpr RTCSceneFlags k_scene_flags =
    RTCSceneFlags(int(RTC_SCENE_FLAG_ROBUST) | int(RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION));

static void embree_error(void* user, RTCError code, const char* str) {
  auto* last_error = static_cast<std::string*>(user);
  *last_error = std::string("Embree error ") + std::to_string(int(code)) + ": " + (str ? str : "");
}

/// A triangle geometry with the mesh's vertices and indices copied into Embree's buffers
/// (not committed); null when Embree cannot allocate them (the device's error function says why).
static RTCGeometry triangle_geometry(RTCDevice device, const TriangleMesh& mesh) {
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                         3 * sizeof(float), mesh.positions.size()));
  auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                              3 * sizeof(uint32_t), mesh.triangle_count()));
  if (!v || !idx) {
    rtcReleaseGeometry(geom);
    return nullptr;
  }
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    v[3 * i] = mesh.positions[i].x;
    v[3 * i + 1] = mesh.positions[i].y;
    v[3 * i + 2] = mesh.positions[i].z;
  }
  std::copy(mesh.indices.begin(), mesh.indices.end(), idx);
  return geom;
}

Accel::Accel() : m_impl(new Impl) {
  m_impl->device = rtcNewDevice("verbose=0");
  if (!m_impl->device) throw Error("could not create the Embree device");
  rtcSetDeviceErrorFunction(m_impl->device, embree_error, &m_impl->last_error);
  m_impl->top = rtcNewScene(m_impl->device);
  rtcSetSceneFlags(m_impl->top, k_scene_flags);
  rtcSetSceneBuildQuality(m_impl->top, RTC_BUILD_QUALITY_MEDIUM);
}

Accel::~Accel() {
  for (auto& kv : m_impl->instances) rtcReleaseGeometry(kv.second);
  for (auto& kv : m_impl->meshes) rtcReleaseScene(kv.second);
  if (m_impl->top) rtcReleaseScene(m_impl->top);
  if (m_impl->device) rtcReleaseDevice(m_impl->device);
}

void Accel::build_mesh(uint32_t slot, const TriangleMesh& mesh, bool needs_alpha_test) {
  RTCScene old = nullptr;
  if (auto it = m_impl->meshes.find(slot); it != m_impl->meshes.end()) old = it->second;
  RTCScene scene = rtcNewScene(m_impl->device);
  // NOTE: ROBUST makes Embree use conservative traversal and avoid accuracy-reducing
  // optimizations, so rays do not slip through edges shared by neighbouring triangles
  // (no holes in label masks, no light leaks). It costs about 10% of traversal time
  // (measured on the Cornell box, bench/embree_cbox.py). CONTEXT_FILTER_FUNCTION lets
  // all_hits' context filter see this scene's hits (it must be set on instanced scenes too;
  // Debian's Embree asserts otherwise). Queries without a context filter are unchanged: the
  // default scenario's images were identical bit for bit and as fast (3 frames, 16 spp:
  // 10.73-11.00 s CPU with the flag, 10.70-10.77 s without).
  rtcSetSceneFlags(scene, k_scene_flags);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geom;
  if (mesh.shape) {
    geom = rtcNewGeometry(m_impl->device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geom, 1);
    rtcSetGeometryUserData(geom, const_cast<UserShape*>(mesh.shape.get()));
    rtcSetGeometryBoundsFunction(geom, shape_bounds, nullptr);
    rtcSetGeometryIntersectFunction(geom, shape_intersect);
    rtcSetGeometryOccludedFunction(geom, shape_occluded);
  } else {
    geom = triangle_geometry(m_impl->device, mesh);
  }
  if (!geom) {
    rtcReleaseScene(scene);
    throw Error("Embree could not allocate buffers for mesh '" + mesh.name + "': " + m_impl->last_error);
  }
  if (needs_alpha_test) {
    rtcSetGeometryIntersectFilterFunction(geom, alpha_filter);
    rtcSetGeometryOccludedFilterFunction(geom, alpha_filter);
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(scene, geom, 0);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  m_impl->meshes[slot] = scene;
  if (needs_alpha_test) m_impl->alpha_meshes.insert(slot);
  else m_impl->alpha_meshes.erase(slot);
  ++m_mesh_builds;
  // Instances of this mesh must point to the new scene.
  for (auto& kv : m_impl->instance_mesh)
    if (kv.second == slot) {
      rtcSetGeometryInstancedScene(m_impl->instances[kv.first], scene);
      rtcCommitGeometry(m_impl->instances[kv.first]);
    }
  if (old) rtcReleaseScene(old);
}

void Accel::release_mesh(uint32_t slot) {
  auto it = m_impl->meshes.find(slot);
  if (it == m_impl->meshes.end()) return;
  for (auto& kv : m_impl->instance_mesh)
    if (kv.second == slot) throw Error("mesh " + std::to_string(slot) + " is still used by instance " + std::to_string(kv.first));
  rtcReleaseScene(it->second);
  m_impl->meshes.erase(it);
  m_impl->alpha_meshes.erase(slot);
}

bool Accel::mesh_alpha_tested(uint32_t slot) const { return m_impl->alpha_meshes.count(slot) != 0; }

void Accel::set_alpha_test(AlphaTest test, const void* user) {
  m_impl->alpha_test = test;
  m_impl->alpha_user = user;
}

uint64_t Accel::alpha_test_calls() const { return m_impl->alpha_calls.load(std::memory_order_relaxed); }

void Accel::set_instance(uint32_t inst_slot, uint32_t mesh_slot, const Transform& world_from_object, bool catcher) {
  auto mit = m_impl->meshes.find(mesh_slot);
  if (mit == m_impl->meshes.end()) throw Error("instance refers to mesh " + std::to_string(mesh_slot) + " which has no BVH");
  RTCGeometry geom;
  auto it = m_impl->instances.find(inst_slot);
  if (it == m_impl->instances.end()) {
    geom = rtcNewGeometry(m_impl->device, RTC_GEOMETRY_TYPE_INSTANCE);
    m_impl->instances[inst_slot] = geom;
    rtcAttachGeometryByID(m_impl->top, geom, inst_slot);
  } else {
    geom = it->second;
  }
  m_impl->instance_mesh[inst_slot] = mesh_slot;
  rtcSetGeometryInstancedScene(geom, mit->second);
  float m34[12];
  for (int i = 0; i < 12; ++i) m34[i] = world_from_object.m[i];
  rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, m34);
  // Full-scene rays (mask all) see every instance; catcher-layer rays (mask 0x2) only catchers.
  rtcSetGeometryMask(geom, catcher ? 0x3u : 0x1u);
  rtcCommitGeometry(geom);
}

void Accel::remove_instance(uint32_t inst_slot) {
  auto it = m_impl->instances.find(inst_slot);
  if (it == m_impl->instances.end()) return;
  rtcDetachGeometry(m_impl->top, inst_slot);
  rtcReleaseGeometry(it->second);
  m_impl->instances.erase(it);
  m_impl->instance_mesh.erase(inst_slot);
}

void Accel::commit() {
  m_impl->last_error.clear();
  rtcCommitScene(m_impl->top);
  ++m_top_builds;
  if (!m_impl->last_error.empty()) throw Error("Embree: " + m_impl->last_error);
}

namespace {

/// Embree's single ray and empty hit of a closest-hit query.
RTCRayHit embree_ray_hit(const Ray& ray, RayLayer layer) {
  RTCRayHit rh;
  rh.ray.org_x = ray.o.x;
  rh.ray.org_y = ray.o.y;
  rh.ray.org_z = ray.o.z;
  rh.ray.dir_x = ray.d.x;
  rh.ray.dir_y = ray.d.y;
  rh.ray.dir_z = ray.d.z;
  rh.ray.tnear = 0.f;
  rh.ray.tfar = ray.t_max;
  rh.ray.time = 0.f;
  rh.ray.mask = uint32_t(layer);
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

}  // namespace

bool Accel::intersect(const Ray& ray, RayHit* hit, RayLayer layer) const {
  QueryContext ctx;
  init_context(&ctx, m_impl->alpha_test, m_impl->alpha_user);
  RTCRayHit rh = embree_ray_hit(ray, layer);
  rtcIntersect1(m_impl->top, &ctx.embree, &rh);
  if (ctx.calls) m_impl->alpha_calls.fetch_add(ctx.calls, std::memory_order_relaxed);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  hit->t = rh.ray.tfar;
  hit->u = rh.hit.u;
  hit->v = rh.hit.v;
  hit->ng = Vec3f(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  hit->prim = rh.hit.primID;
  hit->inst = rh.hit.instID[0];
  return true;
}

void Accel::all_hits(const Ray& ray, HitVisitor visit, void* user, RayLayer layer) const {
  QueryContext ctx;
  init_context(&ctx, m_impl->alpha_test, m_impl->alpha_user);
  ctx.embree.filter = visit_filter;
  ctx.visit = visit;
  ctx.visit_user = user;
  RTCRayHit rh = embree_ray_hit(ray, layer);
  rtcIntersect1(m_impl->top, &ctx.embree, &rh);
  if (ctx.calls) m_impl->alpha_calls.fetch_add(ctx.calls, std::memory_order_relaxed);
}

bool Accel::occluded(const Ray& ray, RayLayer layer) const {
  QueryContext ctx;
  init_context(&ctx, m_impl->alpha_test, m_impl->alpha_user);
  RTCRay r;
  r.org_x = ray.o.x;
  r.org_y = ray.o.y;
  r.org_z = ray.o.z;
  r.dir_x = ray.d.x;
  r.dir_y = ray.d.y;
  r.dir_z = ray.d.z;
  r.tnear = 0.f;
  r.tfar = ray.t_max;
  r.time = 0.f;
  r.mask = uint32_t(layer);
  r.id = 0;
  r.flags = 0;
  rtcOccluded1(m_impl->top, &ctx.embree, &r);
  if (ctx.calls) m_impl->alpha_calls.fetch_add(ctx.calls, std::memory_order_relaxed);
  return r.tfar < 0.f;
}

namespace {

// Fills an Embree SoA ray packet of width N from the lanes listed in `lanes`.
template <int N, class R>
void fill_rays(const RayPacket& rays, const int* lanes, int n, R& r, int* valid, uint32_t mask) {
  for (int k = 0; k < N; ++k) {
    int i = lanes[k < n ? k : 0];
    valid[k] = k < n ? -1 : 0;
    r.org_x[k] = rays.ox[i];
    r.org_y[k] = rays.oy[i];
    r.org_z[k] = rays.oz[i];
    r.dir_x[k] = rays.dx[i];
    r.dir_y[k] = rays.dy[i];
    r.dir_z[k] = rays.dz[i];
    r.tnear[k] = 0.f;
    r.tfar[k] = rays.t_max[i];
    r.time[k] = 0.f;
    r.mask[k] = mask;
    r.id[k] = 0;
    r.flags[k] = 0;
  }
}

template <int N, class RH>
void scatter_hits(const RH& rh, const int* lanes, int n, HitPacket* hits) {
  for (int k = 0; k < n; ++k) {
    int i = lanes[k];
    hits->found[i] = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
    if (!hits->found[i]) continue;
    RayHit& h = hits->hit[i];
    h.t = rh.ray.tfar[k];
    h.u = rh.hit.u[k];
    h.v = rh.hit.v[k];
    h.ng = Vec3f(rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]);
    h.prim = rh.hit.primID[k];
    h.inst = rh.hit.instID[0][k];
  }
}

}  // namespace

// NOTE: active lanes are compacted; when at most 8 remain, the 8-wide Embree kernel is
// used (a 16-wide traversal costs the same for 5 rays as for 16), and a packet query costs
// about as much as a few single-ray queries, so at most 3 lanes are traced as single rays
// (measured with bench/embree_cbox.py).
void Accel::intersect_packet(const RayPacket& rays, HitPacket* hits, RayLayer layer) const {
  int lanes[k_packet_size];
  int n = 0;
  for (int i = 0; i < k_packet_size; ++i) {
    hits->found[i] = false;
    lanes[n] = i;  // NOTE: branch-free compaction (lanes end in random order: no misprediction)
    n += rays.valid[i] != 0;
  }
  if (n == 0) return;
  if (n <= 3) {
    for (int k = 0; k < n; ++k) hits->found[lanes[k]] = intersect(rays.get(lanes[k]), &hits->hit[lanes[k]], layer);
    return;
  }
  QueryContext ctx;
  init_context(&ctx, m_impl->alpha_test, m_impl->alpha_user);
  if (n <= 8) {
    alignas(32) RTCRayHit8 rh;
    alignas(32) int valid[8];
    fill_rays<8>(rays, lanes, n, rh.ray, valid, uint32_t(layer));
    for (int k = 0; k < 8; ++k) {
      rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect8(valid, m_impl->top, &ctx.embree, &rh);
    if (ctx.calls) m_impl->alpha_calls.fetch_add(ctx.calls, std::memory_order_relaxed);
    scatter_hits<8>(rh, lanes, n, hits);
  } else {
    alignas(64) RTCRayHit16 rh;
    alignas(64) int valid[16];
    fill_rays<16>(rays, lanes, n, rh.ray, valid, uint32_t(layer));
    for (int k = 0; k < 16; ++k) {
      rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect16(valid, m_impl->top, &ctx.embree, &rh);
    if (ctx.calls) m_impl->alpha_calls.fetch_add(ctx.calls, std::memory_order_relaxed);
    scatter_hits<16>(rh, lanes, n, hits);
  }
}

void Accel::occluded_packet(const RayPacket& rays, bool occluded[k_packet_size], RayLayer layer) const {
  int lanes[k_packet_size];
  int n = 0;
  for (int i = 0; i < k_packet_size; ++i) {
    occluded[i] = false;
    lanes[n] = i;  // branch-free compaction, as in intersect_packet
    n += rays.valid[i] != 0;
  }
  if (n == 0) return;
  if (n <= 3) {
    for (int k = 0; k < n; ++k) occluded[lanes[k]] = this->occluded(rays.get(lanes[k]), layer);
    return;
  }
  QueryContext ctx;
  init_context(&ctx, m_impl->alpha_test, m_impl->alpha_user);
  if (n <= 8) {
    alignas(32) RTCRay8 r;
    alignas(32) int valid[8];
    fill_rays<8>(rays, lanes, n, r, valid, uint32_t(layer));
    rtcOccluded8(valid, m_impl->top, &ctx.embree, &r);
    if (ctx.calls) m_impl->alpha_calls.fetch_add(ctx.calls, std::memory_order_relaxed);
    for (int k = 0; k < n; ++k) occluded[lanes[k]] = r.tfar[k] < 0.f;
  } else {
    alignas(64) RTCRay16 r;
    alignas(64) int valid[16];
    fill_rays<16>(rays, lanes, n, r, valid, uint32_t(layer));
    rtcOccluded16(valid, m_impl->top, &ctx.embree, &r);
    if (ctx.calls) m_impl->alpha_calls.fetch_add(ctx.calls, std::memory_order_relaxed);
    for (int k = 0; k < n; ++k) occluded[lanes[k]] = r.tfar[k] < 0.f;
  }
}

namespace {

/// Closest point of triangle (a, b, c) to p.
/// NOTE: Ericson, Real-Time Collision Detection (2005), section 5.1.5 "Closest point on
/// triangle to point": Voronoi regions of the vertices, then edges, then the face, tested
/// with barycentric sign checks; no normal needed, exact for slivers.
Vec3f closest_on_triangle(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const Vec3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.f && d2 <= 0.f) return a;
  const Vec3f bp = p - b;
  const float d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0.f && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.f && d1 >= 0.f && d3 <= 0.f) return a + ab * (d1 / (d1 - d3));
  const Vec3f cp = p - c;
  const float d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0.f && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.f && d2 >= 0.f && d6 <= 0.f) return a + ac * (d2 / (d2 - d6));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.f && (d4 - d3) >= 0.f && (d5 - d6) >= 0.f) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const float denom = 1.f / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

struct ClosestQuery {
  const TriangleMesh* mesh;
  float best;
  uint32_t prim;
};

/// Embree point-query callback: shrinks the query radius to the closest triangle so far
/// (Embree then skips BVH nodes farther than it).
bool closest_triangle(RTCPointQueryFunctionArguments* args) {
  auto* q = static_cast<ClosestQuery*>(args->userPtr);
  const auto& m = *q->mesh;
  const uint32_t* t = &m.indices[3 * size_t(args->primID)];
  const Vec3f p(args->query->x, args->query->y, args->query->z);
  const float d = length(p - closest_on_triangle(p, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]));
  if (d < args->query->radius) {
    args->query->radius = d;
    q->best = d;
    q->prim = args->primID;
    return true;
  }
  return false;
}

}  // namespace

std::vector<float> surface_distances(const TriangleMesh& mesh, const std::vector<Vec3f>& points,
                                     std::vector<uint32_t>* closest) {
  if (mesh.triangle_count() == 0) throw Error("surface_distances: the mesh '" + mesh.name + "' has no triangles");
  for (const Vec3f& p : points)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw Error("surface_distances: a query point is not finite");
  for (uint32_t i : mesh.indices)
    if (i >= mesh.positions.size()) throw Error("surface_distances: a triangle index is out of range");
  std::string error;
  RTCDevice device = rtcNewDevice("verbose=0");
  rtcSetDeviceErrorFunction(device, embree_error, &error);
  RTCScene scene = rtcNewScene(device);
  RTCGeometry geom = triangle_geometry(device, mesh);
  if (!geom) {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
    throw Error("Embree could not allocate buffers for mesh '" + mesh.name + "': " + error);
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  std::vector<float> out(points.size());
  if (closest) closest->assign(points.size(), 0);
  for (size_t i = 0; i < points.size(); ++i) {
    RTCPointQuery query;
    query.x = points[i].x;
    query.y = points[i].y;
    query.z = points[i].z;
    query.time = 0.f;
    query.radius = k_inf;
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    ClosestQuery q{&mesh, k_inf, 0};
    rtcPointQuery(scene, &query, &context, closest_triangle, &q);
    out[i] = q.best;
    if (closest) (*closest)[i] = q.prim;
  }
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  return out;
}

}  // namespace sg
