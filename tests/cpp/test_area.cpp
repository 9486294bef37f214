// Area lights (light/area.cpp): sg::AreaLight built from EmissiveTriangles with real
// "emissive" materials, as the scene builds them at commit.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "chi2.h"
#include "core/error.h"
#include "core/params.h"
#include "core/rng.h"
#include "integrator/interaction.h"
#include "light/light.h"
#include "material/material.h"

using namespace sg;
using namespace sgtest;

namespace {

Vec3f to_f(const DVec3& v) { return Vec3f(float(v.x), float(v.y), float(v.z)); }
DVec3 to_d(const Vec3f& v) { return {v.x, v.y, v.z}; }
DVec3 dsub(const DVec3& a, const DVec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
DVec3 dadd(const DVec3& a, const DVec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
DVec3 dscale(const DVec3& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dlen(const DVec3& a) { return std::sqrt(ddot(a, a)); }

std::shared_ptr<Material> emissive(const Color& radiance, bool two_sided) {
  ParamSet p;
  p.set("radiance", std::vector<double>{radiance.x, radiance.y, radiance.z});
  p.set("two_sided", two_sided);
  return create_material("emissive", p, sg::MaterialContext{[](uint32_t) { return std::shared_ptr<sg::Texture>(); }, [](uint32_t) { return std::shared_ptr<sg::Material>(); }}, "test");
}

/// Emissive triangle with the winding normal, like Scene::build_render_scene makes it.
EmissiveTriangle make_tri(const DVec3& a, const DVec3& b, const DVec3& c, uint32_t prim, const Material* m) {
  EmissiveTriangle t;
  t.p0 = to_f(a);
  t.p1 = to_f(b);
  t.p2 = to_f(c);
  t.n = normalize(cross(t.p1 - t.p0, t.p2 - t.p0));
  t.uv0 = Vec2f(0, 0);
  t.uv1 = Vec2f(1, 0);
  t.uv2 = Vec2f(0, 1);
  // World-space triangle (identity instance): hit-point bound plus interpolation bound.
  t.p_error = 2.f * gamma_n(7) * max_component(vmax(vabs(t.p0), vmax(vabs(t.p1), vabs(t.p2))));
  t.prim = prim;
  t.material = m;
  return t;
}

double tri_area(const EmissiveTriangle& t) {
  DVec3 e1 = dsub(to_d(t.p1), to_d(t.p0)), e2 = dsub(to_d(t.p2), to_d(t.p0));
  return 0.5 * dlen(dcross(e1, e2));
}

/// Orients the triangle (a, b, c) so that its winding normal faces towards (or away from) x.
std::array<DVec3, 3> facing(const DVec3& a, const DVec3& b, const DVec3& c, const DVec3& x, bool towards) {
  DVec3 n = dcross(dsub(b, a), dsub(c, a));
  bool faces = ddot(n, dsub(x, a)) > 0.0;
  if (faces == towards) return {a, b, c};
  return {a, c, b};
}

/// Barycentric coordinates of p in the plane of t, and its distance to that plane.
bool on_triangle(const EmissiveTriangle& t, const DVec3& p, double tol) {
  DVec3 p0 = to_d(t.p0), e1 = dsub(to_d(t.p1), p0), e2 = dsub(to_d(t.p2), p0), d = dsub(p, p0);
  DVec3 n = dnormalize(dcross(e1, e2));
  if (std::fabs(ddot(d, n)) > tol) return false;
  double d11 = ddot(e1, e1), d12 = ddot(e1, e2), d22 = ddot(e2, e2), d1 = ddot(d, e1), d2 = ddot(d, e2);
  double den = d11 * d22 - d12 * d12;
  double b1 = (d22 * d1 - d12 * d2) / den, b2 = (d11 * d2 - d12 * d1) / den;
  double eps = 1e-5;
  return b1 >= -eps && b2 >= -eps && b1 + b2 <= 1.0 + eps;
}

/// Irradiance at x (receiver normal n) from a polygon of uniform radiance L entirely above
/// the receiver's tangent plane: Lambert's formula for polygonal luminaires,
/// E = L / 2 * sum_i angle(v_i, v_i+1) * (n . normalize(v_i x v_i+1)), v_i = unit vectors to
/// the vertices.
double polygon_irradiance(const std::vector<DVec3>& poly, const DVec3& x, const DVec3& n, double L) {
  double s = 0.0;
  for (size_t i = 0; i < poly.size(); ++i) {
    DVec3 a = dnormalize(dsub(poly[i], x)), b = dnormalize(dsub(poly[(i + 1) % poly.size()], x));
    double ang = std::acos(std::max(-1.0, std::min(1.0, ddot(a, b))));
    s += ang * ddot(n, dnormalize(dcross(a, b)));
  }
  return 0.5 * L * std::fabs(s);
}

}  // namespace

// A light made of four triangles seen from a reference point: A and B face the point
// (B farther away, partly behind A: light sampling ignores visibility, so densities add),
// C is one-sided and faces away (its samples must fail), D is two-sided and faces away
// (it must still emit). Primitives 1 and 4 are not emissive.
struct AreaFixture {
  DVec3 x{0.1, -0.2, 0.05};
  std::shared_ptr<Material> mA = emissive(Color(1.f), false), mB = emissive(Color(3.f, 2.f, 1.f), false),
                            mC = emissive(Color(2.f), false), mD = emissive(Color(0.5f, 0.5f, 2.f), true);
  std::vector<EmissiveTriangle> tris;
  std::unique_ptr<AreaLight> light;
  AreaFixture() {
    auto A = facing({-1, -1, 2}, {1, -0.8, 2.2}, {0, 1, 1.9}, x, true);
    auto B = facing({-0.5, 0, 3.5}, {1.5, 0.5, 3.8}, {0.5, 2, 3.2}, x, true);
    auto C = facing({-1.5, -1.5, 2.5}, {-0.5, -1.8, 2.6}, {-1, -0.6, 2.4}, x, false);
    auto D = facing({0.8, -1.5, 2.8}, {1.8, -1.2, 2.6}, {1.2, -0.4, 3.0}, x, false);
    tris.push_back(make_tri(A[0], A[1], A[2], 0, mA.get()));
    tris.push_back(make_tri(B[0], B[1], B[2], 2, mB.get()));
    tris.push_back(make_tri(C[0], C[1], C[2], 3, mC.get()));
    tris.push_back(make_tri(D[0], D[1], D[2], 5, mD.get()));
    light = std::make_unique<AreaLight>(7, 6, tris);
  }
  double weight(const EmissiveTriangle& t) const {
    return tri_area(t) * std::max(double(luminance(t.material->average_emission())), 1e-6);
  }
  double total_weight() const {
    double s = 0.0;
    for (const auto& t : tris) s += weight(t);
    return s;
  }
};

TEST(area, area_pdf_and_power) {
  AreaFixture f;
  double total = f.total_weight(), power = 0.0;
  for (const auto& t : f.tris) {
    double expected = (f.weight(t) / total) / tri_area(t);
    EXPECT_NEAR(f.light->area_pdf(t.prim) / expected, 1.0, 1e-5) << "prim " << t.prim;
    power += k_pi_d * (t.material->two_sided_emission() ? 2.0 : 1.0) * f.weight(t);
  }
  EXPECT_EQ(f.light->area_pdf(1), 0.f);
  EXPECT_EQ(f.light->area_pdf(4), 0.f);
  EXPECT_EQ(f.light->area_pdf(1000), 0.f);
  EXPECT_NEAR(f.light->power() / power, 1.0, 1e-5);
  EXPECT_FALSE(f.light->is_delta());
  EXPECT_FALSE(f.light->is_infinite());
}

TEST(area, sample_records_are_consistent) {
  AreaFixture f;
  LightSampleContext ctx{to_f(f.x), Vec3f(0.f)};
  Pcg32 rng(301);
  const int n = 200000;
  std::vector<int> per_tri(f.tris.size(), 0);
  int succeeded = 0, bad = 0;
  std::string first;
  auto report = [&](const std::string& s) {
    if (bad++ == 0) first = s;
  };
  for (int i = 0; i < n; ++i) {
    LightSample ls;
    if (!f.light->sample(ctx, rng.next_2d(), &ls)) continue;
    ++succeeded;
    DVec3 pl = to_d(ls.p_light);
    int which = -1;
    for (size_t k = 0; k < f.tris.size(); ++k)
      if (on_triangle(f.tris[k], pl, 1e-5)) which = int(k);
    if (which < 0) {
      report("sampled point on no triangle");
      continue;
    }
    ++per_tri[size_t(which)];
    const EmissiveTriangle& t = f.tris[size_t(which)];
    DVec3 d = dsub(pl, f.x);
    double dist = dlen(d);
    DVec3 w = dscale(d, 1.0 / dist);
    double cos_l = std::fabs(ddot(to_d(t.n), w));
    double pdf = f.light->area_pdf(t.prim) * dist * dist / cos_l;
    if (std::fabs(ls.pdf / pdf - 1.0) > 1e-4) report("pdf " + std::to_string(ls.pdf) + " vs " + std::to_string(pdf));
    if (dlen(dsub(to_d(ls.wi), w)) > 1e-5) report("wi does not point at p_light");
    if (ls.li != t.material->average_emission()) report("li is not the triangle's radiance");
    if (ls.n_light != t.n) report("n_light is not the triangle normal");
    if (ls.delta || ls.infinite) report("area light sample flagged delta or infinite");
    if (!(ls.p_light_error.x > 0.f)) report("no error bound on p_light");
  }
  EXPECT_EQ(bad, 0) << first;
  // C faces away and is one-sided: none of its samples may succeed; D is two-sided.
  EXPECT_EQ(per_tri[2], 0) << "back face of a one-sided emitter was sampled";
  EXPECT_GT(per_tri[3], 0) << "back face of a two-sided emitter was never sampled";
  // Successful fraction = 1 - pmf(C), within 5 binomial standard deviations.
  double p_ok = 1.0 - f.weight(f.tris[2]) / f.total_weight();
  EXPECT_NEAR(double(succeeded) / n, p_ok, 5.0 * std::sqrt(p_ok * (1.0 - p_ok) / n));
}

// Chi-square of the sampled directions against the solid-angle density. Expected cell
// probabilities integrate the area pdf over the parts of the emitting triangles whose
// directions fall in each cell (a fine subdivision of every triangle into sub-triangles,
// assigned by their centroid); no sampling is involved.
TEST(area, direction_distribution_chi2) {
  AreaFixture f;
  LightSampleContext ctx{to_f(f.x), Vec3f(0.f)};
  // Cone-local cells around the mean direction to the triangles.
  DVec3 axis{0, 0, 0};
  for (const auto& t : f.tris)
    for (const Vec3f& p : {t.p0, t.p1, t.p2}) axis = dadd(axis, dnormalize(dsub(to_d(p), f.x)));
  DFrame frame(dnormalize(axis));
  double theta_ref = 0.0;
  for (const auto& t : f.tris)
    for (const Vec3f& p : {t.p0, t.p1, t.p2})
      theta_ref = std::max(theta_ref, std::acos(ddot(frame.n, dnormalize(dsub(to_d(p), f.x)))));
  theta_ref *= 1.02;
  Grid2D g{40, 64, 0.0, 1.0, 0.0, 2.0 * k_pi_d};

  const int n = 1000000;
  Pcg32 rng(302);
  std::vector<double> obs(g.size(), 0.0);
  int outside = 0;
  for (int i = 0; i < n; ++i) {
    LightSample ls;
    if (!f.light->sample(ctx, rng.next_2d(), &ls)) continue;
    double tau, phi;
    cone_coords(frame, theta_ref, to_d(ls.wi), &tau, &phi);
    long c = g.cell(tau, phi);
    if (c < 0) {
      ++outside;
      continue;
    }
    obs[size_t(c)] += 1.0;
  }
  EXPECT_EQ(outside, 0);

  std::vector<double> exp(g.size(), 0.0);
  const int m = 700;  // m^2 sub-triangles per triangle
  for (const auto& t : f.tris) {
    DVec3 p0 = to_d(t.p0), e1 = dsub(to_d(t.p1), p0), e2 = dsub(to_d(t.p2), p0);
    double sub_area = tri_area(t) / double(m) / double(m);
    double mass = n * double(f.light->area_pdf(t.prim)) * sub_area;
    auto emit = [&](double b1, double b2) {
      DVec3 p = dadd(p0, dadd(dscale(e1, b1), dscale(e2, b2)));
      DVec3 w = dnormalize(dsub(p, f.x));
      SurfaceInteraction si;
      si.p = to_f(p);
      si.ng = si.ns = t.n;
      if (is_black(t.material->emission(si, to_f(dscale(w, -1.0))))) return;
      double tau, phi;
      cone_coords(frame, theta_ref, w, &tau, &phi);
      long c = g.cell(tau, phi);
      ASSERT_GE(c, 0);
      exp[size_t(c)] += mass;
    };
    // Upward and downward sub-triangles of the regular subdivision, by their centroids.
    for (int i = 0; i < m; ++i)
      for (int j = 0; i + j < m; ++j) {
        emit((i + 1.0 / 3.0) / m, (j + 1.0 / 3.0) / m);
        if (i + j + 1 < m) emit((i + 2.0 / 3.0) / m, (j + 2.0 / 3.0) / m);
      }
  }
  double p_ok = 1.0 - f.weight(f.tris[2]) / f.total_weight();
  EXPECT_NEAR(sum(exp) / n, p_ok, 1e-5) << "integrated pdf differs from the emitting fraction";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << r.message;
}

// Irradiance from light sampling vs Lambert's analytic formula for polygonal luminaires.
TEST(area, irradiance_matches_polygon_formula) {
  auto m = emissive(Color(2.5f), false);
  struct Case {
    DVec3 x, n;
    std::vector<DVec3> poly;  // triangle or quad (split into two triangles)
  };
  const double c20 = std::cos(20.0 * k_pi_d / 180.0), s20 = std::sin(20.0 * k_pi_d / 180.0);
  std::vector<Case> cases = {
      // One large triangle above the point.
      {{0, 0, 0}, {0, 0, 1}, {{-3, -2, 1}, {4, -1, 1.5}, {0, 5, 1.2}}},
      // An offset quad, receiver tilted by 20 degrees.
      {{0.3, 0.2, -0.1}, {s20, 0, c20}, {{-1, -1, 1}, {2, -1, 1}, {2, 2, 1.4}, {-1, 2, 1.4}}},
      // A small, distant, oblique triangle.
      {{0, 0, 0}, {0, 0, 1}, {{5, 0, 10}, {6, 0.5, 10.5}, {5.2, 1.5, 9.5}}},
  };
  uint64_t seed = 310;
  for (const Case& cs : cases) {
    for (const DVec3& p : cs.poly) ASSERT_GT(ddot(cs.n, dsub(p, cs.x)), 0.0) << "polygon must be above the receiver";
    std::vector<EmissiveTriangle> tris;
    for (size_t k = 1; k + 1 < cs.poly.size(); ++k) {
      auto t = facing(cs.poly[0], cs.poly[k], cs.poly[k + 1], cs.x, true);
      tris.push_back(make_tri(t[0], t[1], t[2], uint32_t(k - 1), m.get()));
    }
    AreaLight light(0, uint32_t(tris.size()), tris);
    LightSampleContext ctx{to_f(cs.x), Vec3f(0.f)};
    Pcg32 rng(seed++);
    const int n = 2000000;
    double e = 0.0;
    for (int i = 0; i < n; ++i) {
      LightSample ls;
      if (!light.sample(ctx, rng.next_2d(), &ls)) continue;
      double c = ddot(cs.n, to_d(ls.wi));
      if (c > 0.0) e += double(ls.li.y) * c / double(ls.pdf);
    }
    e /= n;
    double ref = polygon_irradiance(cs.poly, cs.x, cs.n, 2.5);
    EXPECT_NEAR(e / ref, 1.0, 5e-3) << "MC " << e << " vs analytic " << ref;
  }
}

TEST(area, zero_area_light_throws) {
  auto m = emissive(Color(1.f), false);
  EmissiveTriangle t = make_tri({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0, m.get());
  t.p2 = t.p1;  // degenerate
  EXPECT_THROW(AreaLight(0, 1, {t}), Error);
}

// AreaLight skips the emission lookup for materials that declare uniform_emission(): the
// declaration must hold wherever the light is hit, from either side.
TEST(area, uniform_emission_contract_of_emissive) {
  for (bool two_sided : {false, true}) {
    auto m = emissive(Color(0.3f, 2.f, 5.f), two_sided);
    ASSERT_TRUE(m->uniform_emission());
    Pcg32 rng(11);
    for (int i = 0; i < 1000; ++i) {
      SurfaceInteraction si;
      si.p = Vec3f(rng.next_float(), rng.next_float(), rng.next_float()) * 10.f;
      si.ng = si.ns = normalize(Vec3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f));
      si.uv = rng.next_2d();
      Vec3f wo = normalize(Vec3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f));
      Color expect = (two_sided || dot(si.ng, wo) > 0.f) ? m->average_emission() : Color(0.f);
      ASSERT_EQ(m->emission(si, wo), expect) << "two_sided=" << two_sided;
    }
  }
}
