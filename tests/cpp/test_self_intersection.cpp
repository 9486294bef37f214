// Robust ray spawning (integrator/interaction.h): rays leaving a surface, and shadow rays
// towards points on emitters, never hit the triangle they start from (or end on).
//
// Random triangles, including thin slivers, at scene scales 1e-4 .. 1e5 (triangle size
// and distance from the origin both scale), partly in world space under an identity
// instance, partly in object space under rotation + non-uniform scale + translation
// instances, and partly authored far from the object origin and translated back (large
// object coordinates that cancel in world space). For each triangle a ray is traced at
// it with sg::Accel, its hit interaction is built with make_interaction, and rays are
// spawned on both sides (cosine-distributed and grazing directions) with spawn_ray /
// offset_ray_origin, exactly as the path tracer does.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "api/scene.h"
#include "core/params.h"
#include "core/rng.h"
#include "geometry/accel.h"
#include "integrator/interaction.h"
#include "integrator/render_scene.h"
#include "light/light.h"
#include "material/material.h"

using namespace sg;

namespace {

struct D3 {
  double x = 0, y = 0, z = 0;
};
D3 operator+(const D3& a, const D3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator-(const D3& a, const D3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator*(const D3& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot3(const D3& a, const D3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 cross3(const D3& a, const D3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double len3(const D3& a) { return std::sqrt(dot3(a, a)); }
D3 norm3(const D3& a) { return a * (1.0 / len3(a)); }
D3 d3(const Vec3f& v) { return {v.x, v.y, v.z}; }
Vec3f f3(const D3& v) { return Vec3f(float(v.x), float(v.y), float(v.z)); }

double uniform(Pcg32& r, double a, double b) { return a + (b - a) * r.next_float(); }
D3 random_unit(Pcg32& r) {
  double z = 1.0 - 2.0 * r.next_float(), phi = 2.0 * 3.141592653589793 * r.next_float();
  double s = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {s * std::cos(phi), s * std::sin(phi), z};
}
/// Orthonormal tangents of a unit vector.
void tangents(const D3& n, D3* s, D3* t) {
  D3 h = std::fabs(n.x) < 0.6 ? D3{1, 0, 0} : D3{0, 1, 0};
  *s = norm3(cross3(h, n));
  *t = cross3(n, *s);
}
/// Direction around unit axis n at cosine c, random azimuth.
D3 dir_at_cos(const D3& n, double c, Pcg32& r) {
  D3 s, t;
  tangents(n, &s, &t);
  double phi = 2.0 * 3.141592653589793 * r.next_float(), sn = std::sqrt(std::max(0.0, 1.0 - c * c));
  return norm3(s * (sn * std::cos(phi)) + t * (sn * std::sin(phi)) + n * c);
}

enum class Placement { world, instanced, far_object_space };

const char* placement_name(Placement p) {
  return p == Placement::world ? "world-space mesh" : p == Placement::instanced ? "instanced" : "far-object-space";
}

struct TestTriangle {
  uint32_t inst, prim;
  Placement placement;
  bool sliver;
  double size;
};

struct ScaleScene {
  double scale;
  Accel accel;
  std::vector<std::unique_ptr<TriangleMesh>> meshes;
  std::vector<InstanceRecord> records;  // by instance slot
  std::vector<TestTriangle> tris;

  /// World-space vertex k of a test triangle, in double (the exact affine map of the
  /// float object-space vertex by the float instance matrix).
  D3 world_vertex(const TestTriangle& t, int k) const {
    const InstanceRecord& r = records[t.inst];
    Vec3f p = r.mesh->positions[r.mesh->indices[3 * t.prim + k]];
    const auto& m = r.world_from_object.m;
    return {double(m[0]) * p.x + double(m[1]) * p.y + double(m[2]) * p.z + m[3],
            double(m[4]) * p.x + double(m[5]) * p.y + double(m[6]) * p.z + m[7],
            double(m[8]) * p.x + double(m[9]) * p.y + double(m[10]) * p.z + m[11]};
  }
};

/// A random triangle of size ~`size` around `center` (object space); 1 in 4 is a sliver
/// whose smallest altitude is 1e-3 .. 1e-2 of its longest edge.
void add_random_triangle(TriangleMesh* m, const D3& center, double size, bool sliver, Pcg32& r) {
  D3 a = random_unit(r), u, v;
  tangents(a, &u, &v);
  std::array<D3, 3> p;
  if (sliver) {
    double aspect = std::pow(10.0, uniform(r, -3.0, -2.0));
    p[0] = center - u * (0.5 * size);
    p[1] = center + u * (0.5 * size);
    p[2] = center + u * (size * uniform(r, -0.4, 0.4)) + v * (size * aspect);
  } else {
    for (int k = 0; k < 3; ++k) {
      double ang = 2.0 * 3.141592653589793 * (k / 3.0) + uniform(r, -0.6, 0.6);
      double rad = size * uniform(r, 0.3, 0.6);
      p[k] = center + u * (rad * std::cos(ang)) + v * (rad * std::sin(ang));
    }
  }
  uint32_t base = uint32_t(m->positions.size());
  for (auto& q : p) m->positions.push_back(f3(q));
  m->indices.insert(m->indices.end(), {base, base + 1, base + 2});
}

/// Random rotation (Rodrigues), non-uniform scale 0.3 .. 3 and translation.
Transform random_transform(const D3& translation, Pcg32& r) {
  D3 k = random_unit(r);
  double th = uniform(r, 0.0, 2.0 * 3.141592653589793), c = std::cos(th), s = std::sin(th);
  double R[3][3] = {{c + k.x * k.x * (1 - c), k.x * k.y * (1 - c) - k.z * s, k.x * k.z * (1 - c) + k.y * s},
                    {k.y * k.x * (1 - c) + k.z * s, c + k.y * k.y * (1 - c), k.y * k.z * (1 - c) - k.x * s},
                    {k.z * k.x * (1 - c) - k.y * s, k.z * k.y * (1 - c) + k.x * s, c + k.z * k.z * (1 - c)}};
  double sc[3] = {std::pow(10.0, uniform(r, -0.5, 0.5)), std::pow(10.0, uniform(r, -0.5, 0.5)),
                  std::pow(10.0, uniform(r, -0.5, 0.5))};
  float m[16] = {0};
  double t[3] = {translation.x, translation.y, translation.z};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m[4 * i + j] = float(R[i][j] * sc[j]);
    m[4 * i + 3] = float(t[i]);
  }
  m[15] = 1.f;
  return Transform::from_row_major(m);
}

/// The per-instance hit-point error constants, as documented for make_interaction /
/// InstanceRecord (and computed by Scene::build_render_scene at commit):
/// p_error = gamma(7) (||M||_inf max|p|_inf + |t|_inf).
void set_error_constants(InstanceRecord* rec) {
  const auto& M = rec->world_from_object.m;
  float row_norm = 0.f, t_max = 0.f;
  for (int row = 0; row < 3; ++row) {
    row_norm = std::max(row_norm, std::fabs(M[4 * row]) + std::fabs(M[4 * row + 1]) + std::fabs(M[4 * row + 2]));
    t_max = std::max(t_max, std::fabs(M[4 * row + 3]));
  }
  rec->error_scale = gamma_n(7) * row_norm;
  rec->error_offset = gamma_n(7) * t_max;
}

/// Random point at distance ~ scale * 10^U(-1, 2) from the origin.
D3 random_position(double scale, Pcg32& r) { return random_unit(r) * (scale * std::pow(10.0, uniform(r, -1.0, 2.0))); }

std::unique_ptr<ScaleScene> build_scene(double scale, uint64_t seed) {
  auto sc = std::make_unique<ScaleScene>();
  sc->scale = scale;
  Pcg32 r(seed);
  uint32_t mesh_slot = 0, inst_slot = 0;
  auto add_instance = [&](std::unique_ptr<TriangleMesh> mesh, const Transform& T, Placement pl,
                          const std::vector<std::pair<bool, double>>& info) {
    sc->accel.build_mesh(mesh_slot, *mesh);
    sc->accel.set_instance(inst_slot, mesh_slot, T);
    InstanceRecord rec;
    rec.active = true;
    rec.mesh = mesh.get();
    rec.world_from_object = T;
    set_error_constants(&rec);
    sc->records.push_back(rec);
    for (uint32_t p = 0; p < info.size(); ++p)
      sc->tris.push_back({inst_slot, p, pl, info[p].first, info[p].second});
    sc->meshes.push_back(std::move(mesh));
    ++mesh_slot;
    ++inst_slot;
  };
  // 1. One world-space mesh of 60 triangles, identity instance.
  {
    auto m = std::make_unique<TriangleMesh>();
    std::vector<std::pair<bool, double>> info;
    for (int i = 0; i < 60; ++i) {
      double size = scale * uniform(r, 0.2, 1.0);
      bool sliver = i % 4 == 3;
      add_random_triangle(m.get(), random_position(scale, r), size, sliver, r);
      info.push_back({sliver, size});
    }
    add_instance(std::move(m), Transform(), Placement::world, info);
  }
  // 2. Twelve instanced meshes of 5 triangles near their object origin.
  for (int k = 0; k < 12; ++k) {
    auto m = std::make_unique<TriangleMesh>();
    std::vector<std::pair<bool, double>> info;
    for (int i = 0; i < 5; ++i) {
      double size = scale * uniform(r, 0.2, 1.0);
      bool sliver = (k + i) % 4 == 3;
      add_random_triangle(m.get(), random_unit(r) * (scale * uniform(r, 0.0, 4.0)), size, sliver, r);
      info.push_back({sliver, size});
    }
    add_instance(std::move(m), random_transform(random_position(scale, r), r), Placement::instanced, info);
  }
  // 3. Four meshes authored ~1000 sizes away from their object origin and translated
  //    back near the world origin: large object coordinates that cancel in world space.
  for (int k = 0; k < 4; ++k) {
    auto m = std::make_unique<TriangleMesh>();
    std::vector<std::pair<bool, double>> info;
    D3 offset = random_unit(r) * (scale * 1000.0);
    for (int i = 0; i < 5; ++i) {
      double size = scale * uniform(r, 0.2, 1.0);
      bool sliver = (k + i) % 4 == 3;
      add_random_triangle(m.get(), offset + random_unit(r) * (scale * uniform(r, 0.0, 4.0)), size, sliver, r);
      info.push_back({sliver, size});
    }
    // Translation = -(rotation-scale part applied to the offset) + a small world position.
    Transform T = random_transform(D3{0, 0, 0}, r);
    D3 mo = d3(T.apply_vector(f3(offset)));
    D3 world = random_unit(r) * (scale * uniform(r, 0.0, 10.0));
    float m16[16];
    for (int i = 0; i < 16; ++i) m16[i] = T.m[i];
    m16[3] = float(world.x - mo.x);
    m16[7] = float(world.y - mo.y);
    m16[11] = float(world.z - mo.z);
    add_instance(std::move(m), Transform::from_row_major(m16), Placement::far_object_space, info);
  }
  sc->accel.commit();
  return sc;
}

struct Failure {
  std::string kind;
  std::string detail;
};

struct Stats {
  long spawned = 0, shadow = 0, nee = 0, targeted = 0, skipped_first_hit = 0;
  long self_spawn = 0, self_shadow = 0, occluded_inconsistent = 0, self_nee_target = 0;
  long nee_by_placement[3] = {0, 0, 0}, self_nee_by_placement[3] = {0, 0, 0};
  std::vector<Failure> examples;
  void fail(const std::string& kind, const std::string& detail) {
    int same = 0;
    for (const auto& e : examples) same += e.kind == kind;
    if (same < 3) examples.push_back({kind, detail});
  }
};

std::string describe(const ScaleScene& sc, const TestTriangle& t, const SurfaceInteraction& si, const Vec3f& d,
                     const char* dir_kind, float hit_t) {
  std::ostringstream os;
  os << "scale " << sc.scale << ", " << placement_name(t.placement) << (t.sliver ? " sliver" : "") << " (inst "
     << t.inst << ", prim " << t.prim << ", size " << t.size << "), p = (" << si.p.x << ", " << si.p.y << ", "
     << si.p.z << "), |p| = " << length(si.p) << ", p_error = " << si.p_error.x << ", " << dir_kind
     << " direction with cos(ng) = " << dot(si.ng, d) << ", self-hit at t = " << hit_t;
  return os.str();
}

void run_scale(double scale, uint64_t seed, Stats* st) {
  auto sc = build_scene(scale, seed);
  Pcg32 r(seed * 7919 + 1);
  ParamSet lamp;
  lamp.set("radiance", 1.0);
  lamp.set("two_sided", true);
  auto emissive = create_material("emissive", lamp, sg::MaterialContext{[](uint32_t) { return std::shared_ptr<sg::Texture>(); }, [](uint32_t) { return std::shared_ptr<sg::Material>(); }}, "lamp");
  for (const TestTriangle& t : sc->tris) {
    D3 v0 = sc->world_vertex(t, 0), v1 = sc->world_vertex(t, 1), v2 = sc->world_vertex(t, 2);
    D3 n = norm3(cross3(v1 - v0, v2 - v0));
    // Trace a ray at a random interior point, from either side, at normal to grazing incidence.
    double b1 = r.next_float(), b2 = r.next_float();
    if (b1 + b2 > 1.0) {
      b1 = 1.0 - b1;
      b2 = 1.0 - b2;
    }
    b1 = 0.02 + 0.96 * b1;
    b2 = 0.02 + 0.96 * b2 * (1.0 - b1) / std::max(1e-9, 1.0 - b1);
    D3 q = v0 * (1.0 - b1 - b2) + v1 * b1 + v2 * b2;
    double side = r.next_float() < 0.5 ? 1.0 : -1.0;
    double cos_in = std::pow(10.0, uniform(r, -1.5, 0.0));
    D3 w_in = dir_at_cos(n * side, cos_in, r);  // from q towards the ray origin
    Ray ray;
    ray.o = f3(q + w_in * (t.size * uniform(r, 0.5, 3.0)));
    ray.d = f3(norm3(w_in * -1.0));
    ray.t_max = k_inf;
    RayHit hit;
    if (!sc->accel.intersect(ray, &hit) || hit.inst != t.inst || hit.prim != t.prim) {
      ++st->skipped_first_hit;  // another triangle is in the way (or a sliver was missed)
      continue;
    }
    ++st->targeted;
    SurfaceInteraction si = make_interaction(sc->records[t.inst], hit, ray);
    auto is_self = [&](const RayHit& h) { return h.inst == si.inst && h.prim == si.prim; };
    D3 ng = d3(si.ng);

    // Emitter for the NEE checks below: this very triangle, two-sided.
    // NOTE: built exactly as Scene::build_render_scene builds EmissiveTriangles (world
    // vertices by the instance transform in float, error bound from
    // emissive_triangle_error); keep this in sync with it.
    EmissiveTriangle et;
    const InstanceRecord& rec = sc->records[t.inst];
    {
      const TriangleMesh& m = *rec.mesh;
      et.p0 = rec.world_from_object.apply_point(m.positions[m.indices[3 * t.prim]]);
      et.p1 = rec.world_from_object.apply_point(m.positions[m.indices[3 * t.prim + 1]]);
      et.p2 = rec.world_from_object.apply_point(m.positions[m.indices[3 * t.prim + 2]]);
    }
    et.n = si.ng;
    {
      const TriangleMesh& m = *rec.mesh;
      et.p_error = emissive_triangle_error(rec, m.positions[m.indices[3 * t.prim]], m.positions[m.indices[3 * t.prim + 1]],
                                           m.positions[m.indices[3 * t.prim + 2]], et.p0, et.p1, et.p2);
    }
    et.prim = t.prim;
    et.material = emissive.get();
    AreaLight light(t.inst, uint32_t(rec.mesh->triangle_count()), {et});

    for (int k = 0; k < 160; ++k) {
      // Both sides; cosine-distributed (k even) or grazing, cos = 1e-5 .. 1e-2 (k odd).
      double s = (k / 2) % 2 == 0 ? 1.0 : -1.0;
      double c;
      const char* kind;
      if (k % 2 == 0) {
        c = std::sqrt(std::max(1e-12, double(r.next_float())));  // cosine-weighted: cos = sqrt(u)
        kind = "cosine";
      } else {
        c = std::pow(10.0, uniform(r, -5.0, -2.0));
        kind = "grazing";
      }
      Vec3f d = f3(dir_at_cos(ng * s, c, r));
      Ray sr = spawn_ray(si, d);
      ++st->spawned;
      RayHit h;
      if (sc->accel.intersect(sr, &h) && is_self(h)) {
        ++st->self_spawn;
        st->fail("spawned ray", describe(*sc, t, si, d, kind, h.t));
      }
      // Shadow ray from the same surface to a point a short distance along d.
      if (k % 2 == 0 || k % 4 == 1) {
        // The target must lie clearly on the side of d: at least 16 error bounds of the
        // hit point away from the surface plane (a point within the error band of the
        // plane is on neither side). Grazing rays are lengthened to get there.
        double len = t.size * std::pow(10.0, uniform(r, -2.0, 0.5));
        len = std::max(len, 16.0 * double(si.p_error.x) / std::fabs(double(dot(si.ng, d))));
        Vec3f target = f3(d3(si.p) + d3(d) * len);
        Ray shadow;
        shadow.o = offset_ray_origin(si.p, si.p_error, si.ng, target - si.p);
        shadow.d = target - shadow.o;
        shadow.t_max = 1.f - k_shadow_epsilon;
        ++st->shadow;
        RayHit hs;
        bool any = sc->accel.intersect(shadow, &hs);
        if (any && is_self(hs)) {
          ++st->self_shadow;
          st->fail("shadow ray (origin side)", describe(*sc, t, si, d, kind, hs.t));
        }
        if (sc->accel.occluded(shadow) != any) {
          ++st->occluded_inconsistent;
          st->fail("occluded() disagrees with intersect()", describe(*sc, t, si, d, kind, hs.t));
        }
      }
    }

    // NEE towards this triangle as an area light, from points off the surface on both
    // sides, as the path tracer does: the shadow ray ends at the sampled point offset by
    // its error bound, t_max = 1 - shadow epsilon. The light's own triangle must not
    // occlude it.
    for (int k = 0; k < 24; ++k) {
      double s = k % 2 == 0 ? 1.0 : -1.0;
      double c = k % 4 < 2 ? std::sqrt(std::max(1e-6, double(r.next_float()))) : std::pow(10.0, uniform(r, -3.0, -1.0));
      D3 x = d3(si.p) + dir_at_cos(ng * s, c, r) * (t.size * uniform(r, 0.05, 2.0));
      LightSampleContext ctx{f3(x), Vec3f(0.f)};
      LightSample ls;
      if (!light.sample(ctx, r.next_2d(), &ls)) continue;
      Vec3f target = offset_ray_origin(ls.p_light, ls.p_light_error, ls.n_light, -ls.wi);
      Ray shadow;
      shadow.o = ctx.p;
      shadow.d = target - shadow.o;
      shadow.t_max = 1.f - k_shadow_epsilon;
      ++st->nee;
      ++st->nee_by_placement[int(t.placement)];
      RayHit hs;
      if (sc->accel.intersect(shadow, &hs) && hs.inst == t.inst && hs.prim == t.prim) {
        ++st->self_nee_target;
        ++st->self_nee_by_placement[int(t.placement)];
        std::ostringstream os;
        os << "scale " << scale << ", " << placement_name(t.placement) << (t.sliver ? " sliver" : "")
           << " (inst " << t.inst << ", prim " << t.prim << ", size " << t.size << "), p_light = (" << ls.p_light.x
           << ", " << ls.p_light.y << ", " << ls.p_light.z << "), p_light_error = " << ls.p_light_error.x
           << " (make_interaction's bound there: " << si.p_error.x << "), cos at light = "
           << std::fabs(dot(ls.n_light, ls.wi)) << ", hit at t = " << hs.t << " of 1";
        st->fail("NEE shadow ray hits the emitter it aims at (target side)", os.str());
      }
    }
  }
}

}  // namespace

TEST(self_intersection, spawned_and_shadow_rays_never_hit_their_own_triangle) {
  Stats total;
  std::ostringstream per_scale;
  uint64_t seed = 801;
  for (double scale : {1e-4, 1e-2, 1.0, 1e2, 1e5}) {
    Stats st;
    run_scale(scale, seed++, &st);
    per_scale << "scale " << scale << ": " << st.targeted << " triangles hit (" << st.skipped_first_hit
              << " skipped), " << st.spawned << " spawned (" << st.self_spawn << " self-hits), " << st.shadow
              << " shadow (" << st.self_shadow << " self-hits, " << st.occluded_inconsistent
              << " occluded/intersect mismatches), " << st.nee << " NEE (" << st.self_nee_target
              << " self-hits at the target; by placement:";
    for (int pl = 0; pl < 3; ++pl)
      per_scale << " " << placement_name(Placement(pl)) << " " << st.self_nee_by_placement[pl] << "/"
                << st.nee_by_placement[pl];
    per_scale << ")\n";
    total.spawned += st.spawned;
    total.shadow += st.shadow;
    total.nee += st.nee;
    total.targeted += st.targeted;
    total.self_spawn += st.self_spawn;
    total.self_shadow += st.self_shadow;
    total.occluded_inconsistent += st.occluded_inconsistent;
    total.self_nee_target += st.self_nee_target;
    for (auto& e : st.examples)
      total.fail(e.kind, e.detail);
    // Enough triangles of every scale must actually have been tested.
    EXPECT_GT(st.targeted, 80) << "scale " << scale;
  }
  std::ostringstream ex;
  for (auto& e : total.examples) ex << "  [" << e.kind << "] " << e.detail << "\n";
  EXPECT_GE(total.spawned, 100000);
  EXPECT_EQ(total.self_spawn, 0) << per_scale.str() << ex.str();
  EXPECT_EQ(total.self_shadow, 0) << per_scale.str() << ex.str();
  EXPECT_EQ(total.occluded_inconsistent, 0) << per_scale.str() << ex.str();
  EXPECT_EQ(total.self_nee_target, 0) << per_scale.str() << ex.str();
}

// End to end through sg::Scene: the same tilted emitting quad, authored once far away
// from its object origin and translated back by the instance transform (as happens with
// georeferenced or CAD coordinates), and once directly in world space (its world vertices
// computed in double from the first), must light a diffuse floor identically. Shadow rays
// towards the far-authored emitter must not be blocked by the emitter itself.
TEST(self_intersection, emitter_authored_far_from_object_origin_lights_the_same) {
  auto render_floor = [](const TriangleMesh& lamp, const Transform& lamp_transform) {
    Scene s;
    TriangleMesh floor;
    floor.positions = {{-10, -10, 0}, {10, -10, 0}, {10, 10, 0}, {-10, 10, 0}};
    floor.indices = {0, 1, 2, 0, 2, 3};
    uint32_t floor_mesh = s.add_mesh(floor);
    uint32_t lamp_mesh = s.add_mesh(lamp);
    ParamSet white;
    white.set("albedo", 0.8);
    ParamSet lamp_params;
    lamp_params.set("radiance", 10.0);
    uint32_t white_mat = s.add_material("diffuse", white), lamp_mat = s.add_material("emissive", lamp_params);
    s.add_instance(floor_mesh, Transform(), 1, 1u, white_mat);
    s.add_instance(lamp_mesh, lamp_transform, 2, 2u, lamp_mat);
    s.set_camera(PinholeCamera::from_fov(
        40.f, 32, 32, PinholeCamera::look_at(Vec3f(0.f, -3.f, 4.f), Vec3f(0.f, 0.f, 0.f), Vec3f(0.f, 0.f, 1.f))));
    RenderSettings rs;
    rs.spp = 16;
    rs.max_depth = 2;  // direct lighting: next-event estimation + emitter hits (MIS)
    rs.seed = 5;
    Film f;
    s.render(rs, &f);
    double sum = 0.0;
    int n = 0;
    for (size_t i = 0; i < f.instance_id.size(); ++i)
      if (f.instance_id[i] == 1u) {
        sum += f.rgb[3 * i];
        ++n;
      }
    EXPECT_GT(n, 500);
    return sum / n;
  };
  // Rotation: 37 degrees about z after 15 degrees about x; the lamp faces down-ish.
  const double a = 37.0 * 3.141592653589793 / 180.0, b = 15.0 * 3.141592653589793 / 180.0;
  const double R[3][3] = {{std::cos(a), -std::sin(a) * std::cos(b), std::sin(a) * std::sin(b)},
                          {std::sin(a), std::cos(a) * std::cos(b), -std::cos(a) * std::sin(b)},
                          {0.0, std::sin(b), std::cos(b)}};
  const D3 w{0.1, 0.2, 1.5};
  for (double offset : {1e3, 1e4, 1e5}) {
    D3 o{0.7 * offset, -1.3 * offset, 0.9 * offset};
    TriangleMesh lamp;
    for (D3 q : {D3{-0.5, -0.5, 0}, D3{0.5, -0.5, 0}, D3{0.5, 0.5, 0}, D3{-0.5, 0.5, 0}}) lamp.positions.push_back(f3(q + o));
    lamp.indices = {0, 2, 1, 0, 3, 2};  // winding normal -z (object space): emits downwards
    // world = R (object - offset) + w
    float m[16] = {0};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) m[4 * i + j] = float(R[i][j]);
      double ro = R[i][0] * o.x + R[i][1] * o.y + R[i][2] * o.z;
      m[4 * i + 3] = float((i == 0 ? w.x : i == 1 ? w.y : w.z) - ro);
    }
    m[15] = 1.f;
    Transform T = Transform::from_row_major(m);
    // The same lamp in world space: exact affine map of the float data, rounded once.
    TriangleMesh lamp_world = lamp;
    for (auto& p : lamp_world.positions) {
      D3 q{double(m[0]) * p.x + double(m[1]) * p.y + double(m[2]) * p.z + m[3],
           double(m[4]) * p.x + double(m[5]) * p.y + double(m[6]) * p.z + m[7],
           double(m[8]) * p.x + double(m[9]) * p.y + double(m[10]) * p.z + m[11]};
      p = f3(q);
    }
    double ref = render_floor(lamp_world, Transform());
    double far = render_floor(lamp, T);
    EXPECT_GT(ref, 0.0);
    EXPECT_NEAR(far / ref, 1.0, 0.005) << "floor radiance under a lamp authored in world space: " << ref
                                       << "; authored " << offset << " units from its object origin: " << far;
  }
}

namespace {
// pbrt-v4's NextFloatUp / NextFloatDown with branches, as offset_ray_origin used them.
inline float next_float_up(float v) {
  if (std::isinf(v) && v > 0.f) return v;
  if (v == -0.f) v = 0.f;
  uint32_t ui;
  std::memcpy(&ui, &v, 4);
  ui = v >= 0 ? ui + 1 : ui - 1;
  std::memcpy(&v, &ui, 4);
  return v;
}
inline float next_float_down(float v) {
  if (std::isinf(v) && v < 0.f) return v;
  if (v == 0.f) v = -0.f;
  uint32_t ui;
  std::memcpy(&ui, &v, 4);
  ui = v > 0 ? ui - 1 : ui + 1;
  std::memcpy(&v, &ui, 4);
  return v;
}
}  // namespace

// offset_ray_origin steps each coordinate with the branch-free next_float_away: the same
// bits as next_float_up / next_float_down (and v itself for a zero offset), for zeros of both
// signs, subnormals, normal values, the largest finite, infinities and NaN.
TEST(self_intersection, next_float_away_is_next_float_up_and_down) {
  std::vector<float> vs = {0.f, -0.f, 1e-45f, -1e-45f, 1e-38f, -1e-38f, 1.f, -1.f, 0.1f, -3e7f,
                           std::numeric_limits<float>::max(), -std::numeric_limits<float>::max(),
                           k_inf, -k_inf, std::numeric_limits<float>::quiet_NaN()};
  Pcg32 rng(3);
  for (int i = 0; i < 100000; ++i) {
    uint32_t bits = rng.next_u32();
    float v;
    std::memcpy(&v, &bits, 4);
    vs.push_back(v);
  }
  auto same = [](float a, float b) { return std::memcmp(&a, &b, 4) == 0; };
  for (float v : vs) {
    for (float dir : {1.f, 1e-30f, k_inf}) ASSERT_TRUE(same(next_float_away(v, dir), next_float_up(v))) << v;
    for (float dir : {-1.f, -1e-30f, -k_inf}) ASSERT_TRUE(same(next_float_away(v, dir), next_float_down(v))) << v;
    for (float dir : {0.f, -0.f}) ASSERT_TRUE(same(next_float_away(v, dir), v)) << v;
  }
}
