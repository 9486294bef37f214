// Texture "noise": Perlin or value noise, plain, as a fractal sum (fBm) or as turbulence,
// band-limited by the ray footprint, through a texture-coordinate mapping and a colour ramp.
//
// Parameters (defaults): pattern "fbm" | "turbulence" | "plain"; basis "perlin" | "value";
// octaves 5, lacunarity 2, H 1 (octave weights lacunarity^-H i, the seed's eqs. (4-5)-(4-7)),
// normalize true; seed 0; mapping "object" | "uv" | "world" | "relative", scale (number or
// 3 numbers) 1, offset 0; remap [lo, hi] (default [-1, 1] for fbm/plain, [0, 1] for
// turbulence) -> [0, 1], smooth false, invert false; ramp_positions / ramp_colors (a colour
// map; grey without); band_limit true.
#include "texture/procedural.h"

namespace sg {

namespace {

class NoiseTexture final : public PointTexture {
 public:
  enum class Pattern { Plain, Fbm, Turbulence };

  NoiseTexture(Pattern pattern, NoiseKind basis, FractalParams fractal, uint64_t seed, ProceduralMapping mapping,
               ProceduralShaping shaping, bool band_limit)
      : m_pattern(pattern), m_basis_kind(basis), m_fractal(fractal), m_basis(seed), m_mapping(mapping),
        m_shaping(std::move(shaping)), m_band_limit(band_limit) {
    m_average = estimate_average([&](const Vec3f& p) { return m_shaping.color(value(p, 0.f)); });
  }

  /// The scalar before shaping at mapped point p with footprint w (mapped units).
  float value(const Vec3f& p, float w) const {
    if (!m_band_limit) w = 0.f;
    switch (m_pattern) {
      case Pattern::Plain: {
        float a = octave_fade(1.f, w);
        float n = (m_mapping.kind == ProceduralMapping::Kind::UV && m_basis_kind == NoiseKind::Perlin)
                      ? m_basis.perlin2(p.x, p.y)
                      : (m_basis_kind == NoiseKind::Perlin ? m_basis.perlin(p) : m_basis.value(p));
        return a * n;
      }
      case Pattern::Turbulence:
        return turbulence(m_basis, m_basis_kind, p, m_fractal, w);
      case Pattern::Fbm:
      default:
        return fbm(m_basis, m_basis_kind, p, m_fractal, w);
    }
  }

  bool needs_position() const override { return m_mapping.needs_position(); }
  bool needs_uv_footprint() const override { return !m_mapping.needs_position(); }
  bool eval_gradient(const TexturePoint& q, Vec3f* grad, bool* world_space) const override {
    if (m_basis_kind != NoiseKind::Perlin || m_pattern == Pattern::Plain || !m_shaping.ramp.empty()) return false;
    Vec3f diag;
    if (!m_mapping.jacobian(q, &diag, world_space)) return false;
    float w;
    Vec3f p = m_mapping.point(q, &w);
    if (!m_band_limit) w = 0.f;
    Vec3f g;
    float v = m_pattern == Pattern::Fbm ? fbm_grad(m_basis, p, m_fractal, w, &g)
                                        : turbulence_grad(m_basis, p, m_fractal, w, &g);
    *grad = g * diag * m_shaping.shape_derivative(v);
    return true;
  }
  Color eval_point(const TexturePoint& q) const override {
    float w;
    Vec3f p = m_mapping.point(q, &w);
    return m_shaping.color(value(p, w));
  }
  Color average() const override { return m_average; }

 private:
  Pattern m_pattern;
  NoiseKind m_basis_kind;
  Fractal m_fractal;
  NoiseBasis m_basis;
  ProceduralMapping m_mapping;
  ProceduralShaping m_shaping;
  bool m_band_limit;
  Color m_average;
};

}  // namespace

namespace {

PluginInfo info() {
  PluginInfo i("texture", "noise",
               "Perlin or value noise, plain, as a fractal sum (fBm) or as turbulence, band-limited by the ray "
               "footprint, through a texture-coordinate mapping and a colour ramp.");
  i.add(param::choice("pattern", "fbm", {"fbm", "turbulence", "plain"}, "fractal sum, sum of |noise|, or one octave"))
      .add(param::choice("basis", "perlin", {"perlin", "value"}, "gradient (Perlin) or value noise"))
      .add(param::integer("octaves", 5, "fractal octaves").in(1, 16))
      .add(param::real("lacunarity", 2.0, "frequency ratio of successive octaves").above(1).at_most(16))
      .add(param::real("H", 1.0, "octave weights lacunarity^(-H i)").in(0, 4))
      .add(param::boolean("normalize", true, "divide the fractal sum by the sum of its weights"))
      .add(param::integer("seed", 0, "pattern seed").at_least(0))
      .add(ProceduralMapping::params("object"));
  ProceduralShaping::declare(i, std::nullopt, "[-1, 1] for fbm and plain, [0, 1] for turbulence");
  i.add(param::boolean("band_limit", true, "fade octaves finer than the ray footprint to their mean"));
  return i;
}

std::shared_ptr<Texture> create(const Params& params, const PluginContext&) {
  std::string pat = params.get_string("pattern");
  NoiseTexture::Pattern pattern = pat == "turbulence" ? NoiseTexture::Pattern::Turbulence
                                  : pat == "plain"    ? NoiseTexture::Pattern::Plain
                                                      : NoiseTexture::Pattern::Fbm;
  std::string b = params.get_string("basis");
  FractalParams f;
  f.octaves = int(params.get_int("octaves"));
  f.lacunarity = params.get_float("lacunarity");
  f.H = params.get_float("H");
  f.normalize = params.get_bool("normalize");
  int64_t seed = params.get_int("seed");
  ProceduralMapping mapping = ProceduralMapping::from_params(params);
  Vec2f range = pattern == NoiseTexture::Pattern::Turbulence ? Vec2f(0.f, 1.f) : Vec2f(-1.f, 1.f);
  ProceduralShaping shaping = ProceduralShaping::from_params(params, range);
  bool band_limit = params.get_bool("band_limit");
  return std::make_shared<NoiseTexture>(pattern, b == "perlin" ? NoiseKind::Perlin : NoiseKind::Value, f,
                                        uint64_t(seed), mapping, std::move(shaping), band_limit);
}

}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
