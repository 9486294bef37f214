// Procedural textures baked into images at the resolution the camera needs (`bake: auto`,
// docs/texture_lod.md). A procedural texture with uv mapping and `bake: auto` is created
// wrapped in a BakedTexture (create_texture): before each render with texture_lod, the scene
// bakes it over the uv rectangle the texture resolution estimate saw it in, one texel per
// smallest footprint (a power of two per side), and lookups inside that rectangle read the
// image's pyramid instead of evaluating the noise graph; outside it (a bounce the estimate did
// not follow) and without texture_lod they evaluate the procedural texture itself.
#pragma once

#include <memory>

#include "texture/footprint.h"
#include "texture/mipmap.h"
#include "texture/texture.h"

namespace sg {

class BakedTexture : public Texture {
 public:
  explicit BakedTexture(std::shared_ptr<Texture> inner);

  Color eval_point(const TexturePoint& q) const override;
  Color eval(const Vec2f& uv, float footprint) const override;
  Color average() const override { return m_inner->average(); }
  bool needs_position() const override { return false; }
  bool needs_uv_footprint() const override { return true; }
  bool eval_gradient(const TexturePoint& q, Vec3f* grad, bool* world_space) const override {
    return m_inner->eval_gradient(q, grad, world_space);
  }

  /// The largest baked image, texels per side (16 MiB of float RGB with its pyramid): a
  /// camera that needs more -- a close-up, or a road seen from near to far, whose nearest
  /// pixels set the resolution of the whole image -- evaluates the procedural texture.
  static constexpr int k_max_side = 1024;
  /// Bakes (or keeps) the image for what the estimate recorded of this texture: its uv
  /// rectangle, one texel per smallest footprint. Returns false when nothing is baked (not
  /// seen, or finer than k_max_side allows). Between renders only; `threads` 0 = all cores.
  bool bake(const FootprintRecorder::UvUse& use, int threads) const;
  /// Forgets the image (lookups evaluate the procedural texture).
  void clear() const;
  /// The baked image's size (0 x 0 when none) and its bytes.
  int width() const { return m_mip ? m_mip->width(0) : 0; }
  int height() const { return m_mip ? m_mip->height(0) : 0; }
  uint64_t bytes() const { return m_mip ? m_mip->bytes(0) : 0; }

 private:
  /// The baked lookup at uv with footprint `fp` (uv units), or false outside the image.
  bool lookup(const Vec2f& uv, float fp, Color* out) const;
  std::shared_ptr<Texture> m_inner;
  // NOTE: mutable: baked between renders (Scene::render, before tracing), never during one.
  mutable std::shared_ptr<const MipMap> m_mip;
  mutable Vec2f m_lo, m_hi;       ///< the uv rectangle of the image
  mutable Vec2f m_inner_lo, m_inner_hi;  ///< the part read (one texel in from the edges)
};

/// A procedural texture made bakeable (`bake: auto`).
std::shared_ptr<Texture> make_baked_texture(std::shared_ptr<Texture> inner);

}  // namespace sg
