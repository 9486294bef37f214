// Medium "ground_fog": patchy fog hugging the ground -- density = height profile x noise mask:
// exp(-(y - base) / scale_height) above `base` (1 below it), times a coverage mask of 3D fBm noise
// (fog banks feature_size wide and feature_height tall; `coverage` about the share of the ground
// under fog, `contrast` how sharp their edges are), drifted by `wind`. Extinction at density 1 (on
// the ground inside a bank) from the visibility there. Confined to a box: extent around the origin
// horizontally, base - scale_height .. top vertically.
//
// Tracked against a majorant grid (medium/tracking.h); the cells' bounds come from interval bounds
// of the noise (fbm_range, core/noise.h) and the profile's monotonicity, so they are conservative
// (tests/cpp/test_ground_fog.cpp samples them).
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/noise.h"
#include "core/plugin.h"
#include "medium/noise_mask.h"
#include "medium/tracking.h"

namespace sg {

namespace {

class GroundFog final : public TrackedMedium {
 public:
  struct Shape {
    float base, scale_height, top, extent, feature_size, feature_height;
    Vec3f wind;
  };
  GroundFog(float sigma, const Color& albedo, float g, const Shape& shape, const FractalParams& fp, float coverage,
            float contrast, uint64_t seed, const Vec3f& cells)
      : TrackedMedium(sigma, albedo, g, quadrature_step_for(shape, fp)),
        m_shape(shape),
        m_noise(seed),
        m_fractal(fp),
        m_mask(m_fractal, coverage, contrast) {
    m_inv_scale = Vec3f(1.f / shape.feature_size, 1.f / shape.feature_height, 1.f / shape.feature_size);
    Box3 box{Vec3f(-shape.extent, shape.base - shape.scale_height, -shape.extent),
             Vec3f(shape.extent, shape.top, shape.extent)};
    m_grid.build(box, int(cells.x), int(cells.y), int(cells.z),
                 [this](const Vec3f& lo, const Vec3f& hi) { return bounds(lo, hi); });
  }

  float density(const Vec3f& p) const override {
    return profile(p.y) * m_mask(fbm(m_noise, NoiseKind::Perlin, noise_point(p), m_fractal));
  }

 private:
  static float quadrature_step_for(const Shape& s, const FractalParams& fp) {
    // A quarter of the finest octave's lattice spacing (vertically, the smallest).
    const float finest = std::min(s.feature_height, s.feature_size) / std::pow(fp.lacunarity, float(fp.octaves - 1));
    return std::max(0.25f * finest, 0.02f);
  }
  Vec3f noise_point(const Vec3f& p) const {
    const Vec3f q = p - m_shape.wind;
    return Vec3f(q.x * m_inv_scale.x, q.y * m_inv_scale.y, q.z * m_inv_scale.z);
  }
  float profile(float y) const {
    return y <= m_shape.base ? 1.f : std::exp(-(y - m_shape.base) / m_shape.scale_height);
  }
  DensityBounds bounds(const Vec3f& lo, const Vec3f& hi) const {
    float n_lo = 0.f, n_hi = 0.f;
    if (!m_mask.full) fbm_range(m_noise, noise_point(lo), noise_point(hi), m_fractal, &n_lo, &n_hi);
    // NOTE: margins for rounding: the noise's float evaluation may stray ~1e-6 past its interval
    // bound, and the profile's exp by an ulp; a majorant a hair too large costs nothing, one too
    // small would bias.
    const float m_hi = m_mask(n_hi + 1e-4f), m_lo = m_mask(n_lo - 1e-4f);
    DensityBounds b;
    b.mx = m_hi > 0.f ? profile(lo.y) * m_hi * (1.f + 1e-4f) : 0.f;
    b.mn = profile(hi.y) * m_lo * (1.f - 1e-4f);
    return b;
  }

  Shape m_shape;
  NoiseBasis m_noise;
  Fractal m_fractal;
  CoverageMask m_mask;
  Vec3f m_inv_scale{1.f};
};

PluginInfo info() {
  return PluginInfo("medium", "ground_fog",
                    "Patchy ground fog: density = exp(-(y - base) / scale_height) (1 below base) times a "
                    "coverage mask of 3D fBm noise (fog banks feature_size wide, feature_height tall), "
                    "extinction at density 1 from the visibility inside a bank on the ground; within extent "
                    "metres of the origin horizontally and below top. Tracked against a majorant grid (delta / "
                    "ratio tracking): unbiased.")
      .add(tracked_medium_params("density 1 (inside a fog bank on the ground)", 0.95, 0.75))
      .exactly_one_of({"visibility", "extinction"})
      .add(param::real("base", 0.0, "height of the ground in metres: the profile is 1 at and below it"))
      .add(param::real("scale_height", 10.0, "height in metres over which the density falls by e (fog about "
                                             "2-30 m deep)")
               .above(0))
      .add(param::real("top", "height in metres of the fog's top (clear air above)")
               .default_is("base + 7 scale_height (density 0.001)"))
      .add(param::real("coverage", 0.6, "about the share of space under fog banks: 1 fog everywhere (then only "
                                        "the height profile varies), small: scattered patches")
               .above(0)
               .at_most(1))
      .add(param::real("contrast", 1.5, "sharpness of the banks' edges: the mask rises over 2 / contrast "
                                        "standard deviations of the noise")
               .above(0)
               .at_most(100))
      .add(param::real("feature_size", 60.0, "horizontal size in metres of the fog banks (the noise's "
                                             "coarsest lattice spacing)")
               .above(0))
      .add(param::real("feature_height", 12.0, "vertical size in metres of the banks' noise").above(0))
      .add(param::integer("octaves", 5, "octaves of the fBm noise (detail down to feature_size / 2^(octaves-1))")
               .in(1, 10))
      .add(param::integer("seed", 0, "seed of the noise (another seed, other banks)").at_least(0))
      .add(param::vec3("wind", Vec3f(0.f), "offset in metres of the noise field: the banks drift with it "
                                           "(wind velocity x time)"))
      .add(param::real("extent", 1000.0, "half-width in metres of the fogged square around the origin (x and z)")
               .above(0))
      .add(param::vec3("majorant_cells", Vec3f(64.f, 16.f, 64.f), "cells of the majorant grid along x, y, z "
                                                                  "(whole numbers)")
               .in(1, 512));
}

std::shared_ptr<Medium> create(const Params& params, const PluginContext&) {
  GroundFog::Shape s;
  s.base = params.get_float("base");
  s.scale_height = params.get_float("scale_height");
  s.top = params.has("top") ? params.get_float("top") : s.base + 7.f * s.scale_height;
  s.extent = params.get_float("extent");
  s.feature_size = params.get_float("feature_size");
  s.feature_height = params.get_float("feature_height");
  s.wind = params.get_vec3("wind");
  if (!(s.top > s.base))
    throw Error("medium 'ground_fog': top (" + std::to_string(s.top) + ") must be above base (" +
                std::to_string(s.base) + ")");
  const Vec3f cells = params.get_vec3("majorant_cells");
  for (int a = 0; a < 3; ++a)
    if (cells[a] != std::floor(cells[a]))
      throw Error("medium 'ground_fog': majorant_cells must be whole numbers, got " + std::to_string(cells[a]));
  FractalParams fp;
  fp.octaves = int(params.get_int("octaves"));
  return std::make_shared<GroundFog>(extinction_from(params), params.get_color("albedo"), params.get_float("g"), s,
                                     fp, params.get_float("coverage"), params.get_float("contrast"),
                                     uint64_t(params.get_int("seed")), cells);
}

}  // namespace

SG_REGISTER_PLUGIN(Medium, info(), create)

}  // namespace sg
