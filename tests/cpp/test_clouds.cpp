// Medium "clouds" (medium/clouds.cpp): nothing outside the layer, flat bases (no density in the
// lowest sliver), thinner tops than middles, the covered share of the sky by coverage, bad parameters.
// Tracking, bounds and transmittance: test_tracking.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "tracked_media.h"

using namespace sg;
using namespace sgtest;

TEST(clouds, layer_shape_and_coverage) {
  auto m = small_clouds();  // 100..200 m
  const TrackedMedium& c = tracked(*m);
  EXPECT_NEAR(c.sigma(), 3.912 / 60.0, 1e-6);
  // Mean density by height: zero at the base, largest in the lower half, thinning to the top.
  double mean[10] = {};
  for (int h = 0; h < 10; ++h)
    for (int i = 0; i < 100; ++i)
      for (int k = 0; k < 100; ++k)
        mean[h] += c.density({-390.f + 7.8f * i, 100.f + 10.f * h + 0.01f, -390.f + 7.8f * k}) / 1e4;
  std::printf("clouds: mean density by tenth of the layer:");
  for (double v : mean) std::printf(" %.3f", v);
  std::printf("\n");
  EXPECT_LT(mean[0], 0.01);
  EXPECT_GT(mean[2], mean[9]);
  EXPECT_GT(mean[3], 0.1);
  // The covered share of the sky: vertical rays from the ground that pass under 50% transmittance.
  int covered = 0;
  for (int i = 0; i < 40; ++i)
    for (int k = 0; k < 40; ++k)
      covered += m->transmittance({-380.f + 19.f * i, 0.f, -380.f + 19.f * k}, {0.f, 1.f, 0.f}, k_inf) < 0.5f;
  std::printf("clouds coverage 0.5: share of vertical rays with T < 0.5: %.3f\n", covered / 1600.0);
  EXPECT_GT(covered / 1600.0, 0.25);
  EXPECT_LT(covered / 1600.0, 0.8);
  // Outside the layer: transmittance 1 (nothing below the base, above the tops).
  EXPECT_EQ(m->transmittance({0.f, 50.f, 0.f}, {1.f, 0.f, 0.f}, k_inf), 1.f);
  EXPECT_EQ(m->transmittance({0.f, 250.f, 0.f}, {1.f, 0.1f, 0.f}, k_inf), 1.f);
}

TEST(clouds, bad_parameters) {
  ParamSet p;
  p.set("visibility", 50.0);
  p.set("bottom", 800.0);
  p.set("top", 700.0);
  try {
    create_medium("clouds", p, "medium");
    FAIL() << "top below bottom accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bottom"), std::string::npos) << e.what();
  }
  ParamSet q;
  q.set("extinction", 0.05);
  q.set("g", -1.0);
  EXPECT_THROW(create_medium("clouds", q, "medium"), Error);
  ParamSet r;
  r.set("visibility", 50.0);
  r.set("octaves", int64_t(0));
  EXPECT_THROW(create_medium("clouds", r, "medium"), Error);
}
