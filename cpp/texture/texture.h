// Textures: colour (or scalar) fields over the surface UV parameterization.
// Created by name ("constant", "image") from a ParamSet; see texture/*.cpp.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/params.h"
#include "core/plugin.h"

namespace sg {

class MipMap;

/// Everything a texture may be evaluated from: the surface parameterization and footprint
/// (all textures) and, for procedural textures with 3D mappings (object, world,
/// relative-local), the hit point in world and object space, the object's bounds and the
/// footprint width in world units.
struct TexturePoint {
  Vec2f uv;
  float uv_footprint = 0.f;
  Vec2f uv_axis_a, uv_axis_b;  ///< footprint ellipse in uv (zero when unknown)
  Vec3f p_world, p_object;
  Vec3f object_lo, object_hi;  ///< object-space bounds of the mesh (relative-local mapping)
  float world_footprint = 0.f; ///< footprint width at the hit in world units (0 = point sample)
  float object_per_world = 1.f; ///< object-space length per world-space length (instance scale)
  float ao = 1.f;               ///< ambient occlusion at the point ("ao" textures), 1 = open
  float edge = 0.f;             ///< convex-edge measure at the point ("edges" textures), 0 = open panel
  Vec3f n_world, n_object;      ///< unit shading normal in world and object space (triplanar)
};

class Texture {
 public:
  virtual ~Texture() = default;
  /// True when the texture reads more than uv (positions: procedural 3D mappings); it is
  /// then evaluated through eval_point.
  virtual bool needs_position() const { return false; }
  /// Value at a full TexturePoint. Default: the uv lookup (eval_ellipse when the ellipse is known).
  virtual Color eval_point(const TexturePoint& q) const {
    if (q.uv_axis_a.x != 0.f || q.uv_axis_a.y != 0.f) return eval_ellipse(q.uv, q.uv_axis_a, q.uv_axis_b);
    return eval(q.uv, q.uv_footprint);
  }
  /// Linear RGB value at texture coordinate `uv`, filtered over a footprint of width
  /// `footprint` in texture space (0 = point sample).
  virtual Color eval(const Vec2f& uv, float footprint = 0.f) const = 0;
  /// Linear RGB value filtered over the ellipse with conjugate axes `axis_a`, `axis_b`
  /// (full widths, texture space), e.g. a ray cone's footprint on a slanted surface.
  /// Default: the isotropic eval over the longer axis.
  virtual Color eval_ellipse(const Vec2f& uv, const Vec2f& axis_a, const Vec2f& axis_b) const {
    float la = axis_a.x * axis_a.x + axis_a.y * axis_a.y, lb = axis_b.x * axis_b.x + axis_b.y * axis_b.y;
    return eval(uv, std::sqrt(std::max(la, lb)));
  }
  /// Gradient of the first channel at q, for bump mapping without finite differences:
  /// with respect to p_object (`*world_space` false) or p_world (true). False when the
  /// texture has no analytic gradient (bump mapping then uses central differences).
  virtual bool eval_gradient(const TexturePoint& q, Vec3f* grad, bool* world_space) const { return false; }
  /// Ray length and ray count of the ambient occlusion this texture reads (0: none).
  virtual float ao_radius() const { return 0.f; }
  virtual int ao_samples() const { return 0; }
  /// Convex-edge rays wanted ("edges" textures): their length (0 = none) and number.
  virtual float edge_radius() const { return 0.f; }
  virtual int edge_samples() const { return 0; }
  /// True when lookups read the uv footprint (uv_footprint, the uv ellipse): image textures
  /// and uv-mapped procedural ones. Procedural textures over 3D mappings read only the world
  /// footprint, which the integrator always provides (cheaply), so the uv ellipse of the ray
  /// cone is not computed for them.
  virtual bool needs_uv_footprint() const { return true; }
  /// True when the value does not depend on the point (lets materials skip footprints and
  /// lookups); the value is then constant_value(). Not virtual: read per lookup.
  bool is_constant() const { return m_constant; }
  const Color& constant_value() const { return m_constant_value; }
  /// Average value over the texture (used for light power estimates and albedo priors).
  virtual Color average() const = 0;
  /// True when the texture has an alpha channel (image files with 2 or 4+ channels).
  virtual bool has_alpha_channel() const { return false; }
  /// Alpha channel at `uv`, filtered like eval(); 1 without an alpha channel.
  virtual float eval_alpha(const Vec2f& uv, float footprint = 0.f) const { return 1.f; }
  /// The pyramid an image texture reads (texture/mipmap.h); null for other textures.
  virtual const MipMap* mipmap() const { return nullptr; }
  /// What went wrong during lookups ("" when nothing did): user extensions' textures record
  /// non-finite outputs here, and the render that saw one fails with this message.
  virtual std::string failure() const { return {}; }

 protected:
  /// For textures that know at construction that they are constant.
  void set_constant(const Color& value) {
    m_constant = true;
    m_constant_value = value;
  }

 private:
  bool m_constant = false;
  Color m_constant_value{0.f};
};

/// Base of the textures defined on a TexturePoint (procedural and composite ones): a plain
/// uv lookup is eval_point at that uv with every other field at its default.
class PointTexture : public Texture {
 public:
  Color eval_point(const TexturePoint& q) const override = 0;
  Color eval(const Vec2f& uv, float footprint) const final {
    TexturePoint q;
    q.uv = uv;
    q.uv_footprint = footprint;
    return eval_point(q);
  }
};

/// Texture library lookup for textures built from other textures ("blend"); null when absent.
using TextureInputs = TextureLookup;
/// Creates a texture plugin by registry key (core/plugin.h: the parameters are checked
/// against the plugin's declaration first). Image files are decoded through `images`
/// (the scene's shared cache, texture/image_cache.h; null = a private copy); `inputs`
/// resolves texture references of composite textures (textures are immutable once added,
/// so a reference always sees the same texture).
/// Throws sg::Error naming `context` for unknown types or parameters.
std::shared_ptr<Texture> create_texture(const std::string& type, const ParamSet& params,
                                        const std::string& context, ImageCache* images = nullptr,
                                        const TextureInputs& inputs = nullptr);
/// Registry keys of all texture plugins.
std::vector<std::string> texture_types();

/// A Texture / ColorTexture / FloatTexture parameter given as a texture reference,
/// resolved through `lookup` (throws when the texture does not exist); null when the
/// parameter is absent or a constant.
std::shared_ptr<Texture> texture_param(const Params& p, const std::string& name, const TextureLookup& lookup);
/// A ColorTexture parameter: the referenced texture (its average checked against the
/// declared component range) or a constant texture of the given value or default.
std::shared_ptr<Texture> color_texture_param(const Params& p, const std::string& name, const TextureLookup& lookup);

std::shared_ptr<Texture> make_constant_texture(const Color& value);

struct ImageData;
/// Image texture from decoded pixels (already linear), repeat wrapping, times `scale`.
std::shared_ptr<Texture> make_image_texture(const ImageData& pixels, const Color& scale);

}  // namespace sg
