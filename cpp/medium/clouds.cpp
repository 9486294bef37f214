// Medium "clouds": a deck of low clouds (cumulus, stratocumulus) between two heights. The density is
// a sharp coverage mask of 3D fBm noise whose threshold rises with height: flat-ish bases where the
// layer starts (condensation level), billows that thin out into rounded tops, gaps of clear sky by
// `coverage`. Extinction at density 1 (the cloud's inside) from the visibility there: tens of metres
// in real clouds. Confined to the layer and extent metres of the origin horizontally.
//
// Tracked against a majorant grid (medium/tracking.h) with conservative cell bounds from interval
// bounds of the noise (fbm_range) and of the vertical envelope.
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/noise.h"
#include "core/plugin.h"
#include "medium/noise_field.h"
#include "medium/tracking.h"

namespace sg {

namespace {

class CloudDeck final : public TrackedMedium {
 public:
  struct Shape {
    float bottom, top, extent, base_sharpness;
  };
  CloudDeck(float sigma, const Color& albedo, float g, const Shape& shape, const NoiseField& field, float coverage,
            float contrast, const int cells[3])
      : TrackedMedium(sigma, albedo, g, field.quadrature_step(0.05f)),
        m_shape(shape),
        m_field(field),
        m_mask(m_field.fractal(), coverage, contrast) {
    // The erosion at the top: the threshold rises by this many noise deviations.
    m_erosion = 2.5f * m_mask.sigma_f;
    Box3 box{Vec3f(-shape.extent, shape.bottom, -shape.extent), Vec3f(shape.extent, shape.top, shape.extent)};
    m_grid.build(box, cells[0], cells[1], cells[2], [this](const Vec3f& lo, const Vec3f& hi) { return bounds(lo, hi); });
  }

  float density(const Vec3f& p) const override {
    const float h = (p.y - m_shape.bottom) / (m_shape.top - m_shape.bottom);
    return base(h) * m_mask(m_field(p) - m_erosion * rise(h));
  }

 private:
  /// The base: the density rises over the lowest 1 / base_sharpness of the layer (increasing in h).
  float base(float h) const { return smoothstep(0.f, 1.f / m_shape.base_sharpness, h); }
  /// The threshold's rise with height (increasing in h): none in the lower third, the full erosion
  /// at the top, so billows narrow into rounded tops.
  static float rise(float h) { return smoothstep(0.3f, 1.f, h); }
  DensityBounds bounds(const Vec3f& lo, const Vec3f& hi) const {
    float n_lo, n_hi;
    m_field.range(lo, hi, &n_lo, &n_hi);
    const float h0 = (lo.y - m_shape.bottom) / (m_shape.top - m_shape.bottom);
    const float h1 = (hi.y - m_shape.bottom) / (m_shape.top - m_shape.bottom);
    // NOTE: density = base(h) x mask(n - e rise(h)), base and rise increasing in h, mask
    // increasing: its largest value over the cell is at most base(h1) mask(n_hi - e rise(h0)), its
    // smallest at least base(h0) mask(n_lo - e rise(h1)); margins for rounding as in ground_fog.
    const float m_hi = m_mask(n_hi + 1e-4f - m_erosion * rise(h0) + 1e-5f);
    const float m_lo = m_mask(n_lo - 1e-4f - m_erosion * rise(h1) - 1e-5f);
    DensityBounds b;
    b.mx = m_hi > 0.f ? std::min(1.f, base(std::min(1.f, h1 + 1e-5f)) * 1.0001f) * m_hi * (1.f + 1e-4f) : 0.f;
    b.mn = base(std::max(0.f, h0 - 1e-5f)) * m_lo * (1.f - 1e-4f);
    return b;
  }

  Shape m_shape;
  NoiseField m_field;
  CoverageMask m_mask;
  float m_erosion = 0.f;
};

PluginInfo info() {
  return PluginInfo("medium", "clouds",
                    "A deck of low clouds between bottom and top (metres): a sharp coverage mask of 3D fBm noise "
                    "(billows feature_size wide) whose threshold rises with height -- flat-ish bases, rounded "
                    "tops, clear gaps by coverage; extinction at density 1 from the visibility inside a cloud; "
                    "within extent metres of the origin horizontally. Tracked against a majorant grid (delta / "
                    "ratio tracking): unbiased.")
      .add(tracked_medium_params("density 1 (inside a cloud; real clouds 20-100 m)", 0.99, 0.8))
      .exactly_one_of({"visibility", "extinction"})
      .add(param::real("bottom", 600.0, "height in metres of the cloud base"))
      .add(param::real("top", 1100.0, "height in metres of the highest tops"))
      .add(param::real("coverage", 0.5, "about the share of the sky covered (0: none, 1: overcast)")
               .above(0)
               .at_most(1))
      .add(param::real("contrast", 4.0, "sharpness of the clouds' edges: the mask rises over 2 / contrast "
                                        "standard deviations of the noise")
               .above(0)
               .at_most(100))
      .add(param::real("base_sharpness", 12.0, "the density rises over the lowest 1 / base_sharpness of the "
                                               "layer: larger, flatter and sharper bases")
               .at_least(1))
      .add(noise_field_params("billows", 500.0, 350.0, 6, 5000.0));
}

std::shared_ptr<Medium> create(const Params& params, const PluginContext&) {
  CloudDeck::Shape s;
  s.bottom = params.get_float("bottom");
  s.top = params.get_float("top");
  s.extent = params.get_float("extent");
  s.base_sharpness = params.get_float("base_sharpness");
  if (!(s.top > s.bottom))
    throw Error("medium 'clouds': top (" + std::to_string(s.top) + ") must be above bottom (" +
                std::to_string(s.bottom) + ")");
  int cells[3];
  whole_numbers(params, "majorant_cells", "clouds", cells);
  return std::make_shared<CloudDeck>(extinction_from(params), params.get_color("albedo"), params.get_float("g"), s,
                                     NoiseField(params), params.get_float("coverage"), params.get_float("contrast"),
                                     cells);
}

}  // namespace

SG_REGISTER_PLUGIN(Medium, info(), create)

}  // namespace sg
