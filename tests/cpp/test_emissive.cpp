// Material "emissive" (material/emissive.cpp), created through sg::create_material:
// one- and two-sided emission, and its optional diffuse reflection lobe.
#include <gtest/gtest.h>

#include "core/error.h"
#include "material_checks.h"

using namespace sg;
using namespace sgtest;

namespace {

std::shared_ptr<Material> make_emissive(const Color& radiance, const Color& albedo, bool two_sided,
                                        double strength = 1.0) {
  ParamSet p;
  p.set("radiance", std::vector<double>{radiance.x, radiance.y, radiance.z});
  p.set("albedo", std::vector<double>{albedo.x, albedo.y, albedo.z});
  p.set("two_sided", two_sided);
  p.set("strength", strength);
  return create_material("emissive", p, no_textures(), "test");
}

std::string error_of(const ParamSet& p) {
  try {
    create_material("emissive", p, no_textures(), "material 3");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(emissive, one_sided_emits_only_towards_the_front) {
  auto mat = make_emissive(Color(1.f, 2.f, 3.f), Color(0.f), false, 2.0);
  EXPECT_TRUE(mat->is_emissive());
  EXPECT_FALSE(mat->two_sided_emission());
  EXPECT_EQ(mat->average_emission(), Color(2.f, 4.f, 6.f));
  Pcg32 rng(201);
  for (int i = 0; i < 2000; ++i) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(random_unit(rng));
    float c = dot(si.ng, wo);
    Color le = mat->emission(si, wo);
    if (c > 0.f) EXPECT_EQ(le, Color(2.f, 4.f, 6.f)) << "front side, cos " << c;
    else EXPECT_TRUE(is_black(le)) << "back side emits, cos " << c;
  }
  // Grazing but on the front side still emits; the emission is Lambertian (constant radiance).
  DVec3 n{0, 0, 1};
  SurfaceInteraction si = make_si(n, n);
  EXPECT_EQ(mat->emission(si, to_f(direction_at_cos(n, 0.01, rng))), Color(2.f, 4.f, 6.f));
  EXPECT_TRUE(is_black(mat->emission(si, to_f(direction_at_cos(n, -0.01, rng)))));
}

TEST(emissive, two_sided_emits_both_sides) {
  auto mat = make_emissive(Color(0.5f), Color(0.f), true);
  EXPECT_TRUE(mat->two_sided_emission());
  Pcg32 rng(202);
  for (int i = 0; i < 2000; ++i) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(random_unit(rng));
    EXPECT_EQ(mat->emission(si, wo), Color(0.5f));
  }
}

TEST(emissive, default_does_not_reflect) {
  ParamSet p;
  p.set("radiance", 4.0);
  auto mat = create_material("emissive", p, no_textures(), "test");
  EXPECT_EQ(mat->flags(), uint32_t(k_bsdf_none));
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  Pcg32 rng(203);
  for (int i = 0; i < 100; ++i) {
    Vec3f wo = to_f(direction_at_cos({0, 0, 1}, 0.5, rng)), wi = to_f(direction_at_cos({0, 0, 1}, 0.8, rng));
    EXPECT_TRUE(is_black(mat->eval(si, wo, wi)));
    EXPECT_EQ(mat->pdf(si, wo, wi), 0.f);
    BsdfSample bs;
    EXPECT_FALSE(mat->sample(si, wo, 0.5f, rng.next_2d(), &bs));
  }
  // Zero radiance is not an emitter.
  ParamSet dark;
  dark.set("radiance", 0.0);
  EXPECT_FALSE(create_material("emissive", dark, no_textures(), "test")->is_emissive());
}

TEST(emissive, reflection_lobe_sample_matches_pdf_chi2) {
  auto mat = make_emissive(Color(1.f), Color(0.7f, 0.4f, 0.1f), false);
  EXPECT_EQ(mat->flags(), uint32_t(k_bsdf_diffuse | k_bsdf_reflection));
  Pcg32 rng(204);
  uint64_t seed = 2000;
  for (double c : incoming_cosines()) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    check_sampling(*mat, si, wo, seed++, "emissive, cos(wo) = " + std::to_string(c));
  }
}

TEST(emissive, reciprocity) { check_reciprocity(*make_emissive(Color(1.f), Color(0.5f, 0.25f, 1.f), true), 205); }

TEST(emissive, white_furnace) {
  auto mat = make_emissive(Color(3.f), Color(1.f), false);
  Pcg32 rng(206);
  uint64_t seed = 2100;
  for (double c : incoming_cosines()) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    check_white_furnace(*mat, si, wo, seed++, "emissive, cos(wo) = " + std::to_string(c));
  }
}

TEST(emissive, parameter_errors) {
  ParamSet typo;
  typo.set("radience", 2.0);
  std::string msg = error_of(typo);
  EXPECT_NE(msg.find("did you mean 'radiance'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("material 3"), std::string::npos) << msg;

  ParamSet typo2;
  typo2.set("two_side", true);
  msg = error_of(typo2);
  EXPECT_NE(msg.find("did you mean 'two_sided'"), std::string::npos) << msg;

  ParamSet negative;
  negative.set("radiance", std::vector<double>{1.0, -1.0, 1.0});
  EXPECT_THROW(create_material("emissive", negative, no_textures(), "t"), Error);
  ParamSet wrong_type;
  wrong_type.set("two_sided", std::string("yes"));
  EXPECT_THROW(create_material("emissive", wrong_type, no_textures(), "t"), Error);

  msg = "";
  try {
    create_material("emisive", ParamSet{}, no_textures(), "t");
  } catch (const Error& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("did you mean 'emissive'"), std::string::npos) << msg;
}
