#include "integrator/texture_estimate.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <vector>

#include "integrator/interaction.h"
#include "integrator/ray_cone.h"
#include "material/microfacet.h"

namespace sg {

namespace {

/// A ray with its two differential rays (the rays through the next pixel in x and in y,
/// carried along the same sharp bounces).
struct DifferentialRay {
  Ray ray;
  Vec3f ox, dx, oy, dy;
  uint32_t depth = 0;
};

/// Where the line o + t d meets the plane through p with normal n (any t: differentials
/// are linear); false when it is parallel to the plane.
bool plane_point(const Vec3f& o, const Vec3f& d, const Vec3f& p, const Vec3f& n, Vec3f* q) {
  float den = dot(d, n);
  if (!(std::fabs(den) > 1e-12f)) return false;
  float t = dot(p - o, n) / den;
  *q = o + d * t;
  return is_finite(*q);
}

/// The shading normal the mesh's vertex normals give at p + dp in the hit triangle's plane
/// (barycentrics extrapolated linearly beyond the triangle), on the side of `ns`; `ns`
/// itself for meshes without normals.
Vec3f shading_normal_at(const InstanceRecord& inst, const RayHit& hit, const TriangleUvMap& bary, const Vec3f& dp,
                        const Vec3f& ns) {
  const TriangleMesh& m = *inst.mesh;
  if (m.normals.empty() || !bary.valid()) return ns;
  Vec2f db = bary(dp);
  float b1 = hit.u + db.x, b2 = hit.v + db.y, b0 = 1.f - b1 - b2;
  uint32_t i0 = m.indices[3 * hit.prim], i1 = m.indices[3 * hit.prim + 1], i2 = m.indices[3 * hit.prim + 2];
  Vec3f n = inst.world_from_object.apply_normal(m.normals[i0] * b0 + m.normals[i1] * b1 + m.normals[i2] * b2);
  float l = length(n);
  if (!(l > 0.f) || !std::isfinite(l)) return ns;
  n = n / l;
  return dot(n, ns) < 0.f ? -n : n;
}

/// The direction after a sharp event for a ray arriving along `d` at a surface with shading
/// normal `n` (either side); false on total internal reflection.
bool scatter(const SpecularEvent& e, const Vec3f& d, const Vec3f& n, bool entering, Vec3f* out) {
  Vec3f wo = -d;
  Vec3f nf = dot(wo, n) < 0.f ? -n : n;  // the normal on the side the ray comes from
  if (!e.refract) {
    *out = normalize(reflect(wo, nf));
    return true;
  }
  float eta = entering ? e.eta : 1.f / e.eta;
  if (!refract(wo, nf, eta, out)) return false;
  *out = normalize(*out);
  return true;
}

class Estimator {
 public:
  Estimator(const RenderScene& sc, const TextureEstimateSettings& s) : m_sc(sc), m_s(s) {}

  struct Local {
    FootprintRecorder recorder;
    uint64_t camera_rays = 0, bounce_rays = 0;
    std::vector<DifferentialRay> stack;
  };

  void pixel(uint32_t x, uint32_t y, Local& local) const {
    const PinholeCamera& cam = m_sc.camera;
    DifferentialRay r;
    r.ray = cam.generate_ray(float(x) + 0.5f, float(y) + 0.5f);
    Ray rx = cam.generate_ray(float(x) + 1.5f, float(y) + 0.5f);
    Ray ry = cam.generate_ray(float(x) + 0.5f, float(y) + 1.5f);
    r.ox = rx.o, r.dx = rx.d, r.oy = ry.o, r.dy = ry.d;
    local.stack.clear();
    local.stack.push_back(r);
    uint32_t traced = 0;
    while (!local.stack.empty() && traced < m_s.max_rays_per_pixel) {
      DifferentialRay cur = local.stack.back();
      local.stack.pop_back();
      ++traced;
      ++(cur.depth == 0 ? local.camera_rays : local.bounce_rays);
      shade(cur, local);
    }
  }

 private:
  void shade(const DifferentialRay& r, Local& local) const {
    RayHit hit;
    {
      // Alpha tests run inside traversal without a footprint: they are not recorded there
      // (the hit's own alpha is looked up below with the hit's footprint).
      ScopedFootprintRecorder off(nullptr);
      if (!m_sc.accel->intersect(r.ray, &hit)) return;
    }
    const InstanceRecord& inst = m_sc.instances[hit.inst];
    const Material* mat = m_sc.material_of(inst, hit.prim);
    SurfaceInteraction si = make_interaction(inst, hit, r.ray, true);
    si.primary = true;  // stochastic mixes look both components up
    Vec3f qx, qy;
    if (!plane_point(r.ox, r.dx, si.p, si.ng, &qx) || !plane_point(r.oy, r.dy, si.p, si.ng, &qy)) return;
    const Vec3f dpx = qx - si.p, dpy = qy - si.p;
    const ConeTriangle tri = cone_triangle(inst, hit.prim);
    const TriangleUvMap to_uv(tri);
    if (!to_uv.valid()) return;
    const Vec2f dux = to_uv(dpx), duy = to_uv(dpy);
    si.uv_axis_a = dux;
    si.uv_axis_b = duy;
    si.uv_footprint = std::sqrt(std::max(dux.x * dux.x + dux.y * dux.y, duy.x * duy.x + duy.y * duy.y));
    si.world_footprint = std::sqrt(std::max(dot(dpx, dpx), dot(dpy, dpy)));
    {
      FootprintRecorder& rec = local.recorder;
      rec.hit_a = dux;
      rec.hit_b = duy;
      ScopedFootprintRecorder on(&rec);
      Vec3f wo = -r.ray.d;
      Vec3f wi = reflect(wo, dot(wo, si.ns) < 0.f ? -si.ns : si.ns);
      (void)mat->eval(si, wo, wi);
      (void)mat->albedo(si);
      if (mat->is_emissive()) (void)mat->emission(si, wo);
      if (mat->has_alpha()) (void)mat->alpha(si);
    }
    if (r.depth >= m_s.max_depth) return;
    SpecularEvent events[4];
    int n = mat->specular_events(si, events);
    if (n == 0) return;
    ConeTriangle unit = tri;  // barycentric coordinates: uv edges (1, 0) and (0, 1)
    unit.u1 = Vec2f(1.f, 0.f);
    unit.u2 = Vec2f(0.f, 1.f);
    const TriangleUvMap bary(unit);
    const Vec3f nx = shading_normal_at(inst, hit, bary, dpx, si.ns);
    const Vec3f ny = shading_normal_at(inst, hit, bary, dpy, si.ns);
    const bool entering = dot(r.ray.d, si.ng) < 0.f;
    for (int i = n - 1; i >= 0; --i) {
      DifferentialRay next;
      Vec3f d, dx, dy;
      if (!scatter(events[i], r.ray.d, si.ns, entering, &d) || !scatter(events[i], r.dx, nx, entering, &dx) ||
          !scatter(events[i], r.dy, ny, entering, &dy))
        continue;
      next.ray = spawn_ray(si, d);
      next.ox = qx, next.dx = dx, next.oy = qy, next.dy = dy;
      next.depth = r.depth + 1;
      local.stack.push_back(next);
    }
  }

  const RenderScene& m_sc;
  const TextureEstimateSettings& m_s;
};

}  // namespace

TextureEstimate estimate_texture_footprints(const RenderScene& scene, const TextureEstimateSettings& settings) {
  TextureEstimate out;
  if (!scene.accel || scene.camera.width == 0 || scene.camera.height == 0) return out;
  Estimator est(scene, settings);
  tbb::enumerable_thread_specific<Estimator::Local> locals;
  auto run = [&] {
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, scene.camera.height), [&](const tbb::blocked_range<uint32_t>& rows) {
      Estimator::Local& local = locals.local();
      for (uint32_t y = rows.begin(); y < rows.end(); ++y)
        for (uint32_t x = 0; x < scene.camera.width; ++x) est.pixel(x, y, local);
    });
  };
  if (settings.threads > 0) {
    tbb::task_arena arena(int(settings.threads));
    arena.execute(run);
  } else {
    run();
  }
  // NOTE: minima and sums: the merged result does not depend on how rows were split.
  for (const Estimator::Local& l : locals) {
    out.recorded.merge(l.recorder);
    out.camera_rays += l.camera_rays;
    out.bounce_rays += l.bounce_rays;
  }
  return out;
}

}  // namespace sg
