// Internal: what the procedural texture plugins ("noise", "cellular") share:
// texture-coordinate mappings (the seed's mapping U) and output shaping (remap, colour ramp).
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/noise.h"
#include "core/params.h"
#include "core/plugin.h"
#include "texture/texture.h"

namespace sg {

/// Texture coordinates of a procedural texture, and the footprint in those units.
///   uv:       (u, v, 0) * scale + offset
///   object:   object-space position * scale + offset (moves and scales with the object)
///   world:    world-space position * scale + offset
///   relative: relative-local, the object-space position divided by the mesh's bounding-box
///             extent: (p - lo) / (hi - lo) in [0, 1]^3 (the seed's equation (4-9)), so an
///             effect can be confined to e.g. the lower part of any model; * scale + offset.
struct ProceduralMapping {
  enum class Kind { UV, Object, World, Relative } kind = Kind::Object;
  Vec3f scale{1.f}, offset{0.f};
  bool bake = false;  ///< `bake: auto` (texture/baked.h; uv mapping only)

  /// The declared parameters `mapping`, `scale`, `offset`.
  static std::vector<ParamDecl> params(const std::string& default_kind = "object") {
    return {param::choice("mapping", default_kind, {"uv", "object", "world", "relative"},
                          "texture coordinates: uv, object- or world-space position, or relative-local "
                          "(object position / bounding-box extent, in [0, 1])"),
            param::vec3("scale", Vec3f(1.f), "multiplies the coordinates (a number or one per axis)").above(0),
            param::vec3("offset", Vec3f(0.f), "added after scaling"),
            param::choice("bake", "off", {"off", "auto"},
                          "auto: with render.texture_lod, baked per frame into an image at the resolution the camera "
                          "needs (the texture resolution estimate), then looked up instead of evaluated; uv mapping "
                          "only (docs/texture_lod.md)")};
  }

  static ProceduralMapping from_params(const Params& p) {
    ProceduralMapping m;
    std::string k = p.get_string("mapping");
    m.kind = k == "uv" ? Kind::UV : k == "world" ? Kind::World : k == "relative" ? Kind::Relative : Kind::Object;
    m.scale = p.get_vec3("scale");
    m.offset = p.get_vec3("offset");
    m.bake = p.get_string("bake") == "auto";
    if (m.bake && m.kind != Kind::UV)
      throw Error("parameter 'bake': auto needs mapping: uv (a " + k + " mapping has no image to bake into)");
    return m;
  }

  bool needs_position() const { return kind != Kind::UV; }

  /// The object's bounding-box extent per axis, degenerate axes (flat meshes) counted as 1.
  static Vec3f safe_extent(const TexturePoint& q) {
    Vec3f ext = q.object_hi - q.object_lo;
    auto safe = [](float e) { return e > 1e-12f ? e : 1.f; };
    return Vec3f(safe(ext.x), safe(ext.y), safe(ext.z));
  }

  /// d(mapped) / d(position) per axis (diagonal): position = p_object, or p_world for the
  /// world mapping; false for uv (no 3D gradient).
  bool jacobian(const TexturePoint& q, Vec3f* diag, bool* world_space) const {
    switch (kind) {
      case Kind::Object: *diag = scale; *world_space = false; return true;
      case Kind::World: *diag = scale; *world_space = true; return true;
      case Kind::Relative: {
        Vec3f ext = safe_extent(q);
        *diag = Vec3f(scale.x / ext.x, scale.y / ext.y, scale.z / ext.z);
        *world_space = false;
        return true;
      }
      default: return false;
    }
  }

  /// Mapped point without the footprint.
  Vec3f point(const TexturePoint& q) const {
    switch (kind) {
      case Kind::UV: return Vec3f(q.uv.x, q.uv.y, 0.f) * scale + offset;
      case Kind::Object: return q.p_object * scale + offset;
      case Kind::World: return q.p_world * scale + offset;
      case Kind::Relative:
      default: {
        Vec3f ext = safe_extent(q);
        Vec3f r((q.p_object.x - q.object_lo.x) / ext.x, (q.p_object.y - q.object_lo.y) / ext.y,
                (q.p_object.z - q.object_lo.z) / ext.z);
        return r * scale + offset;
      }
    }
  }

  /// Mapped point; `footprint` receives the filter width in mapped units (0 = point sample).
  Vec3f point(const TexturePoint& q, float* footprint) const {
    float smax = std::max(scale.x, std::max(scale.y, scale.z));
    switch (kind) {
      case Kind::UV: {
        float fa = std::sqrt(std::max(q.uv_axis_a.x * q.uv_axis_a.x + q.uv_axis_a.y * q.uv_axis_a.y,
                                      q.uv_axis_b.x * q.uv_axis_b.x + q.uv_axis_b.y * q.uv_axis_b.y));
        *footprint = std::max(q.uv_footprint, fa) * smax;
        break;
      }
      case Kind::Object: *footprint = q.world_footprint * q.object_per_world * smax; break;
      case Kind::World: *footprint = q.world_footprint * smax; break;
      case Kind::Relative:
      default: {
        Vec3f ext = safe_extent(q);
        float emin = std::max(1e-12f, std::min(ext.x, std::min(ext.y, ext.z)));
        *footprint = q.world_footprint * q.object_per_world / emin * smax;
      }
    }
    return point(q);
  }
};

/// Scalar -> colour: v -> clamp((v - lo) / (hi - lo)) (smoothstep with `smooth`), then a
/// colour ramp (grey without one), times `strength`.
struct ProceduralShaping {
  float lo = 0.f, hi = 1.f;
  float inv_range = 1.f;  ///< 1 / (hi - lo), kept so that a lookup multiplies instead of dividing
  bool smooth = false;
  bool invert = false;
  ColorRamp ramp;

  /// Declares `remap` (default `default_range`, or described by `default_doc` when it
  /// depends on other parameters), `smooth`, `invert`, `ramp_positions`, `ramp_colors`.
  static PluginInfo& declare(PluginInfo& info, std::optional<Vec2f> default_range, const std::string& default_doc = "") {
    ParamDecl remap = default_range ? param::vec2("remap", *default_range, "input range [lo, hi] mapped to [0, 1]")
                                    : param::vec2("remap", Vec2f(0.f, 1.f), "input range [lo, hi] mapped to [0, 1]");
    if (!default_range) {
      remap.has_default = false;
      remap.default_is(default_doc);
    }
    info.add(remap)
        .add(param::boolean("smooth", false, "smoothstep instead of a linear remap"))
        .add(param::boolean("invert", false, "1 - the remapped value"))
        .add(param::floats("ramp_positions", "colour ramp: increasing positions in [0, 1]").in(0, 1))
        .add(param::floats("ramp_colors", "colour ramp: r, g, b per position (grey without a ramp)"))
        .requires_all("ramp_positions", {"ramp_colors"})
        .requires_all("ramp_colors", {"ramp_positions"});
    return info;
  }

  static ProceduralShaping from_params(const Params& p, Vec2f default_range) {
    ProceduralShaping s;
    Vec2f r = p.has("remap") ? p.get_vec2("remap") : default_range;
    s.lo = r.x;
    s.hi = r.y;
    if (!(s.hi != s.lo)) throw Error("parameter 'remap': the two ends must differ");
    s.inv_range = 1.f / (s.hi - s.lo);
    s.smooth = p.get_bool("smooth");
    s.invert = p.get_bool("invert");
    if (p.has("ramp_positions")) {
      std::vector<float> pos = p.get_floats("ramp_positions");
      std::vector<float> flat = p.get_floats("ramp_colors");
      if (flat.size() != 3 * pos.size())
        throw Error("parameter 'ramp_colors': needs 3 numbers (r, g, b) per ramp position (" +
                    std::to_string(pos.size()) + " positions, " + std::to_string(flat.size()) + " numbers)");
      std::vector<Color> cols;
      for (size_t i = 0; i < pos.size(); ++i) cols.emplace_back(flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]);
      s.ramp = ColorRamp(pos, cols);
    }
    return s;
  }

  float shape(float v) const {
    float t = (v - lo) * inv_range;
    t = t < 0.f ? 0.f : (t > 1.f ? 1.f : t);
    if (smooth) t = t * t * (3.f - 2.f * t);
    return invert ? 1.f - t : t;
  }
  Color color(float v) const {
    float t = shape(v);
    return ramp.empty() ? Color(t) : ramp.eval(t);
  }
  /// d shape / d v (0 where the remap clamps).
  float shape_derivative(float v) const {
    float t = (v - lo) * inv_range;
    if (t <= 0.f || t >= 1.f) return 0.f;
    float d = inv_range;
    if (smooth) d *= 6.f * t * (1.f - t);
    return invert ? -d : d;
  }

  /// The linear remap (no smoothstep) averaged over v +- w/2: exact box filtering of the
  /// shaping for a field v with unit gradient (distances), in closed form.
  /// NOTE: the antiderivative of clamp((u - lo) / (hi - lo), 0, 1) is 0 below lo,
  /// (u - lo)^2 / (2 (hi - lo)) up to hi and (hi - lo) / 2 + (u - hi) above (the
  /// "filtered step" of Ebert et al., "Texturing & Modeling", ch. 2).
  float shape_box(float v, float w) const {
    if (!(w > 1e-6f)) return shape(v);
    float a = std::min(lo, hi), b = std::max(lo, hi);
    auto F = [&](float u) {
      if (u <= a) return 0.f;
      if (u <= b) return (u - a) * (u - a) / (2.f * (b - a));
      return 0.5f * (b - a) + (u - b);
    };
    float t = (F(v + 0.5f * w) - F(v - 0.5f * w)) / w;
    if (hi < lo) t = 1.f - t;
    t = t < 0.f ? 0.f : (t > 1.f ? 1.f : t);
    return invert ? 1.f - t : t;
  }
  Color color_box(float v, float w) const {
    float t = shape_box(v, w);
    return ramp.empty() ? Color(t) : ramp.eval(t);
  }
};

/// Mean colour of a procedural texture, estimated once at creation from a fixed set of `n`
/// points (for light power estimates and albedo priors; "strokes" also shades with it where the
/// footprint spans a cell, and asks for more points).
template <class F>
Color estimate_average(const F& value_at, int n = 512) {
  Color sum(0.f);
  for (int i = 0; i < n; ++i) {
    // A 3D Halton-like lattice over a 16-unit cube (bases 2, 3, 5).
    auto radical = [](int i, int b) {
      float f = 1.f, r = 0.f;
      for (; i > 0; i /= b) {
        f /= float(b);
        r += f * float(i % b);
      }
      return r;
    };
    sum += value_at(Vec3f(radical(i + 1, 2), radical(i + 1, 3), radical(i + 1, 5)) * 16.f);
  }
  return sum / float(n);
}

}  // namespace sg
