// Accel::all_hits (geometry/accel.h): every instance a ray meets anywhere along it, through the
// alpha test, for triangles and user shapes; each reported exactly when a closest-hit query of a
// scene holding that instance alone finds a hit. And Scene::instance_coverage's bits against
// label-only renders of each instance alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <vector>

#include "api/scene.h"
#include "mesh_checks.h"
#include "core/rng.h"
#include "geometry/accel.h"

using namespace sg;
using sgtest::box;

namespace {

/// A sphere as a user shape (analytic, object space: centre 0, radius r).
class Ball : public UserShape {
 public:
  float r = 0.5f;
  Bounds3 bounds() const override {
    Bounds3 b;
    b.expand(Vec3f(-r));
    b.expand(Vec3f(r));
    return b;
  }
  bool intersect(const Vec3f& o, const Vec3f& d, float t0, float t1, float* t, Vec3f* n, Vec2f* uv) const override {
    const float a = dot(d, d), b = dot(o, d), c = dot(o, o) - r * r, disc = b * b - a * c;
    if (disc < 0.f) return false;
    for (float s : {(-b - std::sqrt(disc)) / a, (-b + std::sqrt(disc)) / a})
      if (s > t0 && s < t1) {
        *t = s;
        *n = normalize(o + d * s);
        *uv = Vec2f(0.f, 0.f);
        return true;
      }
    return false;
  }
};

std::set<uint32_t> all_hits(const Accel& a, const Ray& ray, RayLayer layer = RayLayer::all) {
  std::set<uint32_t> seen;
  a.all_hits(ray, [](void* user, uint32_t inst) { static_cast<std::set<uint32_t>*>(user)->insert(inst); }, &seen,
             layer);
  return seen;
}

/// Whether the ray crosses the box [lo, hi] (slabs).
bool crosses_box(const Ray& r, const Vec3f& lo, const Vec3f& hi) {
  float t0 = 0.f, t1 = k_inf;
  const float o[3] = {r.o.x, r.o.y, r.o.z}, d[3] = {r.d.x, r.d.y, r.d.z}, a[3] = {lo.x, lo.y, lo.z},
              b[3] = {hi.x, hi.y, hi.z};
  for (int k = 0; k < 3; ++k) {
    const float u = (a[k] - o[k]) / d[k], v = (b[k] - o[k]) / d[k];
    t0 = std::max(t0, std::min(u, v));
    t1 = std::min(t1, std::max(u, v));
  }
  return t0 < t1;
}

/// The alpha test of the tests: instance 2's triangles are holes where u > 0.5.
bool half_holes(const void*, uint32_t inst, uint32_t, float u, float) { return inst != 2 || u <= 0.5f; }

struct Placed {
  uint32_t mesh;
  Transform world_from_object;
  bool catcher;
};

/// Meshes: 0 a box, 1 a box built with the alpha test, 2 a user-shape ball.
void build_meshes(Accel& a, const TriangleMesh& ball) {
  a.build_mesh(0, box(Vec3f(-0.5f), Vec3f(0.5f)));
  a.build_mesh(1, box(Vec3f(-0.5f), Vec3f(0.5f)), true);
  a.build_mesh(2, ball);
  a.set_alpha_test(&half_holes, nullptr);
}

}  // namespace

TEST(all_hits, every_instance_along_the_ray_as_if_alone) {
  TriangleMesh ball;
  ball.name = "ball";
  ball.shape = std::make_shared<Ball>();
  // A row of overlapping objects along z: boxes, a cut-out box (instance 2), a ball, a catcher.
  std::vector<Placed> placed = {
      {0, Transform::translate(Vec3f(0.f, 0.f, 2.f)), false},
      {0, Transform::translate(Vec3f(0.3f, 0.2f, 3.f)), false},
      {1, Transform::translate(Vec3f(-0.2f, 0.f, 4.f)), false},
      {2, Transform::translate(Vec3f(0.1f, -0.3f, 5.f)) * Transform::scale(Vec3f(1.5f, 1.f, 1.f)), false},
      {0, Transform::translate(Vec3f(0.f, 0.f, 7.f)) * Transform::scale(Vec3f(3.f, 3.f, 0.2f)), true},
  };
  Accel all;
  build_meshes(all, ball);
  for (uint32_t i = 0; i < placed.size(); ++i)
    all.set_instance(i, placed[i].mesh, placed[i].world_from_object, placed[i].catcher);
  all.commit();
  std::vector<std::unique_ptr<Accel>> alone;
  for (uint32_t i = 0; i < placed.size(); ++i) {
    alone.push_back(std::make_unique<Accel>());
    build_meshes(*alone.back(), ball);
    alone.back()->set_instance(i, placed[i].mesh, placed[i].world_from_object, placed[i].catcher);
    alone.back()->commit();
  }
  Pcg32 rng(7, 1);
  int multi = 0, holes = 0;
  for (int k = 0; k < 4000; ++k) {
    Ray ray;
    ray.o = Vec3f(0.f, 0.f, -1.f);
    ray.d = normalize(Vec3f(0.4f * (rng.next_float() - 0.5f), 0.4f * (rng.next_float() - 0.5f), 1.f));
    ray.t_max = k_inf;
    for (RayLayer layer : {RayLayer::all, RayLayer::catchers}) {
      std::set<uint32_t> seen = all_hits(all, ray, layer), expected;
      RayHit hit;
      for (uint32_t i = 0; i < placed.size(); ++i)
        if (alone[i]->intersect(ray, &hit, layer)) expected.insert(i);
      ASSERT_EQ(seen, expected) << "ray " << k;
      // The closest hit is one of them.
      if (all.intersect(ray, &hit, layer)) EXPECT_TRUE(seen.count(hit.inst));
      else EXPECT_TRUE(seen.empty());
      if (layer == RayLayer::catchers) EXPECT_TRUE(seen.empty() || seen == std::set<uint32_t>{4});
      multi += seen.size() >= 3;
    }
    // The cut-out box: rays through its bounds it is not reported for (its holes).
    holes += crosses_box(ray, Vec3f(-0.7f, -0.5f, 3.5f), Vec3f(0.3f, 0.5f, 4.5f)) && !all_hits(all, ray).count(2);
  }
  EXPECT_GT(multi, 500);
  EXPECT_GT(holes, 10);
  EXPECT_GT(all.alpha_test_calls(), 0u);
  // A removed (hidden) instance is never reported.
  all.remove_instance(1);
  all.commit();
  Ray ray;
  ray.o = Vec3f(0.35f, 0.3f, -1.f);
  ray.d = Vec3f(0.f, 0.f, 1.f);
  ray.t_max = k_inf;
  EXPECT_EQ(all_hits(all, ray), (std::set<uint32_t>{0, 4}));
  ray.t_max = 2.7f;  // t_max is respected: only the first box's front face (t = 2.5) is in range
  EXPECT_EQ(all_hits(all, ray), (std::set<uint32_t>{0}));
}

TEST(all_hits, scene_instance_coverage_matches_renders_alone) {
  Scene s;
  std::vector<uint32_t> inst;
  const uint32_t m = s.add_mesh(box(Vec3f(-0.5f), Vec3f(0.5f)));
  for (int i = 0; i < 5; ++i) {
    const Vec3f at(0.4f * float(i) - 1.2f, 0.15f * float(i), 1.2f * float(i));
    inst.push_back(s.add_instance(m, Transform::translate(at), 1, uint32_t(i + 1)));
  }
  s.set_instance_visible(inst[3], false);
  const PinholeCamera cam =
      PinholeCamera::from_fov(50.f, 80, 60, PinholeCamera::look_at(Vec3f(0.f, 0.5f, -5.f), Vec3f(0.f), Vec3f(0, 1, 0)));
  s.set_camera(cam);
  const std::vector<uint32_t> listed = {inst[4], inst[0], inst[1], inst[2], inst[3]};
  const std::vector<uint64_t> bits = s.instance_coverage(cam, listed, 1);
  ASSERT_EQ(bits.size(), size_t(80 * 60));
  EXPECT_EQ(s.instance_coverage(cam, listed, 2), bits);
  RenderSettings rs;
  rs.labels_only = true;
  Film full;
  s.render(rs, &full);
  const std::vector<uint64_t> first = s.instance_coverage(cam, listed, 1, true);
  for (size_t b = 0; b < listed.size(); ++b) {
    const uint32_t id = listed[b] + 1;
    std::vector<bool> shown;
    for (uint32_t i : inst) shown.push_back(s.instance_visible(i));
    for (uint32_t i : inst) s.set_instance_visible(i, i == listed[b] && listed[b] != inst[3]);
    Film alone;
    s.render(rs, &alone);
    for (size_t i = 0; i < inst.size(); ++i) s.set_instance_visible(inst[i], shown[i]);
    size_t n = 0;
    for (size_t p = 0; p < bits.size(); ++p) {
      ASSERT_EQ((bits[p] >> b) & 1, uint64_t(alone.instance_id[p] == id)) << "bit " << b << " pixel " << p;
      ASSERT_EQ((first[p] >> b) & 1, uint64_t(full.instance_id[p] == id)) << "bit " << b << " pixel " << p;
      n += (bits[p] >> b) & 1;
    }
    if (listed[b] == inst[3]) EXPECT_EQ(n, 0u) << "hidden";
    else EXPECT_GT(n, 10u);
  }
  EXPECT_THROW(s.instance_coverage(cam, {inst[0], inst[0]}), Error);
  EXPECT_THROW(s.instance_coverage(cam, {99}), Error);
}
