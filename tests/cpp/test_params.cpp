// ParamSet: typed getters, defaults, the record of read keys; "did you mean" matching.
#include <gtest/gtest.h>

#include "core/error.h"
#include "core/params.h"

using namespace sg;

TEST(params, typed_getters_and_defaults) {
  ParamSet p;
  p.set("albedo", std::vector<double>{0.1, 0.2, 0.3});
  p.set("strength", int64_t(2));
  p.set("two_sided", true);
  EXPECT_EQ(p.get_color("albedo", Color(0.f)), Color(0.1f, 0.2f, 0.3f));
  EXPECT_FLOAT_EQ(p.get_float("strength", 1.f), 2.f);
  EXPECT_TRUE(p.get_bool("two_sided", false));
  EXPECT_FLOAT_EQ(p.get_float("missing", 7.f), 7.f);
  EXPECT_TRUE(p.queried("albedo") && p.queried("strength") && p.queried("two_sided"));
}

TEST(params, queried_records_reads_only) {
  ParamSet p;
  p.set("albdo", 0.5);
  p.get_color("albedo", Color(0.5f));
  EXPECT_TRUE(p.queried("albedo"));
  EXPECT_FALSE(p.queried("albdo"));
}

TEST(params, wrong_type_is_an_error) {
  ParamSet p;
  p.set("albedo", std::string("red"));
  EXPECT_THROW(p.get_color("albedo", Color(0.f)), Error);
  ParamSet q;
  q.set("albedo", std::vector<double>{1.0, 2.0});
  EXPECT_THROW(q.get_color("albedo", Color(0.f)), Error);
}

TEST(params, edit_distance) {
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(closest_match("radiance", {"radiance", "albedo"}), "radiance");
  EXPECT_EQ(closest_match("zzzzzz", {"radiance", "albedo"}), "");
}
