// Scene::instance_coverage: amodal (or visible) masks of many instances from one camera ray per
// pixel.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "api/scene.h"
#include "core/error.h"

namespace sg {

namespace {

/// Accel::all_hits' visitor: sets the bit of each listed instance the ray hits.
struct PixelBits {
  uint64_t* words;
  const std::vector<int32_t>* bit_of_slot;  ///< per instance slot, its bit (-1: not listed)
};

void set_bit(void* user, uint32_t inst) {
  auto* p = static_cast<PixelBits*>(user);
  if (inst >= p->bit_of_slot->size()) return;
  const int32_t b = (*p->bit_of_slot)[inst];
  if (b >= 0) p->words[b >> 6] |= uint64_t(1) << (b & 63);
}

/// Pixels [x0, x1) x [y0, y1).
struct PixelRect {
  uint32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

/// The pixels whose centre ray may hit an instance whose mesh has object-space bounds `b`:
/// those inside the projection of the bounds' box, widened by two pixels; the whole image
/// when the box is not wholly in front of the camera or the camera has lens distortion.
/// NOTE: exact culling: a camera ray hits a point p of the box at t > 0, so p is in front of
/// the camera and the ray's pixel is p's projection, which lies in the convex hull of the
/// projected corners (a perspective projection maps a convex set in front of the camera to a
/// convex set). The margin covers rounding (the corners here, Embree's conservative triangle
/// tests there: both far below a pixel), and a corner at a grazing depth (z < 1e-3 |x, y|) gives
/// up culling rather than trusting a projection a thousand focal lengths out.
PixelRect candidate_pixels(const PinholeCamera& cam, const Bounds3& b, const Transform& world_from_object) {
  const PixelRect all{0, 0, cam.width, cam.height};
  if (cam.distorted() || b.empty()) return all;
  double u0 = k_inf, v0 = k_inf, u1 = -k_inf, v1 = -k_inf;
  for (int c = 0; c < 8; ++c) {
    const Vec3f corner((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z);
    const Vec3f pc = cam.world_from_camera.apply_inverse_point(world_from_object.apply_point(corner));
    if (!(double(pc.z) > 1e-3 * (std::abs(double(pc.x)) + std::abs(double(pc.y))) + 1e-9)) return all;
    const double u = double(cam.fx) * pc.x / pc.z + cam.cx, v = double(cam.fy) * pc.y / pc.z + cam.cy;
    u0 = std::min(u0, u);
    u1 = std::max(u1, u);
    v0 = std::min(v0, v);
    v1 = std::max(v1, v);
  }
  // Pixel x is traced when its centre x + 0.5 lies in [u0 - 2, u1 + 2].
  auto lo = [](double a, uint32_t n) { return uint32_t(std::clamp(std::ceil(a - 2.5), 0.0, double(n))); };
  auto hi = [](double a, uint32_t n) { return uint32_t(std::clamp(std::floor(a + 1.5) + 1.0, 0.0, double(n))); };
  PixelRect r{lo(u0, cam.width), lo(v0, cam.height), hi(u1, cam.width), hi(v1, cam.height)};
  if (r.x0 >= r.x1 || r.y0 >= r.y1) return PixelRect{};
  return r;
}

}  // namespace

std::vector<uint64_t> Scene::instance_coverage(const PinholeCamera& camera, const std::vector<uint32_t>& instances,
                                               uint32_t threads, bool first_hit) {
  camera.validate();
  std::vector<int32_t> bit_of_slot(m_instances.size(), -1);
  for (size_t i = 0; i < instances.size(); ++i) {
    get_slot(m_instances, instances[i], "instance");
    if (bit_of_slot[instances[i]] >= 0)
      throw Error("instance_coverage: instance " + std::to_string(instances[i]) + " is listed twice");
    bit_of_slot[instances[i]] = int32_t(i);
  }
  if (has_pending_edits()) commit();
  const uint32_t w = camera.width, h = camera.height;
  const size_t words = (instances.size() + 63) / 64;
  std::vector<uint64_t> out(size_t(w) * h * words, 0);
  if (words == 0) return out;
  // Hidden instances are not in the BVH: no ray meets them, so they need no rectangle.
  std::vector<PixelRect> rects;
  for (uint32_t id : instances) {
    const InstanceEntry& e = *m_instances[id];
    if (!e.visible) continue;
    PixelRect r = candidate_pixels(camera, m_meshes[e.mesh_id]->bounds, e.world_from_object);
    if (r.x0 < r.x1) rects.push_back(r);
  }
  const Accel& accel = *m_accel;
  const int hw = tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(threads ? std::min(int(threads), hw) : hw);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, h, 4), [&](const tbb::blocked_range<uint32_t>& rows) {
      std::vector<std::pair<uint32_t, uint32_t>> spans;
      for (uint32_t y = rows.begin(); y < rows.end(); ++y) {
        // The row's pixels inside some rectangle, as merged spans (each pixel traced once).
        spans.clear();
        for (const PixelRect& r : rects)
          if (y >= r.y0 && y < r.y1) spans.emplace_back(r.x0, r.x1);
        std::sort(spans.begin(), spans.end());
        uint32_t done = 0;
        for (const auto& [s0, s1] : spans)
          for (uint32_t x = std::max(s0, done); x < s1; ++x) {
            PixelBits bits{&out[(size_t(y) * w + x) * words], &bit_of_slot};
            const Ray ray = camera.generate_ray(float(x) + 0.5f, float(y) + 0.5f);
            RayHit hit;
            // The closest hit as a label-only render finds it (PathTracer::labels).
            if (!first_hit) accel.all_hits(ray, set_bit, &bits);
            else if (accel.intersect(ray, &hit)) set_bit(&bits, hit.inst);
            done = x + 1;
          }
      }
    });
  });
  return out;
}

}  // namespace sg
