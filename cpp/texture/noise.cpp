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
#include "texture/texture_registry.h"

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

std::shared_ptr<Texture> create_noise_texture(const ParamSet& params) {
  std::string pat = params.get_string("pattern", "fbm");
  NoiseTexture::Pattern pattern;
  if (pat == "fbm") pattern = NoiseTexture::Pattern::Fbm;
  else if (pat == "turbulence") pattern = NoiseTexture::Pattern::Turbulence;
  else if (pat == "plain") pattern = NoiseTexture::Pattern::Plain;
  else {
    std::string g = closest_match(pat, {"fbm", "turbulence", "plain"});
    throw Error("parameter 'pattern': unknown pattern '" + pat + "'" + (g.empty() ? "" : " (did you mean '" + g + "'?)") +
                "; allowed: fbm, turbulence, plain");
  }
  std::string b = params.get_string("basis", "perlin");
  if (b != "perlin" && b != "value") throw Error("parameter 'basis': must be perlin or value, got '" + b + "'");
  FractalParams f;
  f.octaves = int(params.get_int("octaves", 5));
  f.lacunarity = params.get_float("lacunarity", 2.f);
  f.H = params.get_float("H", 1.f);
  f.normalize = params.get_bool("normalize", true);
  if (f.octaves < 1 || f.octaves > 16) throw Error("parameter 'octaves': must lie in [1, 16]");
  if (!(f.lacunarity > 1.f && f.lacunarity <= 16.f)) throw Error("parameter 'lacunarity': must lie in (1, 16]");
  if (!(f.H >= 0.f && f.H <= 4.f)) throw Error("parameter 'H': must lie in [0, 4]");
  int64_t seed = params.get_int("seed", 0);
  ProceduralMapping mapping = ProceduralMapping::from_params(params);
  Vec2f range = pattern == NoiseTexture::Pattern::Turbulence ? Vec2f(0.f, 1.f) : Vec2f(-1.f, 1.f);
  ProceduralShaping shaping = ProceduralShaping::from_params(params, range);
  bool band_limit = params.get_bool("band_limit", true);
  return std::make_shared<NoiseTexture>(pattern, b == "perlin" ? NoiseKind::Perlin : NoiseKind::Value, f,
                                        uint64_t(seed), mapping, std::move(shaping), band_limit);
}

}  // namespace sg
