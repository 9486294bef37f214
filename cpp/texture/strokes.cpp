// Texture "strokes": scratch strokes scattered in 3D, as wear leaves them on paint: straight
// strokes of random length and depth along a preferred direction (with an angular spread) or
// in every direction, or swirl marks -- circular arcs around random centres in the surface's
// tangent plane, as polishing leaves them. The value is the stroke's profile (1 on its centre
// line, falling linearly to 0 at half its width), its width tapering to the stroke's ends,
// times a random depth per stroke; the largest of the strokes that reach the point.
//
// Parameters (defaults): mode "straight" | "swirl" ("straight"); density 2 (strokes per cell,
// 1..8); length [0.3, 1] (cells, log-uniform; at most 2); width 0.03 (cells); direction
// [0, 0, 0] (a unit axis in the mapped space; zero: every direction); spread 15 (degrees
// around direction); radius [0.2, 0.6] and arc [40, 140] (swirls: radius in cells, arc in
// degrees); seed 0; mapping, scale, offset as "noise" (mapping "object"); remap, smooth,
// invert, ramp as every procedural texture; band_limit true: a footprint wider than a stroke
// widens it and lowers it in proportion (its area is kept), so far-away scratches fade to a
// faint sheen instead of aliasing, and from half a cell to a whole one the value blends into
// the pattern's mean (the pixel integral of many cells' strokes).
#include "texture/procedural.h"

#include "core/rng.h"

namespace sg {

namespace {

/// A uniform float in [0, 1) from a stream (seed, counter).
inline float unit_float(uint64_t seed, uint64_t k) {
  return float(mix64(seed ^ (0x9E3779B97F4A7C15ull * (k + 1))) >> 40) * 0x1p-24f;
}

class StrokesTexture final : public PointTexture {
 public:
  struct Config {
    bool swirl = false;
    int density = 2;
    Vec2f length{0.3f, 1.f};
    float width = 0.03f;
    Vec3f direction{0.f, 0.f, 0.f};
    float spread_deg = 15.f;
    Vec2f radius{0.2f, 0.6f};
    Vec2f arc_deg{40.f, 140.f};
    uint64_t seed = 0;
    bool band_limit = true;
  };

  StrokesTexture(const Config& c, ProceduralMapping mapping, ProceduralShaping shaping)
      : m_c(c), m_mapping(mapping), m_shaping(std::move(shaping)) {
    m_directed = dot(c.direction, c.direction) > 0.f;
    if (m_directed) {
      m_a = normalize(c.direction);
      m_b = std::fabs(m_a.x) < 0.9f ? normalize(cross(m_a, Vec3f(1.f, 0.f, 0.f)))
                                    : normalize(cross(m_a, Vec3f(0.f, 1.f, 0.f)));
      m_cc = cross(m_a, m_b);
      m_cos_max = std::cos(c.spread_deg * 0.017453293f);
    }
    // NOTE: the mean is the shaded value at footprints of a cell or more (eval_point): 8192
    // quasi-random points (with 512 it was 0.0488 where 20000 points of a plane measured
    // 0.0558; 8192 took 8.1 ms at density 2, 15.8 ms at 4, 27.6 ms at 8).
    m_average = estimate_average([&](const Vec3f& p) { return m_shaping.color(raw(p, Vec3f(0.f, 0.f, 1.f), 0.f)); },
                                 8192);
  }

  /// The stroke value at mapped point p (n: the surface normal in the mapped space, for swirls;
  /// w: the footprint in mapped units).
  float raw(const Vec3f& p, const Vec3f& n, float w) const {
    int cx = int(std::floor(p.x)), cy = int(std::floor(p.y)), cz = int(std::floor(p.z));
    float best = 0.f;
    float hw0 = 0.5f * m_c.width;
    float hw_f = m_c.band_limit ? std::max(hw0, 0.5f * w) : hw0;
    float gain = hw0 / hw_f;  // NOTE: a widened stroke keeps its area (width x depth)
    // Swirls: angles in the tangent plane, in a frame fixed by the axes projected on it.
    Vec3f e1 = std::fabs(n.x) < 0.9f ? normalize(cross(n, Vec3f(1.f, 0.f, 0.f)))
                                     : normalize(cross(n, Vec3f(0.f, 1.f, 0.f)));
    Vec3f e2 = cross(n, e1);
    // NOTE: a stroke reaches the point only if its centre lies within reach in the tangent plane:
    // half its longest length (straight) or its largest radius (swirl), plus the half-width
    // (the triangle inequality on the tests below). Testing that first skips a stroke's
    // direction, length and arc -- most of its cost -- for the many that cannot reach; the
    // small margin keeps the result bit-identical whatever the rounding.
    const float reach = (m_c.swirl ? m_c.radius.y : 0.5f * m_c.length.y) + hw_f;
    const float reach2 = reach * reach * 1.0001f + 1e-6f;
    // So a reaching centre lies within `far` of p on every axis (|v| <= |v_t| + |n| |v.n|, the
    // slab |v.n| <= 1/2): neighbour cells wholly farther are skipped, and a centre is dropped as
    // soon as one coordinate is too far (one hash instead of three).
    const float far = (std::sqrt(reach2) + 0.5f * length(n)) * 1.0001f + 1e-5f;
    const float fx = p.x - float(cx), fy = p.y - float(cy), fz = p.z - float(cz);  // in [0, 1)
    auto skip = [far](int d, float f) { return (d < 0 && f > far) || (d > 0 && 1.f - f > far); };
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (skip(dx, fx) || skip(dy, fy) || skip(dz, fz)) continue;
          uint64_t cell = mix64(m_c.seed * 0xD1B54A32D192ED03ull ^
                                (uint64_t(uint32_t(cx + dx)) | ((uint64_t(uint32_t(cy + dy)) << 21) ^
                                                                 (uint64_t(uint32_t(cz + dz)) << 42))));
          for (int s = 0; s < m_c.density; ++s) {
            uint64_t k = uint64_t(s) * 16;
            Vec3f c;
            c.x = float(cx + dx) + unit_float(cell, k);
            if (std::fabs(p.x - c.x) > far) continue;
            c.y = float(cy + dy) + unit_float(cell, k + 1);
            if (std::fabs(p.y - c.y) > far) continue;
            c.z = float(cz + dz) + unit_float(cell, k + 2);
            Vec3f v = p - c;
            // NOTE: a stroke is drawn on the surface, so distances are taken in the surface's
            // tangent plane at the point (the stroke is a slab half a cell thick along the
            // normal): a 3D capsule this thin would meet a surface only where it happens to
            // pass through it.
            float vn = dot(v, n);
            if (std::fabs(vn) > 0.5f) continue;
            Vec3f vt = v - n * vn;
            if (dot(vt, vt) > reach2) continue;
            float d, t;  // distance to the centre line; position along it in [-1, 1] (ends)
            if (!m_c.swirl) {
              Vec3f dir = stroke_direction(cell, k + 4);
              dir = dir - n * dot(dir, n);
              float dl = length(dir);
              if (dl < 0.2f) continue;  // a stroke along the normal leaves a dot, not a scratch
              dir = dir / dl;
              float u0 = unit_float(cell, k + 8);
              float len = m_c.length.x * std::pow(m_c.length.y / m_c.length.x, u0);
              float h = 0.5f * len;
              float along = dot(vt, dir);
              if (std::fabs(along) > h + hw_f) continue;
              float ac = std::max(-h, std::min(h, along));
              d = length(vt - dir * ac);
              t = ac / h;
            } else {
              // The arc lies in the tangent plane at the point: around the axis n.
              float r = m_c.radius.x + (m_c.radius.y - m_c.radius.x) * unit_float(cell, k + 4);
              float rho = length(vt);
              if (std::fabs(rho - r) > hw_f + 1e-6f) continue;
              d = std::fabs(rho - r);
              float a = std::atan2(dot(vt, e2), dot(vt, e1));  // [-pi, pi]
              float a0 = 6.2831853f * unit_float(cell, k + 5);
              float span = (m_c.arc_deg.x + (m_c.arc_deg.y - m_c.arc_deg.x) * unit_float(cell, k + 6)) *
                           0.017453293f;
              float rel = std::fmod(a - a0 + 12.566371f, 6.2831853f);
              if (rel > span) continue;
              t = 2.f * rel / span - 1.f;
            }
            // Width tapering to the ends (a scratch thins out where the grit lifted off).
            float taper = 1.f - t * t * t * t;
            float hw = hw_f * std::sqrt(std::max(taper, 0.f));
            if (d >= hw) continue;
            const float depth = 0.4f + 0.6f * unit_float(cell, k + 3);
            best = std::max(best, gain * depth * (1.f - d / hw));
          }
        }
    return best;
  }

  bool needs_position() const override { return m_mapping.needs_position(); }
  bool needs_uv_footprint() const override { return !m_mapping.needs_position(); }
  Color eval_point(const TexturePoint& q) const override {
    float w;
    Vec3f p = m_mapping.point(q, &w);
    Vec3f n = q.n_object;
    if (!(dot(n, n) > 0.5f)) n = Vec3f(0.f, 0.f, 1.f);
    // NOTE: a footprint of a cell or more covers the strokes of many cells, and the pixel
    // integral of the pattern is then its mean: with band_limit the value blends into the
    // average from half a cell to a whole one (a smoothstep), like the coarsest levels of a
    // mip-map. Widening every stroke of the 27 neighbouring cells instead (below half a cell)
    // would miss the strokes of farther cells that reach, and cost the most exactly where the
    // result matters least (the wide ray cones of diffuse bounces; bench/wear_overhead.py printed
    // scratches_overhead_pct=141.0 before this).
    const float t = m_c.band_limit ? std::min(1.f, std::max(0.f, 2.f * w - 1.f)) : 0.f;
    if (t >= 1.f) return m_average;
    const Color c = m_shaping.color(raw(p, n, w));
    if (t <= 0.f) return c;
    const float b = t * t * (3.f - 2.f * t);
    return c * (1.f - b) + m_average * b;
  }
  Color average() const override { return m_average; }

 private:
  Vec3f stroke_direction(uint64_t cell, uint64_t k) const {
    float u1 = unit_float(cell, k), u2 = unit_float(cell, k + 1);
    // A direction within `spread` of the preferred one (uniform over that cap), or uniform
    // over the sphere; a stroke and its reverse are one.
    float z = 1.f - u1 * (1.f - m_cos_max);
    float s = std::sqrt(std::max(0.f, 1.f - z * z));
    float phi = 6.2831853f * u2;
    Vec3f local(s * std::cos(phi), s * std::sin(phi), z);
    if (!m_directed) return local;
    return m_b * local.x + m_cc * local.y + m_a * local.z;
  }

  Config m_c;
  // The preferred direction's frame (a, b, cc: cc = a x b) and the cap's cosine, fixed at creation.
  bool m_directed = false;
  Vec3f m_a{0.f, 0.f, 1.f}, m_b{1.f, 0.f, 0.f}, m_cc{0.f, 1.f, 0.f};
  float m_cos_max = -1.f;
  ProceduralMapping m_mapping;
  ProceduralShaping m_shaping;
  Color m_average;
};

PluginInfo info() {
  PluginInfo i("texture", "strokes",
               "Scratch strokes scattered in 3D: straight strokes of random length and depth along a direction (with a "
               "spread) or in every direction, or swirl marks (arcs around random centres in the surface's plane); the "
               "stroke profile, its width tapering to the ends.");
  i.add(param::choice("mode", "straight", {"straight", "swirl"}, "straight strokes or swirl marks (arcs)"))
      .add(param::integer("density", 2, "strokes per cell").in(1, 8))
      .add(param::vec2("length", Vec2f(0.3f, 1.f), "stroke length range, cells (log-uniform; at most 2)"))
      .add(param::real("width", 0.03, "stroke width, cells").in(1e-4, 0.5))
      .add(param::vec3("direction", Vec3f(0.f, 0.f, 0.f), "preferred direction in the mapped space (zero: every "
                                                           "direction)"))
      .add(param::real("spread", 15.0, "angular spread around the direction, degrees").in(0, 90))
      .add(param::vec2("radius", Vec2f(0.2f, 0.6f), "swirl radius range, cells (at most 0.9)"))
      .add(param::vec2("arc", Vec2f(40.f, 140.f), "swirl arc length range, degrees"))
      .add(param::integer("seed", 0, "pattern seed").at_least(0))
      .add(ProceduralMapping::params("object"));
  ProceduralShaping::declare(i, Vec2f(0.f, 1.f));
  i.add(param::boolean("band_limit", true, "a footprint wider than a stroke widens it and lowers it in proportion; "
                                            "one of a cell or more gives the pattern's mean"));
  return i;
}

std::shared_ptr<Texture> create(const Params& params, const PluginContext&) {
  StrokesTexture::Config c;
  c.swirl = params.get_string("mode") == "swirl";
  c.density = int(params.get_int("density"));
  c.length = params.get_vec2("length");
  if (!(c.length.x > 0.f && c.length.x <= c.length.y && c.length.y <= 2.f))
    throw Error("parameter 'length': expected 0 < min <= max <= 2 (cells)");
  c.width = params.get_float("width");
  c.direction = params.get_vec3("direction");
  c.spread_deg = params.get_float("spread");
  c.radius = params.get_vec2("radius");
  if (!(c.radius.x > 0.f && c.radius.x <= c.radius.y && c.radius.y <= 0.9f))
    throw Error("parameter 'radius': expected 0 < min <= max <= 0.9 (cells)");
  c.arc_deg = params.get_vec2("arc");
  if (!(c.arc_deg.x > 0.f && c.arc_deg.x <= c.arc_deg.y && c.arc_deg.y <= 360.f))
    throw Error("parameter 'arc': expected 0 < min <= max <= 360 (degrees)");
  c.seed = uint64_t(params.get_int("seed"));
  c.band_limit = params.get_bool("band_limit");
  return std::make_shared<StrokesTexture>(c, ProceduralMapping::from_params(params),
                                          ProceduralShaping::from_params(params, Vec2f(0.f, 1.f)));
}

}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
