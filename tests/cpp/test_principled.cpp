// Material "principled" (material/principled.cpp) and the normal / bump mapping helpers
// (material/normal_mapping.h), through sg::create_material.
#include <gtest/gtest.h>

#include <map>

#include "core/error.h"
#include "material/microfacet.h"
#include "material/normal_mapping.h"
#include "material_checks.h"

using namespace sg;
using namespace sgtest;

namespace {

constexpr double k_glossy_cell_eps = 1e-7;

using Values = std::map<std::string, ParamSet::Value>;

std::shared_ptr<Material> make(const Values& values, const MaterialContext& ctx = no_textures()) {
  ParamSet p;
  for (const auto& [k, v] : values) p.set(k, v);
  return create_material("principled", p, ctx, "test");
}

std::vector<double> rgb(const Color& c) { return {c.x, c.y, c.z}; }

std::string error_of(const Values& values) {
  try {
    make(values);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

/// A context whose texture ids 0.. are the given constant colours.
MaterialContext constant_textures(std::vector<Color> colors) {
  MaterialContext ctx = no_textures();
  ctx.textures = [colors](uint32_t id) -> std::shared_ptr<Texture> {
    return id < colors.size() ? make_constant_texture(colors[id]) : nullptr;
  };
  return ctx;
}

/// Independent GGX conductor with Schlick F0 (double precision, Walter et al. 2007 eq. 20,
/// Heitz 2014 eq. 99 height-correlated G2, Schlick 1994): f cos_i.
double ggx_schlick(const DVec3& n, const DVec3& wo, const DVec3& wi, double alpha, double f0) {
  double co = ddot(n, wo), ci = ddot(n, wi);
  if (co <= 0 || ci <= 0) return 0.0;
  DVec3 h = dnormalize(DVec3{wo.x + wi.x, wo.y + wi.y, wo.z + wi.z});
  double nh = ddot(n, h), oh = ddot(wo, h);
  double a2 = alpha * alpha;
  double d = a2 / (k_pi_d * std::pow(nh * nh * (a2 - 1) + 1, 2));
  auto lambda = [&](double c) { return 0.5 * (-1 + std::sqrt(1 + a2 * (1 - c * c) / (c * c))); };
  double g2 = 1 / (1 + lambda(co) + lambda(ci));
  double f = f0 + (1 - f0) * std::pow(1 - oh, 5);
  return f * d * g2 / (4 * co);
}

/// Mean sample weight (luminance; transmission weights times eta^2, which undoes the
/// radiance scaling, so that the result is the fraction of energy kept) and the maximum.
double furnace(const Material& mat, const SurfaceInteraction& si, const Vec3f& wo, uint64_t seed, int n,
               double* max_w) {
  Pcg32 rng(seed);
  double s = 0.0;
  *max_w = 0.0;
  for (int i = 0; i < n; ++i) {
    BsdfSample bs;
    float u_lobe = rng.next_float();
    Vec2f u = rng.next_2d();
    if (!mat.sample(si, wo, u_lobe, u, &bs)) continue;
    double w = luminance(bs.weight) * double(bs.eta) * double(bs.eta);
    s += w;
    *max_w = std::max(*max_w, w);
  }
  return s / n;
}

struct Case {
  const char* name;
  Values params;
};

std::vector<Case> cases() {
  return {
      {"dielectric rough", {{"base_color", rgb(Color(0.2f, 0.5f, 0.8f))}, {"roughness", 0.5}}},
      {"metal", {{"base_color", rgb(Color(0.9f, 0.6f, 0.3f))}, {"metallic", 1.0}, {"roughness", 0.3}}},
      {"half metal + clearcoat",
       {{"base_color", rgb(Color(0.7f, 0.3f, 0.3f))},
        {"metallic", 0.5},
        {"roughness", 0.2},
        {"specular", 0.8},
        {"clearcoat", 0.7},
        {"clearcoat_roughness", 0.1}}},
      {"transmission",
       {{"base_color", rgb(Color(0.9f, 0.95f, 1.f))}, {"transmission", 0.8}, {"roughness", 0.3}, {"ior", 1.45}}},
  };
}

}  // namespace

// Chi-square tests: 4 parameter sets x 5 directions = 20 (see chi2.h).
TEST(principled, sample_matches_pdf_chi2) {
  Pcg32 rng(301);
  uint64_t seed = 7000;
  for (const Case& c : cases()) {
    auto mat = make(c.params);
    for (double cos_o : {1.0, 0.5, 0.1, 0.01, -0.5}) {
      DVec3 n = random_unit(rng);
      SurfaceInteraction si = make_si(n, n);
      Vec3f wo = to_f(direction_at_cos(n, cos_o, rng));
      auto deltas = check_sampling_with_deltas(*mat, si, wo, seed++,
                                               std::string(c.name) + ", cos(wo) = " + std::to_string(cos_o), 1000000,
                                               k_glossy_cell_eps);
      EXPECT_TRUE(deltas.empty());
    }
  }
}

TEST(principled, eval_and_pdf_are_consistent) {
  // Wherever eval is non-zero, pdf must be too (else that light is never sampled); opaque
  // sets reflect only.
  for (const Case& c : cases()) {
    auto mat = make(c.params);
    bool transmits = c.params.count("transmission") > 0;
    Pcg32 rng(302);
    int n_nonzero = 0, n_transmit = 0;
    for (int i = 0; i < 20000; ++i) {
      DVec3 n = random_unit(rng);
      SurfaceInteraction si = make_si(n, n);
      Vec3f wo = to_f(random_unit(rng)), wi = to_f(random_unit(rng));
      Color f = mat->eval(si, wo, wi);
      float pdf = mat->pdf(si, wo, wi);
      ASSERT_TRUE(is_finite(f) && std::isfinite(pdf)) << c.name;
      ASSERT_GE(pdf, 0.f);
      bool same_side = dot(si.ng, wo) * dot(si.ng, wi) > 0.f;
      if (!same_side && !transmits) {
        EXPECT_TRUE(is_black(f)) << c.name;
        EXPECT_EQ(pdf, 0.f) << c.name;
      }
      if (!is_black(f)) {
        ++n_nonzero;
        n_transmit += !same_side;
        EXPECT_GT(pdf, 0.f) << c.name;
      }
    }
    EXPECT_GT(n_nonzero, 8000) << c.name;
    if (transmits) {
      EXPECT_GT(n_transmit, 1000) << c.name;
    }
  }
}

TEST(principled, reciprocity) {
  auto cs = cases();
  for (int i = 0; i < 3; ++i) check_reciprocity(*make(cs[size_t(i)].params), 303 + uint64_t(i));
}

TEST(principled, white_furnace_at_most_one) {
  // White base colour: the opaque dielectric is lossless up to the table accuracy (spec +
  // coupled diffuse = E + (1 - E)), the metal loses only single-scattering energy, the
  // clearcoat and glass stay <= 1. Required: <= 1.01 everywhere, and >= 0.98 for the
  // white dielectric (no loss either); quadrature of eval for the reflection-only sets.
  struct F {
    Values p;
    bool lossless;
  };
  std::vector<F> sets = {
      {{{"base_color", 1.0}, {"roughness", 0.05}}, true},
      {{{"base_color", 1.0}, {"roughness", 0.5}}, true},
      {{{"base_color", 1.0}, {"roughness", 1.0}, {"specular", 1.0}}, true},
      {{{"base_color", 1.0}, {"metallic", 1.0}, {"roughness", 0.2}}, false},
      {{{"base_color", 1.0}, {"metallic", 0.3}, {"clearcoat", 1.0}, {"clearcoat_roughness", 0.0}}, false},
      {{{"base_color", 1.0}, {"transmission", 1.0}, {"roughness", 0.2}}, false},
  };
  Pcg32 rng(304);
  uint64_t seed = 7100;
  for (size_t k = 0; k < sets.size(); ++k) {
    auto mat = make(sets[k].p);
    for (double c : incoming_cosines()) {
      DVec3 n = random_unit(rng);
      SurfaceInteraction si = make_si(n, n);
      Vec3f wo = to_f(direction_at_cos(n, c, rng));
      double max_w;
      double mean = furnace(*mat, si, wo, seed++, 100000, &max_w);
      std::string what = "set " + std::to_string(k) + ", cos " + std::to_string(c);
      EXPECT_LE(mean, 1.01) << what;
      if (sets[k].lossless) {
        EXPECT_GE(mean, 0.98) << what;
      }
      // Quadrature of eval (independent of sample()) for the broad lobes (narrow ones make
      // the adaptive quadrature slow).
      if (k == 1 || k == 2) {
        double q = eval_integral(*mat, si, wo, 1e-6);
        EXPECT_NEAR(q, 1.0, 0.01) << what;
      }
    }
  }
}

TEST(principled, rough_dielectric_without_specular_is_close_to_diffuse) {
  // metallic 0, roughness 1, specular 0: only the Schlick term (1 - c)^5 remains; the
  // directional albedo is within 3% of the base colour's (luminance) away from grazing.
  Color base(0.6f, 0.4f, 0.2f);
  auto mat = make({{"base_color", rgb(base)}, {"roughness", 1.0}, {"specular", 0.0}});
  Pcg32 rng(305);
  for (double c : {1.0, 0.7, 0.4}) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, c, rng));
    EXPECT_NEAR(eval_integral(*mat, si, wo, 1e-7), luminance(base), 0.03 * luminance(base)) << c;
    EXPECT_EQ(mat->albedo(si), base);
  }
}

TEST(principled, metallic_equals_ggx_conductor_with_schlick_f0) {
  Color base(0.95f, 0.64f, 0.54f);
  float roughness = 0.4f;
  auto mat = make({{"base_color", rgb(base)}, {"metallic", 1.0}, {"roughness", double(roughness)}});
  Pcg32 rng(306);
  int checked = 0;
  for (int i = 0; i < 5000; ++i) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    DVec3 wo = random_unit(rng), wi = random_unit(rng);
    if (ddot(n, wo) < 0.02 || ddot(n, wi) < 0.02) continue;
    Color f = mat->eval(si, to_f(wo), to_f(wi));
    double alpha = double(roughness) * roughness;
    for (int k = 0; k < 3; ++k) {
      double ref = ggx_schlick(to_d(si.ns), to_d(to_f(wo)), to_d(to_f(wi)), alpha, base[k]);
      ASSERT_NEAR(f[k], ref, 1e-4 * ref + 1e-7) << i;
    }
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

TEST(principled, metallic_roughness_texture_reads_blue_and_green_times_factors) {
  // glTF: metalness = B x metallic factor, roughness = G x roughness factor.
  auto ctx = constant_textures({Color(0.9f, 0.5f, 0.8f)});
  auto textured = make({{"base_color", 0.5}, {"metallic", 0.5}, {"roughness", 0.8}, {"metallic_roughness", TextureRef{0}}},
                       ctx);
  auto scalar = make({{"base_color", 0.5}, {"metallic", 0.4}, {"roughness", 0.4}});
  auto wrong = make({{"base_color", 0.5}, {"metallic", 0.45}, {"roughness", 0.72}});  // R and G swapped
  Pcg32 rng(307);
  double max_rel = 0, max_rel_wrong = 0;
  for (int i = 0; i < 2000; ++i) {
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f wo = to_f(direction_at_cos(n, 0.3 + 0.7 * rng.next_float(), rng));
    Vec3f wi = to_f(direction_at_cos(n, 0.3 + 0.7 * rng.next_float(), rng));
    double a = luminance(textured->eval(si, wo, wi)), b = luminance(scalar->eval(si, wo, wi));
    max_rel = std::max(max_rel, rel_diff(a, b));
    max_rel_wrong = std::max(max_rel_wrong, rel_diff(a, luminance(wrong->eval(si, wo, wi))));
  }
  EXPECT_LT(max_rel, 1e-5);
  EXPECT_GT(max_rel_wrong, 1e-2);
}

TEST(principled, emission_alpha_and_albedo) {
  auto ctx = constant_textures({Color(0.3f)});
  auto mat = make({{"base_color", rgb(Color(0.1f, 0.2f, 0.3f))},
                   {"metallic", 1.0},
                   {"emission", rgb(Color(1.f, 2.f, 3.f))},
                   {"emission_strength", 2.0},
                   {"alpha", TextureRef{0}},
                   {"alpha_mode", std::string("mask")},
                   {"alpha_cutoff", 0.25}},
                  ctx);
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  EXPECT_TRUE(mat->is_emissive());
  EXPECT_EQ(mat->emission(si, Vec3f(0, 0, 1)), Color(2.f, 4.f, 6.f));
  EXPECT_EQ(mat->emission(si, Vec3f(0, 0, -1)), Color(0.f));  // front face only
  EXPECT_EQ(mat->albedo(si), Color(0.1f, 0.2f, 0.3f));        // base colour, also for metals
  EXPECT_FLOAT_EQ(mat->alpha(si), 0.3f);  // the texture's first channel (no alpha channel)
  EXPECT_TRUE(mat->has_alpha());
  EXPECT_EQ(mat->alpha_cutoff(), 0.25f);
  EXPECT_TRUE(mat->alpha_opaque(si));  // 0.3 >= cutoff 0.25
  auto masked = make({{"alpha", TextureRef{0}}, {"alpha_mode", std::string("mask")}, {"alpha_factor", 0.5}}, ctx);
  EXPECT_FLOAT_EQ(masked->alpha(si), 0.15f);
  EXPECT_FALSE(masked->alpha_opaque(si));  // 0.15 < 0.5
  auto blend = make({{"alpha", 0.3}}, ctx);
  EXPECT_TRUE(blend->has_alpha());
  EXPECT_EQ(blend->alpha_cutoff(), 0.5f);
  EXPECT_FALSE(blend->alpha_opaque(si));
  EXPECT_FALSE(make({{"alpha", 0.7}})->has_alpha());  // never below the cutoff
  auto opaque = make({{"alpha", 0.3}, {"alpha_mode", std::string("opaque")}}, ctx);
  EXPECT_FALSE(opaque->has_alpha());
  EXPECT_EQ(opaque->alpha(si), 1.f);
  EXPECT_FALSE(make({})->is_emissive());
}

TEST(principled, bad_parameters_name_the_parameter_and_range) {
  EXPECT_NE(error_of({{"metallic", 1.5}}).find("'metallic'"), std::string::npos);
  EXPECT_NE(error_of({{"metallic", 1.5}}).find("[0, 1]"), std::string::npos);
  EXPECT_NE(error_of({{"roughness", -0.1}}).find("'roughness'"), std::string::npos);
  EXPECT_NE(error_of({{"specular", 2.0}}).find("'specular'"), std::string::npos);
  EXPECT_NE(error_of({{"ior", 0.5}}).find("[1.01, 3]"), std::string::npos);
  EXPECT_NE(error_of({{"transmission", 1.1}}).find("'transmission'"), std::string::npos);
  EXPECT_NE(error_of({{"alpha_mode", std::string("cutout")}}).find("opaque, mask, blend"), std::string::npos);
  EXPECT_NE(error_of({{"normal_map", TextureRef{3}}}).find("texture 3 does not exist"), std::string::npos);
  EXPECT_NE(error_of({{"base_colour", 0.5}}).find("did you mean 'base_color'"), std::string::npos);
}

TEST(principled, flat_normal_map_texel_leaves_ns_unchanged) {
  Pcg32 rng(308);
  for (int i = 0; i < 100; ++i) {
    DVec3 ng = random_unit(rng);
    SurfaceInteraction si = make_si(ng, direction_at_cos(ng, 0.9, rng));
    si.dpdu = normalize(cross(si.ns, Frame(si.ns).t));
    SurfaceInteraction out = si;
    apply_normal_map(&out, *make_constant_texture(Color(0.5f, 0.5f, 1.f)), 1.f);
    EXPECT_LT(length(out.ns - si.ns), 1e-6f);
    EXPECT_LT(length(out.dpdu - si.dpdu), 1e-6f);
  }
}

TEST(principled, tilted_normal_map_texel_tilts_ns_by_the_expected_angle) {
  // Texel (0.5 + 0.5 sin t, 0.5, 0.5 + 0.5 cos t) is the tangent-space normal
  // (sin t, 0, cos t): ns tilts by t towards +dpdu. Green tilts towards +v = ns x dpdu.
  // A scale s tilts by atan(s tan t).
  Pcg32 rng(309);
  for (double deg : {10.0, 30.0, 60.0}) {
    double t = deg * k_pi_d / 180.0;
    DVec3 n = random_unit(rng);
    SurfaceInteraction si = make_si(n, n);
    Vec3f s0 = si.dpdu, t0 = cross(si.ns, si.dpdu);
    Color texel(float(0.5 + 0.5 * std::sin(t)), 0.5f, float(0.5 + 0.5 * std::cos(t)));
    SurfaceInteraction a = si;
    apply_normal_map(&a, *make_constant_texture(texel), 1.f);
    EXPECT_NEAR(std::acos(std::min(1.0, double(dot(a.ns, si.ns)))), t, 1e-3) << deg;
    EXPECT_NEAR(dot(a.ns, s0), std::sin(t), 1e-3) << deg;
    EXPECT_NEAR(dot(a.ns, t0), 0.0, 1e-3) << deg;
    EXPECT_NEAR(dot(a.dpdu, a.ns), 0.0, 1e-5);
    EXPECT_NEAR(length(a.dpdu), 1.0, 1e-5);
    SurfaceInteraction g = si;
    apply_normal_map(&g, *make_constant_texture(Color(0.5f, texel.x, texel.z)), 1.f);
    EXPECT_NEAR(dot(g.ns, t0), std::sin(t), 1e-3) << deg;
    SurfaceInteraction sc = si;
    apply_normal_map(&sc, *make_constant_texture(texel), 0.5f);
    EXPECT_NEAR(std::acos(std::min(1.0, double(dot(sc.ns, si.ns)))), std::atan(0.5 * std::tan(t)), 1e-3) << deg;
  }
  // A texel pointing below the geometric surface is clamped into the hemisphere of ng.
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  apply_normal_map(&si, *make_constant_texture(Color(1.f, 0.5f, 0.f)), 1.f);
  EXPECT_GT(dot(si.ns, si.ng), 0.f);
  EXPECT_NEAR(length(si.ns), 1.f, 1e-5f);
}

namespace {
/// Height h(u, v) = k u (a ramp).
class RampTexture final : public Texture {
 public:
  explicit RampTexture(float k) : m_k(k) {}
  Color eval(const Vec2f& uv, float) const override { return Color(m_k * uv.x); }
  Color average() const override { return Color(0.5f * m_k); }

 private:
  float m_k;
};
}  // namespace

TEST(principled, bump_map_ramp_tilts_away_from_the_slope) {
  // h = 0.5 u with bump_scale 2: slope 1 along u, so ns tilts 45 degrees towards -dpdu.
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  si.dpdu = Vec3f(1, 0, 0);
  SurfaceInteraction b = si;
  apply_bump_map(&b, RampTexture(0.5f), 2.f);
  EXPECT_NEAR(b.ns.x, -std::sqrt(0.5f), 1e-4f);
  EXPECT_NEAR(b.ns.y, 0.f, 1e-5f);
  EXPECT_NEAR(b.ns.z, std::sqrt(0.5f), 1e-4f);
  // A constant height leaves the frame unchanged.
  SurfaceInteraction c = si;
  apply_bump_map(&c, *make_constant_texture(Color(0.7f)), 5.f);
  EXPECT_LT(length(c.ns - si.ns), 1e-6f);
}

TEST(principled, normal_map_changes_the_bsdf_frame) {
  // A material whose normal map tilts ns by 30 degrees reflects like the plain material
  // evaluated with that tilted shading normal.
  double t = 30.0 * k_pi_d / 180.0;
  auto ctx = constant_textures({Color(float(0.5 + 0.5 * std::sin(t)), 0.5f, float(0.5 + 0.5 * std::cos(t)))});
  auto mapped = make({{"base_color", 0.5}, {"roughness", 0.3}, {"normal_map", TextureRef{0}}}, ctx);
  auto plain = make({{"base_color", 0.5}, {"roughness", 0.3}});
  SurfaceInteraction si = make_si({0, 0, 1}, {0, 0, 1});
  si.dpdu = Vec3f(1, 0, 0);
  SurfaceInteraction tilted = si;
  tilted.ns = Vec3f(float(std::sin(t)), 0.f, float(std::cos(t)));
  tilted.dpdu = Vec3f(float(std::cos(t)), 0.f, float(-std::sin(t)));
  Pcg32 rng(310);
  for (int i = 0; i < 200; ++i) {
    Vec3f wo = to_f(direction_at_cos({0, 0, 1}, 0.2 + 0.8 * rng.next_float(), rng));
    Vec3f wi = to_f(direction_at_cos({0, 0, 1}, 0.2 + 0.8 * rng.next_float(), rng));
    Color a = mapped->eval(si, wo, wi), b = plain->eval(tilted, wo, wi);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 1e-4 * b[k] + 1e-7);
  }
}
