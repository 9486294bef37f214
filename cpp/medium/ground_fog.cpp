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
#include "medium/noise_field.h"
#include "medium/tracking.h"

namespace sg {

namespace {

class GroundFog final : public TrackedMedium {
 public:
  struct Shape {
    float base, scale_height, top, extent;
  };
  GroundFog(float sigma, const Color& albedo, float g, const Shape& shape, const NoiseField& field, float coverage,
            float contrast, const int cells[3])
      : TrackedMedium(sigma, albedo, g, field.quadrature_step(0.02f)),
        m_shape(shape),
        m_field(field),
        m_mask(m_field.fractal(), coverage, contrast) {
    Box3 box{Vec3f(-shape.extent, shape.base - shape.scale_height, -shape.extent),
             Vec3f(shape.extent, shape.top, shape.extent)};
    m_grid.build(box, cells[0], cells[1], cells[2], [this](const Vec3f& lo, const Vec3f& hi) { return bounds(lo, hi); });
  }

  float density(const Vec3f& p) const override { return profile(p.y) * m_mask(m_field(p)); }

 private:
  float profile(float y) const {
    return y <= m_shape.base ? 1.f : std::exp(-(y - m_shape.base) / m_shape.scale_height);
  }
  DensityBounds bounds(const Vec3f& lo, const Vec3f& hi) const {
    float n_lo = 0.f, n_hi = 0.f;
    if (!m_mask.full) m_field.range(lo, hi, &n_lo, &n_hi);
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
  NoiseField m_field;
  CoverageMask m_mask;
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
      .add(noise_field_params("fog banks", 60.0, 12.0, 5, 1000.0));
}

std::shared_ptr<Medium> create(const Params& params, const PluginContext&) {
  GroundFog::Shape s;
  s.base = params.get_float("base");
  s.scale_height = params.get_float("scale_height");
  s.top = params.has("top") ? params.get_float("top") : s.base + 7.f * s.scale_height;
  s.extent = params.get_float("extent");
  if (!(s.top > s.base))
    throw Error("medium 'ground_fog': top (" + std::to_string(s.top) + ") must be above base (" +
                std::to_string(s.base) + ")");
  int cells[3];
  whole_numbers(params, "majorant_cells", "ground_fog", cells);
  return std::make_shared<GroundFog>(extinction_from(params), params.get_color("albedo"), params.get_float("g"), s,
                                     NoiseField(params), params.get_float("coverage"), params.get_float("contrast"),
                                     cells);
}

}  // namespace

SG_REGISTER_PLUGIN(Medium, info(), create)

}  // namespace sg
