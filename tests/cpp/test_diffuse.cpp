// Material "diffuse" (material/diffuse.cpp), created through sg::create_material.
#include <gtest/gtest.h>

#include "core/error.h"
#include "material_checks.h"

using namespace sg;
using namespace sgtest;

namespace {

std::shared_ptr<Material> make_diffuse(const Color& albedo) {
  ParamSet p;
  p.set("albedo", std::vector<double>{albedo.x, albedo.y, albedo.z});
  return create_material("diffuse", p, no_textures(), "test");
}

std::string error_of(const std::string& type, const ParamSet& p) {
  try {
    create_material(type, p, no_textures(), "material 7");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(diffuse, sample_matches_pdf_chi2) {
  auto mat = make_diffuse(Color(0.2f, 0.5f, 0.8f));
  Pcg32 rng(101);
  uint64_t seed = 3000;
  for (double c : incoming_cosines()) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    check_sampling(*mat, si, wo, seed++, "diffuse, cos(wo) = " + std::to_string(c));
  }
}

TEST(diffuse, sample_matches_pdf_chi2_with_shading_normal) {
  // A shading normal tilted 30 degrees from the geometric one: sample() must reject what
  // pdf() assigns zero density to (directions below the geometric surface).
  auto mat = make_diffuse(Color(0.6f));
  Pcg32 rng(102);
  DVec3 ng = random_unit(rng);
  DVec3 ns = direction_at_cos(ng, std::cos(30.0 * k_pi_d / 180.0), rng);
  SurfaceInteraction si = make_si(ng, ns);
  Vec3f wo = to_f(direction_at_cos(ng, 0.2, rng));
  check_sampling(*mat, si, wo, 1100, "diffuse with tilted shading normal");
}

TEST(diffuse, eval_is_albedo_cos_over_pi_and_reflection_only) {
  auto mat = make_diffuse(Color(0.2f, 0.5f, 0.8f));
  Pcg32 rng(103);
  for (int i = 0; i < 1000; ++i) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(random_unit(rng)), wi = to_f(random_unit(rng));
    float co = dot(si.ng, wo), ci = dot(si.ng, wi);
    Color f = mat->eval(si, wo, wi);
    float pdf = mat->pdf(si, wo, wi);
    if (co * ci <= 0.f) {
      // Opposite sides: a diffuse reflector transmits nothing.
      EXPECT_TRUE(is_black(f));
      EXPECT_EQ(pdf, 0.f);
    } else {
      EXPECT_NEAR(f.y, 0.5 * std::fabs(ci) / k_pi_d, 1e-6);
      EXPECT_NEAR(pdf, std::fabs(ci) / k_pi_d, 1e-6);
    }
  }
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  EXPECT_EQ(mat->flags(), uint32_t(k_bsdf_diffuse | k_bsdf_reflection));
  EXPECT_EQ(mat->albedo(si), Color(0.2f, 0.5f, 0.8f));
  EXPECT_FALSE(mat->is_emissive());
  EXPECT_TRUE(is_black(mat->emission(si, Vec3f(0, 0, 1))));
}

TEST(diffuse, reciprocity) { check_reciprocity(*make_diffuse(Color(0.3f, 0.6f, 0.9f)), 104); }

TEST(diffuse, white_furnace) {
  auto mat = make_diffuse(Color(1.f));
  Pcg32 rng(105);
  uint64_t seed = 1200;
  for (double c : incoming_cosines()) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    check_white_furnace(*mat, si, wo, seed++, "diffuse, cos(wo) = " + std::to_string(c));
  }
}

TEST(diffuse, parameter_errors) {
  ParamSet typo;
  typo.set("albdo", 0.5);
  std::string msg = error_of("diffuse", typo);
  EXPECT_NE(msg.find("did you mean 'albedo'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("material 7"), std::string::npos) << "error does not name the context: " << msg;

  msg = error_of("difuse", ParamSet{});
  EXPECT_NE(msg.find("did you mean 'diffuse'"), std::string::npos) << msg;

  ParamSet too_bright;
  too_bright.set("albedo", 1.5);
  EXPECT_THROW(create_material("diffuse", too_bright, no_textures(), "t"), Error);
  ParamSet wrong_type;
  wrong_type.set("albedo", std::string("red"));
  EXPECT_THROW(create_material("diffuse", wrong_type, no_textures(), "t"), Error);
  ParamSet missing_texture;
  missing_texture.set("albedo", TextureRef{3});
  EXPECT_THROW(create_material("diffuse", missing_texture, no_textures(), "t"), Error);
}
