// Mip-mapped images for filtered texture lookups (used by the "image" texture plugin).
//
// The pyramid is built once per decoded image with an exact area-weighted box filter
// (the polyphase box filter of Guthe & Heckbert for non-power-of-two sizes): every texel
// of level k+1 is the area average of the level-k texels it covers. The texels of a level
// partition the image exactly, so no texel outside the image is ever read and the
// pyramid is the same for every wrap mode (wrapping applies at lookup time only); the
// same pyramid can therefore be shared by textures with different wrap modes and uv
// transforms (see ImageCache).
//
// Isotropic lookups (`lookup`) are trilinear: two bilinear lookups in the levels around
// lambda = log2(width * max(W, H)) (width = footprint in texture units), blended
// linearly. Anisotropic lookups (`lookup_ellipse`, used with the ray-cone footprint
// ellipse) average up to 8 trilinear probes along the ellipse's major axis at the level
// of its minor axis (Feline). Pixels are linear RGB (sRGB images are decoded on load,
// io/image_io.h), so all filtering happens in linear space.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/math.h"
#include "io/image_io.h"
#include "texture/texture.h"

namespace sg {

enum class WrapMode { Repeat, Clamp, Mirror };

/// Parses "repeat", "clamp" or "mirror"; throws sg::Error naming `context` and the
/// parameter 'wrap' otherwise.
WrapMode parse_wrap_mode(const std::string& s, const std::string& context);

/// Where a pyramid's colour levels come back from once dropped (MipMap::make_resident):
/// returns the texel data (MipMap::channels() values per texel, row-major) of levels
/// [first, first + count). Throws sg::Error (sg::FileError for files) when it cannot.
using MipSource = std::function<std::vector<std::vector<float>>(int first, int count)>;
/// Where single tiles of a level come back from: the texels of each rectangle of `level`
/// (MipMap::channels() values per texel, row-major over the rectangle). Optional: without
/// one, tiles are cut from their whole level (MipSource).
using MipTileSource = std::function<std::vector<std::vector<float>>(int level, const std::vector<TexelRect>& rects)>;

class MipMap {
 public:
  /// Builds the pyramid of `image` (1 or 2 channels: grey, replicated to RGB; 3 or more:
  /// the first three are RGB). The alpha channel (channel 1 of a 2-channel image, channel 3
  /// of a 4+-channel image) gets a separate one-channel pyramid (alpha()).
  /// Throws sg::Error for an empty image.
  explicit MipMap(const ImageData& image);
  /// A pyramid read lazily from `source`: level sizes, channels (1 or 3) and the average
  /// given; only the tail (levels at most k_tail_texels on a side) is read now, the rest when
  /// use_levels asks for it (Scene::render: the texture resolution estimate's levels, or
  /// every level without RenderSettings::texture_lod).
  /// `alpha`: the pyramid of its alpha channel (whole), or null.
  MipMap(std::vector<int> widths, std::vector<int> heights, int channels, const Color& average, MipSource source,
         std::shared_ptr<const MipMap> alpha = nullptr);

  int levels() const { return int(m_levels.size()); }
  int width(int level) const { return m_levels[size_t(level)].width; }
  int height(int level) const { return m_levels[size_t(level)].height; }
  /// 1 for grey images, 3 for colour images.
  int channels() const { return m_channels; }
  /// Mean of level 0 (accumulated in double precision).
  Color average() const { return m_average; }

  /// Texel (x, y) of `level` (x to the right, y down, row 0 = top row), indices wrapped.
  Color texel(int level, int x, int y, WrapMode wrap) const;
  /// Bilinear interpolation in `level` at image coordinates (s, t) in [0, 1]^2 units
  /// (s to the right, t down); texel (i, j) has its centre at ((i + 0.5) / w, (j + 0.5) / h).
  Color bilinear(int level, float s, float t, WrapMode wrap) const;
  /// Trilinear lookup filtered over a footprint of `width` image widths (0 = bilinear in
  /// level 0; a footprint covering the image returns the average).
  Color lookup(float s, float t, float width, WrapMode wrap) const;
  /// Anisotropic lookup over the ellipse with conjugate axes `a` and `b` (full widths, in
  /// image units): up to k_max_probes trilinear probes along the major axis, each as wide
  /// as the minor axis (see mipmap.cpp).
  Color lookup_ellipse(float s, float t, const Vec2f& a, const Vec2f& b, WrapMode wrap) const;
  static constexpr int k_max_probes = 8;

  /// Bytes of the texels of colour levels `first_level` and coarser plus the whole alpha
  /// pyramid (cut-outs stay exact: they decide the labels): the memory the pyramid holds
  /// with those levels resident.
  uint64_t bytes(int first_level = 0) const;
  /// The same with level `level` resident in the tiles flagged in `used` only (empty: whole).
  uint64_t bytes(int level, const std::vector<uint8_t>& used) const;
  /// Bytes of the texels in memory now (whole levels and tiles, the alpha pyramid included).
  uint64_t resident_bytes() const;

  // Residency (docs/texture_lod.md). Lookups read levels first_used() and coarser only: a
  // footprint that asks for a finer one reads that level (bilinear there). Levels from
  // first_resident() <= first_used() on are in memory (finer ones than used may stay,
  // cached for later frames); levels at most k_tail_texels on a side stay resident always.
  static constexpr int k_tail_texels = 64;
  /// The finest colour level lookups read.
  int first_used() const { return m_first; }
  /// The finest colour level in memory.
  int first_resident() const { return m_resident; }
  /// The first level of the tail: the finest level make_resident may leave as the finest.
  int tail_level() const { return m_tail; }
  /// Gives a pyramid built from pixels the source its dropped levels come back from (without
  /// one, levels are never dropped).
  void set_source(MipSource source) { m_source = std::move(source); }
  /// Gives the pyramid a reader of single tiles (a tiled file: only the tiles read decode).
  void set_tile_source(MipTileSource source) { m_tile_source = std::move(source); }

  // Tiles (docs/texture_lod.md): the finest level lookups read may be resident in part, in
  // tiles of k_tile x k_tile texels; lookups whose texels fall in a tile the frame does not
  // use read the next coarser level instead (whole), so a frame's images depend on its own
  // tiles only, never on what an earlier frame left resident.
  static constexpr int k_tile = 64;
  int tiles_x(int level) const { return (width(level) + k_tile - 1) / k_tile; }
  int tiles_y(int level) const { return (height(level) + k_tile - 1) / k_tile; }
  /// use_levels(first), with level `first` read only in the tiles flagged in `used`
  /// (tiles_x * tiles_y flags, row-major; empty: every tile); the tiles are read from the
  /// tile source (or cut from the level) when not resident. `first` at or past the tail
  /// level uses every tile.
  void use_tiles(int first, const std::vector<uint8_t>& used) const;
  /// Tiles of first_used() the frame reads (0 when it reads the whole level), and resident.
  int used_tiles() const;
  int resident_tiles() const;
  /// Lookups read colour levels `first` (clamped to [0, tail_level()]) and coarser: they are
  /// read from the source when not resident; finer resident levels stay (drop_unused frees
  /// them). NOTE: none of the residency calls is safe while lookups run: Scene calls them
  /// between renders only (build, then commit, then render).
  void use_levels(int first) const;
  /// use_levels(first), then frees the levels finer than it (only with a source).
  void make_resident(int first) const;
  /// Frees the resident levels finer than first_used() and the tiles of first_used() the
  /// frame does not use (only with a source).
  void drop_unused() const;

  /// The texels of a level (empty when it is not resident or resident in tiles only); for
  /// sources and tests.
  const std::vector<float>& level_data(int level) const { return m_levels[size_t(level)].data; }

  /// Pyramid of the alpha channel (one channel), null when the image has none.
  const MipMap* alpha() const { return m_alpha.get(); }

 private:
  struct Level {
    int width = 0, height = 0;
    std::vector<float> data;  ///< row-major, m_channels floats per texel (empty: not resident)
    /// Resident in tiles (data empty): tiles_x * tiles_y row-major tiles, each its texels
    /// row-major over the tile's own width (k_tile, less at the right and bottom edges).
    std::vector<std::vector<float>> tiles;
    /// Of the first used level: the tiles lookups read (empty: all).
    std::vector<uint8_t> used;
  };
  void set_tail();
  /// The texels of tile `t` (row-major index) of `level`.
  TexelRect tile_rect(int level, size_t t) const;
  /// Levels [first, levels()) resident and whole (read back, tiled ones completed).
  void make_whole(int first) const;
  /// Pointer to texel (x, y) (in range) of level `level`, or null when a lookup must not read
  /// it (a tile the frame does not use).
  const float* texel_ptr(const Level& l, size_t x, size_t y) const;
  // NOTE: mutable: residency changes between renders (make_resident), never during one.
  mutable std::vector<Level> m_levels;
  int m_channels = 3;
  Color m_average{0.f};
  std::shared_ptr<const MipMap> m_alpha;
  MipSource m_source;
  MipTileSource m_tile_source;
  int m_tail = 0;
  mutable int m_first = 0, m_resident = 0;
};

/// Parameters of an image texture besides its pixels.
struct ImageTextureOptions {
  WrapMode wrap = WrapMode::Repeat;
  Color scale{1.f};                  ///< multiplies the looked-up value
  Vec2f uv_scale{1.f, 1.f};          ///< S in uv' = R S uv + offset (non-zero)
  Vec2f uv_offset{0.f, 0.f};
  float uv_rotation_degrees = 0.f;   ///< R: counter-clockwise in the (u, v) plane
};

/// Image texture over a (possibly shared) pyramid. Implemented in texture/image.cpp.
std::shared_ptr<Texture> make_image_texture(std::shared_ptr<const MipMap> mipmap,
                                                  const ImageTextureOptions& options);

}  // namespace sg
