// Texture "image": an image file read through OpenImageIO (io/image_io.cpp), mip-mapped
// and filtered over the ray footprint (texture/mipmap.h: trilinear for an isotropic
// width, Feline probes for a footprint ellipse), with repeat / clamp / mirror wrapping
// and a 2D uv transform uv' = R S uv + offset (scale first, then rotate about the uv
// origin, then offset).
//
// Parameters: filename, colorspace (auto/srgb/linear), wrap (repeat/clamp/mirror),
// scale (colour multiplier), uv_scale [su, sv] (non-zero), uv_offset [ou, ov],
// uv_rotation (degrees, counter-clockwise). Decoded pixels are shared through the
// scene's ImageCache (texture/image_cache.h).
#include <cmath>
#include <sstream>

#include "core/error.h"
#include "io/image_io.h"
#include "texture/footprint.h"
#include "texture/image_cache.h"
#include "texture/mipmap.h"
#include "texture/texture.h"

namespace sg {

namespace {

class ImageTexture final : public Texture {
 public:
  ImageTexture(std::shared_ptr<const MipMap> mip, const ImageTextureOptions& o)
      : m_mip(std::move(mip)), m_wrap(o.wrap), m_scale(o.scale), m_offset(o.uv_offset) {
    float a = o.uv_rotation_degrees * (k_pi / 180.f);
    float c = std::cos(a), s = std::sin(a);
    // M = R S, row-major: [c -s; s c] diag(su, sv).
    m_m00 = c * o.uv_scale.x;
    m_m01 = -s * o.uv_scale.y;
    m_m10 = s * o.uv_scale.x;
    m_m11 = c * o.uv_scale.y;
    // NOTE: a uv-space footprint of width w becomes an ellipse with axes |su| w and
    // |sv| w after S (R preserves lengths). The isotropic trilinear filter takes the major
    // axis, as pbrt-v4's isotropic filters do (Pharr, Jakob, Humphreys 2023,
    // MIPMap::Filter: width = 2 max |differential component|): blurring more along the
    // minor axis never aliases.
    m_footprint_scale = std::max(std::fabs(o.uv_scale.x), std::fabs(o.uv_scale.y));
    m_identity = o.uv_scale.x == 1.f && o.uv_scale.y == 1.f && o.uv_rotation_degrees == 0.f &&
                 o.uv_offset.x == 0.f && o.uv_offset.y == 0.f;
  }

  Color eval(const Vec2f& uv, float footprint) const override {
    Vec2f p = uv;
    float w = footprint;
    if (!m_identity) {
      p = Vec2f(m_m00 * uv.x + m_m01 * uv.y + m_offset.x, m_m10 * uv.x + m_m11 * uv.y + m_offset.y);
      w *= m_footprint_scale;
    }
    record(p, Vec2f(w, 0.f), Vec2f(0.f, w));
    // NOTE: texture space has v pointing up (glTF/OBJ convention); image rows go down.
    return m_mip->lookup(p.x, 1.f - p.y, w, m_wrap) * m_scale;
  }
  Color eval_ellipse(const Vec2f& uv, const Vec2f& axis_a, const Vec2f& axis_b) const override {
    Vec2f p = uv, a = axis_a, b = axis_b;
    if (!m_identity) {
      // Axes are vectors: the linear part M = R S maps them exactly.
      p = Vec2f(m_m00 * uv.x + m_m01 * uv.y + m_offset.x, m_m10 * uv.x + m_m11 * uv.y + m_offset.y);
      a = Vec2f(m_m00 * axis_a.x + m_m01 * axis_a.y, m_m10 * axis_a.x + m_m11 * axis_a.y);
      b = Vec2f(m_m00 * axis_b.x + m_m01 * axis_b.y, m_m10 * axis_b.x + m_m11 * axis_b.y);
    }
    record(p, a, b);
    // Image t = 1 - v: axis vectors flip their v component.
    return m_mip->lookup_ellipse(p.x, 1.f - p.y, Vec2f(a.x, -a.y), Vec2f(b.x, -b.y), m_wrap) * m_scale;
  }
  Color average() const override { return m_mip->average() * m_scale; }
  bool has_alpha_channel() const override { return m_mip->alpha() != nullptr; }
  /// The alpha channel, not multiplied by `scale` (a colour multiplier).
  float eval_alpha(const Vec2f& uv, float footprint) const override {
    const MipMap* a = m_mip->alpha();
    if (!a) return 1.f;
    Vec2f p = uv;
    float w = footprint;
    if (!m_identity) {
      p = Vec2f(m_m00 * uv.x + m_m01 * uv.y + m_offset.x, m_m10 * uv.x + m_m11 * uv.y + m_offset.y);
      w *= m_footprint_scale;
    }
    record(p, Vec2f(w, 0.f), Vec2f(0.f, w));
    return a->lookup(p.x, 1.f - p.y, w, m_wrap).x;
  }
  const MipMap* mipmap() const override { return m_mip.get(); }

 private:
  /// Reports a lookup at `p` (uv after the transform) with footprint vectors `a`, `b` (image
  /// units; zero: a point lookup) to the texture resolution estimate while one records
  /// (texture/footprint.h).
  void record(const Vec2f& p, const Vec2f& a, const Vec2f& b) const {
    if (FootprintRecorder* r = active_footprint_recorder()) {
      const float m[4] = {m_m00, m_m01, m_m10, m_m11};
      r->record(this, *m_mip, a, b, m, Vec2f(p.x, 1.f - p.y), m_wrap);
    }
  }

  std::shared_ptr<const MipMap> m_mip;
  WrapMode m_wrap;
  Color m_scale;
  Vec2f m_offset;
  float m_m00 = 1.f, m_m01 = 0.f, m_m10 = 0.f, m_m11 = 1.f;
  float m_footprint_scale = 1.f;
  bool m_identity = true;
};

std::string format_vec2(const Vec2f& v) {
  std::ostringstream s;
  s << "[" << v.x << ", " << v.y << "]";
  return s.str();
}

}  // namespace

std::shared_ptr<Texture> make_image_texture(std::shared_ptr<const MipMap> mipmap, const ImageTextureOptions& options) {
  return std::make_shared<ImageTexture>(std::move(mipmap), options);
}

std::shared_ptr<Texture> make_image_texture(const ImageData& pixels, const Color& scale) {
  ImageTextureOptions o;
  o.scale = scale;
  return make_image_texture(std::make_shared<const MipMap>(pixels), o);
}

namespace {

PluginInfo info() {
  return PluginInfo("texture", "image",
                    "An image file read through OpenImageIO (or pixels given from memory with "
                    "Scene.add_image_texture), mip-mapped and filtered over the ray footprint.")
      .add(param::path("file", "image file read by OpenImageIO (relative to the scene file in YAML)").alias("filename"))
      .add(param::choice("colorspace", "auto", {"auto", "srgb", "linear"},
                         "how to decode the pixels (auto: 8/16-bit images are sRGB)"))
      .add(param::choice("wrap", "repeat", {"repeat", "clamp", "mirror"}, "behaviour outside [0, 1] uv"))
      .add(param::color("scale", Color(1.f), "multiplies the texel values"))
      .add(param::vec2("uv_scale", Vec2f(1.f, 1.f), "uv scale S in uv' = R S uv + offset (non-zero)"))
      .add(param::vec2("uv_offset", Vec2f(0.f, 0.f), "uv offset, applied last"))
      .add(param::real("uv_rotation", 0.0, "counter-clockwise uv rotation in degrees, after scaling"));
}

std::shared_ptr<Texture> create(const Params& p, const PluginContext& ctx) {
  std::string filename = p.get_string("file");
  std::string cs = p.get_string("colorspace");
  ImageTextureOptions o;
  o.wrap = parse_wrap_mode(p.get_string("wrap"), "image texture");
  o.scale = p.get_color("scale");
  o.uv_scale = p.get_vec2("uv_scale");
  if (o.uv_scale.x == 0.f || o.uv_scale.y == 0.f)
    throw Error("parameter 'uv_scale': must be a non-zero number or two non-zero numbers, got " +
                format_vec2(o.uv_scale));
  o.uv_offset = p.get_vec2("uv_offset");
  o.uv_rotation_degrees = p.get_float("uv_rotation");
  ColorSpace space = cs == "srgb" ? ColorSpace::SRGB : (cs == "linear" ? ColorSpace::Linear : ColorSpace::Auto);
  // Without a scene cache (standalone use), the texture owns its pyramid.
  std::shared_ptr<const MipMap> mip = ctx.images ? ctx.images->get(filename, space)
                                                 : std::make_shared<const MipMap>(load_image(filename, space));
  return make_image_texture(std::move(mip), o);
}

}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
