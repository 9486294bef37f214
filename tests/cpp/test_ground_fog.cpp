// Medium "ground_fog" (medium/ground_fog.cpp): the height profile and the coverage mask (the share of
// fogged ground follows `coverage`; coverage 1 is the profile alone), the Koschmieder scale, the
// same field for the same seed and another for another, bad parameters. Tracking, bounds and
// transmittance: test_tracking.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "tracked_media.h"

using namespace sg;
using namespace sgtest;

TEST(ground_fog, profile_coverage_and_visibility) {
  // Coverage 1: density exp(-y / H) exactly, extinction 3.912 / V at density 1.
  auto full = small_ground_fog(1.0);
  const TrackedMedium& f = tracked(*full);
  EXPECT_NEAR(f.sigma(), 3.912 / 150.0, 1e-6);
  for (float y : {0.f, 1.f, 4.f, 10.f}) EXPECT_NEAR(f.density({13.f, y, -7.f}), std::exp(-y / 4.0), 1e-5) << y;
  EXPECT_EQ(f.density({0.f, -2.f, 0.f}), 1.f);  // below the base
  // Horizontal ray at y = 0 through uniform fog: Beer-Lambert exactly from the deterministic quadrature.
  EXPECT_NEAR(full->transmittance({-100.f, 0.f, 0.f}, {1.f, 0.f, 0.f}, 100.f), std::exp(-3.912 / 150.0 * 100.0), 2e-4);
  // The share of fogged ground (mask > 0.5 on y = 0) follows coverage.
  for (double c : {0.3, 0.6, 0.9}) {
    auto m = small_ground_fog(c);
    const TrackedMedium& t = tracked(*m);
    int in = 0, n = 0;
    for (int i = 0; i < 200; ++i)
      for (int k = 0; k < 200; ++k, ++n) in += t.density({-290.f + 2.9f * i, 0.f, -290.f + 2.9f * k}) > 0.5f;
    std::printf("ground_fog coverage %.1f: fogged share of the ground %.3f\n", c, double(in) / n);
    EXPECT_NEAR(double(in) / n, c, 0.15) << c;
  }
}

TEST(ground_fog, seeds_and_bad_parameters) {
  ParamSet p;
  p.set("visibility", 100.0);
  auto a = create_medium("ground_fog", p, "medium"), b = create_medium("ground_fog", p, "medium");
  p.set("seed", int64_t(9));
  auto c = create_medium("ground_fog", p, "medium");
  int same = 0, differ = 0;
  for (int i = 0; i < 100; ++i) {
    const Vec3f x(float(i) * 7.1f - 300.f, 1.f, float(i) * 3.3f);
    same += tracked(*a).density(x) == tracked(*b).density(x);
    differ += tracked(*a).density(x) != tracked(*c).density(x);
  }
  EXPECT_EQ(same, 100);
  EXPECT_GT(differ, 50);
  auto expect_error = [](ParamSet q, const char* what) {
    try {
      create_medium("ground_fog", q, "medium");
      FAIL() << "accepted: " << what;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect_error(ParamSet(), "visibility");
  ParamSet q = p;
  q.set("coverage", 1.5);
  expect_error(q, "coverage");
  q = p;
  q.set("top", -1.0);
  expect_error(q, "top");
  q = p;
  q.set("scale_height", 0.0);
  expect_error(q, "scale_height");
  q = p;
  q.set("majorant_cells", std::vector<double>{8.5, 4, 4});
  expect_error(q, "majorant_cells");
  q = p;
  q.set("scale_hieght", 3.0);
  expect_error(q, "did you mean");
}
