// Texture "cellular": Worley (cellular) noise through a texture-coordinate mapping and a
// colour ramp: F1, F2, F2 - F1 (crack-like ridges), the exact distance to the nearest cell
// edge, or a random value per cell (cobbles, flakes, scratched patches).
//
// Parameters (defaults): output "f1" | "f2" | "f2_minus_f1" | "edge" | "cell" ("f1");
// jitter 1 (0 = regular grid); seed 0; mapping, scale, offset as "noise" (mapping "object");
// remap [lo, hi] -> [0, 1] (default [0, 1]), smooth, invert, ramp_positions / ramp_colors;
// band_limit true: where the footprint covers a cell or more, the value fades to its mean.
#include "texture/procedural.h"

namespace sg {

namespace {

class CellularTexture final : public PointTexture {
 public:
  enum class Output { F1, F2, F2MinusF1, Edge, Cell };

  CellularTexture(Output output, float jitter, uint64_t seed, ProceduralMapping mapping, ProceduralShaping shaping,
                  bool band_limit)
      : m_output(output), m_jitter(jitter), m_basis(seed), m_mapping(mapping), m_shaping(std::move(shaping)),
        m_band_limit(band_limit) {
    m_mean = estimate_average([&](const Vec3f& p) { return Color(raw(p)); }).x;
    m_average = estimate_average([&](const Vec3f& p) { return m_shaping.color(raw(p)); });
  }

  float raw(const Vec3f& p) const {
    CellularResult r = cellular(m_basis, p, m_jitter, m_output == Output::Edge);
    switch (m_output) {
      case Output::F2: return r.f2;
      case Output::F2MinusF1: return r.f2 - r.f1;
      case Output::Edge: return r.edge;
      case Output::Cell: return float(r.cell_hash >> 8) * 0x1p-24f;
      case Output::F1:
      default: return r.f1;
    }
  }

  bool needs_position() const override { return m_mapping.needs_position(); }
  bool needs_uv_footprint() const override { return !m_mapping.needs_position(); }
  Color eval_point(const TexturePoint& q) const override {
    float w;
    Vec3f p = m_mapping.point(q, &w);
    // Detail of the shaped pattern: the remap interval (in cell units for distances), one
    // cell for per-cell values. Footprints well below it need no filtering.
    float detail = m_output == Output::Cell ? 1.f : std::fabs(m_shaping.hi - m_shaping.lo);
    if (!m_band_limit || w < 0.25f * detail) return m_shaping.color(raw(p));
    // NOTE: cellular patterns have detail finer than the cells (thin edges, F2 - F1 ridges)
    // and no octave structure to clamp. The distance outputs change at most at unit rate
    // (F1, edge) or twice that (F2 - F1) across space, so the shaping is box-filtered in
    // closed form over the range the value sweeps within the footprint (shape_box; for the
    // per-cell value, which is piecewise constant, the same widening softens cell borders).
    // Beyond one cell per footprint the result fades to the shaped mean (the average).
    float a = 1.f - smoothstep(0.5f, 1.f, w);
    if (a <= 0.f) return m_average;
    float rate = m_output == Output::F2MinusF1 ? 2.f : 1.f;
    return m_shaping.color_box(raw(p), rate * w) * a + m_average * (1.f - a);
  }
  Color average() const override { return m_average; }

 private:
  Output m_output;
  float m_jitter;
  NoiseBasis m_basis;
  ProceduralMapping m_mapping;
  ProceduralShaping m_shaping;
  bool m_band_limit;
  float m_mean;
  Color m_average;
};

}  // namespace

namespace {

PluginInfo info() {
  PluginInfo i("texture", "cellular",
               "Worley (cellular) noise: F1, F2, F2 - F1 (crack-like ridges), the exact distance to the nearest "
               "cell edge, or a random value per cell, through a mapping and a colour ramp.");
  i.add(param::choice("output", "f1", {"f1", "f2", "f2_minus_f1", "edge", "cell"}, "what the texture returns"))
      .add(param::real("jitter", 1.0, "feature point jitter (0: a regular grid)").in(0, 1))
      .add(param::integer("seed", 0, "pattern seed").at_least(0))
      .add(ProceduralMapping::params("object"));
  ProceduralShaping::declare(i, Vec2f(0.f, 1.f));
  i.add(param::boolean("band_limit", true, "where the footprint covers a cell or more, fade to the mean"));
  return i;
}

std::shared_ptr<Texture> create(const Params& params, const PluginContext&) {
  std::string o = params.get_string("output");
  CellularTexture::Output out = o == "f2"            ? CellularTexture::Output::F2
                                : o == "f2_minus_f1" ? CellularTexture::Output::F2MinusF1
                                : o == "edge"        ? CellularTexture::Output::Edge
                                : o == "cell"        ? CellularTexture::Output::Cell
                                                     : CellularTexture::Output::F1;
  float jitter = params.get_float("jitter");
  int64_t seed = params.get_int("seed");
  ProceduralMapping mapping = ProceduralMapping::from_params(params);
  ProceduralShaping shaping = ProceduralShaping::from_params(params, Vec2f(0.f, 1.f));
  bool band_limit = params.get_bool("band_limit");
  return std::make_shared<CellularTexture>(out, jitter, uint64_t(seed), mapping, std::move(shaping), band_limit);
}

}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
