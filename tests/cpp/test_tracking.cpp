// Heterogeneous media tracked against a majorant grid (medium/tracking.h), for each plugin
// (ground_fog, clouds, grid): no density exceeds its cell's majorant (or falls below its
// minorant); ratio tracking's transmittance agrees with a brute-force quadrature of the optical
// depth along random rays within Monte Carlo error (z-scores), and so does the deterministic
// quadrature; delta tracking's free-flight distances follow the quadrature's CDF (chi-square); the
// decoupled points' estimator integrates sigma_t T per bin; empty cells cost no density lookup.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>

#include "chi2.h"
#include "tracked_media.h"

using namespace sg;
using namespace sgtest;

namespace {

std::shared_ptr<Medium> make(const std::string& name) {
  if (name == "ground_fog") return small_ground_fog();
  if (name == "clouds") return small_clouds();
  return small_grid();
}

struct TestRay {
  Vec3f o, d;
  float t_max;
};

/// Random rays through the medium's box: origins in the box grown by 10%, directions flattened
/// towards the horizontal for the layered media, a quarter of them infinite.
std::vector<TestRay> rays(const std::string& name, const TrackedMedium& m, int n, uint64_t seed) {
  const Box3& b = m.majorants().box();
  Pcg32 rng(seed);
  std::vector<TestRay> out;
  const Vec3f size = b.hi - b.lo;
  const float diag = length(size);
  while (int(out.size()) < n) {
    TestRay r;
    r.o = b.lo - size * 0.05f + Vec3f(rng.next_float(), rng.next_float(), rng.next_float()) * (size * 1.1f);
    if (name == "ground_fog") r.o.y = b.lo.y + 4.f + 8.f * rng.next_float();
    Vec3f d(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
    if (name == "ground_fog") d.y *= 0.05f;
    if (name == "clouds") d.y *= 0.3f;
    if (length(d) < 0.05f) continue;
    // Non-unit directions: t in units of |d|.
    r.d = d * (0.5f + rng.next_float());
    const float scale = name == "grid" ? 1.f : 0.4f;
    r.t_max = (out.size() % 4 == 3) ? k_inf : scale * diag * (0.2f + rng.next_float()) / length(r.d);
    // Rays that miss the medium test nothing here.
    if (brute_optical_depth(m, r.o, r.d, r.t_max, 200) < 0.05) continue;
    out.push_back(r);
  }
  return out;
}

/// The part [*lo, *hi] of [0, t_max) inside the medium's box.
bool clip_box(const TrackedMedium& m, const TestRay& r, double* lo, double* hi) {
  const Box3& box = m.majorants().box();
  *lo = 0.0;
  *hi = r.t_max;
  for (int a = 0; a < 3; ++a) {
    if (r.d[a] == 0.f) {
      if (r.o[a] < box.lo[a] || r.o[a] > box.hi[a]) return false;
      continue;
    }
    double ta = (double(box.lo[a]) - r.o[a]) / r.d[a], tb = (double(box.hi[a]) - r.o[a]) / r.d[a];
    if (ta > tb) std::swap(ta, tb);
    *lo = std::max(*lo, ta);
    *hi = std::min(*hi, tb);
  }
  return *lo < *hi;
}

}  // namespace

class TrackedMediumTest : public ::testing::TestWithParam<std::string> {};

TEST_P(TrackedMediumTest, no_density_exceeds_its_cells_bounds) {
  auto medium = make(GetParam());
  const TrackedMedium& m = tracked(*medium);
  const MajorantGrid& g = m.majorants();
  Pcg32 rng(4101);
  double worst = 0.0, sum_d = 0.0, sum_mx = 0.0;
  int empty = 0, cells = g.res(0) * g.res(1) * g.res(2);
  for (int z = 0; z < g.res(2); ++z)
    for (int y = 0; y < g.res(1); ++y)
      for (int x = 0; x < g.res(0); ++x) empty += g.cell(x, y, z).mx == 0.f;
  const int n = 400000;
  for (int i = 0; i < n; ++i) {
    // A random cell, a random point in it; every fourth point on one of its faces (where the
    // neighbouring cells' values meet).
    const int cx = int(rng.next_u32() % uint32_t(g.res(0))), cy = int(rng.next_u32() % uint32_t(g.res(1))),
              cz = int(rng.next_u32() % uint32_t(g.res(2)));
    const Box3 c = g.cell_box(cx, cy, cz);
    Vec3f u(rng.next_float(), rng.next_float(), rng.next_float());
    if (i % 4 == 3) u[int(rng.next_u32() % 3)] = float(rng.next_u32() % 2);
    const Vec3f p = c.lo + Vec3f(u.x * (c.hi.x - c.lo.x), u.y * (c.hi.y - c.lo.y), u.z * (c.hi.z - c.lo.z));
    const float d = m.density(p);
    const DensityBounds& b = g.cell(cx, cy, cz);
    ASSERT_LE(d, b.mx) << GetParam() << " at (" << p.x << ", " << p.y << ", " << p.z << ") cell " << cx << " "
                       << cy << " " << cz;
    ASSERT_GE(d, b.mn) << GetParam() << " at (" << p.x << ", " << p.y << ", " << p.z << ")";
    if (b.mx > 0.f) worst = std::max(worst, double(d) / b.mx);
    sum_d += d;
    sum_mx += b.mx;
  }
  std::printf("%s: %d x %d x %d majorant cells, %d empty (%.0f%%); max density / majorant %.4f, mean density / "
              "mean majorant %.3f\n",
              GetParam().c_str(), g.res(0), g.res(1), g.res(2), empty, 100.0 * empty / cells, worst, sum_d / sum_mx);
}

TEST_P(TrackedMediumTest, ratio_tracking_transmittance_matches_quadrature) {
  auto medium = make(GetParam());
  const TrackedMedium& m = tracked(*medium);
  const auto rs = rays(GetParam(), m, 16, 4102);
  Pcg32 rng(4103);
  const int n = 4000;
  double max_z = 0.0, max_quad_err = 0.0;
  for (size_t k = 0; k < rs.size(); ++k) {
    const TestRay& r = rs[k];
    const double t_ref = std::exp(-brute_optical_depth(m, r.o, r.d, r.t_max));
    double s = 0.0, s2 = 0.0;
    for (int i = 0; i < n; ++i) {
      MediumRng st = stream(rng);
      const double t = medium->transmittance_estimate(r.o, r.d, r.t_max, st);
      ASSERT_GE(t, 0.0);
      s += t;
      s2 += t * t;
    }
    const double mean = s / n, var = std::max(0.0, s2 / n - mean * mean);
    const double se = std::sqrt(var / n);
    const double z = se > 0.0 ? (mean - t_ref) / se : (std::fabs(mean - t_ref) < 1e-5 ? 0.0 : 1e9);
    const double t_quad = medium->transmittance(r.o, r.d, r.t_max);
    std::printf("%s ray %2zu: ratio tracking T %.4f vs quadrature %.4f (z %+.2f); deterministic quadrature %.4f "
                "(error %.1e)\n",
                GetParam().c_str(), k, mean, t_ref, z, t_quad, t_quad - t_ref);
    EXPECT_LT(std::fabs(z), 4.5) << "ray " << k;
    EXPECT_NEAR(t_quad, t_ref, 2e-3) << "ray " << k;
    max_z = std::max(max_z, std::fabs(z));
    max_quad_err = std::max(max_quad_err, std::fabs(t_quad - t_ref));
  }
  std::printf("%s: %zu rays x %d estimates: max |z| %.2f; deterministic quadrature max error %.1e\n",
              GetParam().c_str(), rs.size(), n, max_z, max_quad_err);
}

TEST_P(TrackedMediumTest, delta_tracking_free_flights_chi2) {
  auto medium = make(GetParam());
  const TrackedMedium& m = tracked(*medium);
  const auto rs = rays(GetParam(), m, 2, 4104);
  Pcg32 rng(4105);
  for (size_t k = 0; k < rs.size(); ++k) {
    const TestRay& r = rs[k];
    double lo, hi;
    ASSERT_TRUE(clip_box(m, r, &lo, &hi));
    const int bins = 40, n = 200000;
    // The CDF at the bins' edges from the brute-force optical depth.
    std::vector<double> T(bins + 1);
    for (int b = 0; b <= bins; ++b)
      T[size_t(b)] = std::exp(-brute_optical_depth(m, r.o, r.d, lo + (hi - lo) * b / bins, 4000 + 500 * b));
    std::vector<double> obs(bins + 1, 0.0), exp(bins + 1);
    for (int i = 0; i < n; ++i) {
      MediumRng st = stream(rng);
      float t;
      if (medium->sample_distance(r.o, r.d, r.t_max, st, &t)) {
        ASSERT_GE(t, lo - 1e-3 * (hi - lo));
        ASSERT_LE(t, hi + 1e-3 * (hi - lo));
        obs[size_t(std::clamp(int((t - lo) / (hi - lo) * bins), 0, bins - 1))] += 1.0;
      } else {
        obs[bins] += 1.0;
      }
    }
    for (int b = 0; b < bins; ++b) exp[size_t(b)] = n * (T[size_t(b)] - T[size_t(b) + 1]);
    exp[bins] = n * T[bins];
    Chi2Result res = chi2_test(obs, exp);
    std::printf("%s ray %zu: free flights pass %.4f (quadrature T %.4f), %s\n", GetParam().c_str(), k, obs[bins] / n,
                T[bins], res.message.c_str());
    EXPECT_TRUE(res.ok) << res.message;
  }
}

TEST_P(TrackedMediumTest, decoupled_points_integrate_sigma_t_transmittance) {
  // E[weight [t in bin]] = integral over the bin of sigma_t T = T(a) - T(b): per bin and in total
  // (1 - T(L)), within 4.5 standard errors.
  auto medium = make(GetParam());
  const TrackedMedium& m = tracked(*medium);
  const auto rs = rays(GetParam(), m, 2, 4106);
  Pcg32 rng(4107);
  for (size_t k = 0; k < rs.size(); ++k) {
    const TestRay& r = rs[k];
    double lo, hi;
    ASSERT_TRUE(clip_box(m, r, &lo, &hi));
    const int bins = 10, n = 100000;
    std::vector<double> T(bins + 1);
    for (int b = 0; b <= bins; ++b)
      T[size_t(b)] = std::exp(-brute_optical_depth(m, r.o, r.d, lo + (hi - lo) * b / bins, 4000 + 2000 * b));
    std::vector<double> s(bins, 0.0), s2(bins, 0.0);
    double tot = 0.0, tot2 = 0.0;
    for (int i = 0; i < n; ++i) {
      MediumRng st = stream(rng);
      float t, w;
      if (!medium->sample_in_segment(r.o, r.d, r.t_max, st, &t, &w)) continue;
      ASSERT_GE(w, 0.f);
      const int b = std::clamp(int((t - lo) / (hi - lo) * bins), 0, bins - 1);
      s[size_t(b)] += w;
      s2[size_t(b)] += double(w) * w;
      tot += w;
      tot2 += double(w) * w;
    }
    double max_z = 0.0;
    for (int b = 0; b < bins; ++b) {
      const double mean = s[size_t(b)] / n, se = std::sqrt(std::max(0.0, s2[size_t(b)] / n - mean * mean) / n);
      const double expect = T[size_t(b)] - T[size_t(b) + 1];
      const double z = se > 0.0 ? (mean - expect) / se : (std::fabs(mean - expect) < 1e-4 ? 0.0 : 1e9);
      EXPECT_LT(std::fabs(z), 4.5) << "bin " << b << ": " << mean << " vs " << expect;
      max_z = std::max(max_z, std::fabs(z));
    }
    const double mean = tot / n, se = std::sqrt(std::max(0.0, tot2 / n - mean * mean) / n);
    const double z = (mean - (1.0 - T[bins])) / se;
    std::printf("%s ray %zu: decoupled points' total weight %.4f vs 1 - T %.4f (z %+.2f), per bin max |z| %.2f\n",
                GetParam().c_str(), k, mean, 1.0 - T[bins], z, max_z);
    EXPECT_LT(std::fabs(z), 4.5);
  }
}

INSTANTIATE_TEST_SUITE_P(media, TrackedMediumTest, ::testing::Values("ground_fog", "clouds", "grid"));

namespace {

/// Density 0.5 + 0.4 sin(x) cos(z) for x > 0 and none for x <= 0, counting its lookups.
class HalfEmpty final : public TrackedMedium {
 public:
  HalfEmpty() : TrackedMedium(0.3f, Color(1.f), 0.f, 0.05f) {
    m_grid.build(Box3{Vec3f(-10.f), Vec3f(10.f)}, 8, 8, 8, [](const Vec3f& lo, const Vec3f& hi) {
      return hi.x <= 0.f ? DensityBounds{0.f, 0.f} : DensityBounds{0.f, 0.9f};
    });
  }
  float density(const Vec3f& p) const override {
    ++lookups;
    return p.x <= 0.f ? 0.f : 0.5f + 0.4f * std::sin(p.x) * std::cos(p.z);
  }
  mutable std::atomic<int> lookups{0};
};

}  // namespace

TEST(tracking, empty_cells_cost_no_lookup) {
  HalfEmpty m;
  Pcg32 rng(4108);
  for (int i = 0; i < 1000; ++i) {
    // Rays in the empty half x < 0 (cell planes at multiples of 2.5: x <= -2.5 stays in empty cells).
    const Vec3f o(-9.f + 6.f * rng.next_float(), -9.f + 18.f * rng.next_float(), -9.f + 18.f * rng.next_float());
    const Vec3f d = normalize(Vec3f(-rng.next_float(), rng.next_float() - 0.5f, rng.next_float() - 0.5f));
    MediumRng st = stream(rng);
    float t, w;
    EXPECT_EQ(m.transmittance_estimate(o, d, k_inf, st), 1.f);
    EXPECT_FALSE(m.sample_distance(o, d, k_inf, st, &t));
    EXPECT_FALSE(m.sample_in_segment(o, d, k_inf, st, &t, &w));
    EXPECT_EQ(m.transmittance(o, d, k_inf), 1.f);
  }
  EXPECT_EQ(m.lookups.load(), 0);
  // Through the full half: lookups, and transmittance < 1.
  MediumRng st = stream(rng);
  EXPECT_LT(m.transmittance_estimate(Vec3f(-9.f, 0.f, 0.f), Vec3f(1.f, 0.f, 0.f), k_inf, st), 1.f);
  EXPECT_GT(m.lookups.load(), 0);
}

TEST(tracking, dda_visits_cells_in_order_and_covers_the_ray) {
  HalfEmpty m;
  Pcg32 rng(4109);
  for (int i = 0; i < 2000; ++i) {
    const Vec3f o(-15.f + 30.f * rng.next_float(), -15.f + 30.f * rng.next_float(), -15.f + 30.f * rng.next_float());
    Vec3f d(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
    if (i % 5 == 0) d.y = 0.f;  // axis-parallel components
    if (i % 7 == 0) d.z = 0.f;
    if (length(d) < 1e-3f) continue;
    MajorantDda dda(m.majorants(), o, d, 40.f);
    MajorantSegment s;
    float prev = -1.f, covered = 0.f, first = -1.f;
    while (dda.next(&s)) {
      if (first < 0.f) first = s.t0;
      if (prev >= 0.f) {
        ASSERT_NEAR(s.t0, prev, 1e-4f);
      }
      ASSERT_GE(s.t1, s.t0);
      // The segment's midpoint lies in the cell whose bounds it carries.
      const Vec3f mid = o + d * (0.5f * (s.t0 + s.t1));
      if (s.t1 - s.t0 > 1e-4f) {
        int cx, cy, cz;
        m.majorants().cell_of(mid, &cx, &cy, &cz);
        ASSERT_EQ(m.majorants().cell(cx, cy, cz).mx, s.b.mx);
      }
      covered += s.t1 - s.t0;
      prev = s.t1;
    }
    double lo, hi;
    TestRay r{o, d, 40.f};
    if (clip_box(m, r, &lo, &hi)) {
      EXPECT_NEAR(covered, hi - lo, 1e-3 * (hi - lo) + 1e-4);
      EXPECT_NEAR(first, lo, 1e-4);
    } else {
      EXPECT_EQ(covered, 0.f);
    }
  }
}
