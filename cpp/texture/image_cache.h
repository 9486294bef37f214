// The texture cache of a Scene: every image file is decoded and mip-mapped once per
// (resolved absolute path, colour space); all image textures of the scene that name the
// same file (with any spelling of its path, any wrap mode, scale or uv transform) share
// the same pixels and pyramid. File imports (Scene::load_mesh_file) go through the same
// cache.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "io/image_io.h"
#include "texture/mipmap.h"

namespace sg {

class ImageCache {
 public:
  /// Reads an image (default: io/image_io.h load_image); tests inject counting loaders.
  using Loader = std::function<ImageData(const std::string& path, ColorSpace space)>;

  explicit ImageCache(Loader loader = nullptr);
  ImageCache(const ImageCache&) = delete;
  ImageCache& operator=(const ImageCache&) = delete;

  /// The shared pyramid of `path` decoded with `space`. Loads and builds it on the first
  /// request, and again when the file's size or modification time changed since (an
  /// edited file is re-read). Throws sg::FileError naming `path` when it cannot be read.
  std::shared_ptr<const MipMap> get(const std::string& path, ColorSpace space);

  /// Cache key of a path: absolute, with ".", ".." and symbolic links resolved.
  static std::string resolve(const std::string& path);

  /// Registers decoded pixels held in memory and returns their key ("memory:" and a hash
  /// of the content), which get() then accepts as a path. Identical pixels get the same
  /// key (one pyramid). The cache keeps only a weak reference: the caller keeps the
  /// pixels alive while textures may be created from the key. `integer_source`: the
  /// values came from 8/16-bit integers, so ColorSpace::Auto decodes them as sRGB (as for
  /// such files); otherwise Auto means linear.
  std::string add_memory(std::shared_ptr<const ImageData> pixels, bool integer_source);
  static bool is_memory_key(const std::string& path) { return path.rfind("memory:", 0) == 0; }

  uint64_t loads() const;  ///< files decoded so far
  uint64_t hits() const;   ///< requests served without decoding

  /// Tiled mip-mapped copies of image files (docs/texture_lod.md): with a directory set, the
  /// pyramid of every file (colour, then alpha) is written there once (io/image_io.h
  /// save_mip_file, named by a hash of the resolved path, size, modification time and colour
  /// space) and later requests read it lazily -- only the tail now, the levels a frame needs
  /// when Scene applies the texture resolution estimate. Empty (the default): off.
  void set_mip_cache_dir(const std::string& dir);
  const std::string& mip_cache_dir() const { return m_mip_dir; }
  uint64_t mip_files_written() const;  ///< cache files written so far
  uint64_t mip_files_opened() const;   ///< requests served lazily from a cache file

 private:
  struct Entry {
    std::weak_ptr<const MipMap> mipmap;  ///< alive while some texture uses it
    int64_t mtime = 0;
    int64_t size = -1;
  };
  struct Memory {
    std::weak_ptr<const ImageData> pixels;
    bool integer_source = false;
  };
  Loader m_loader;
  std::map<std::pair<std::string, int>, Entry> m_entries;
  std::map<std::string, Memory> m_memory;
  /// The pyramid of a decoded file: written to the mip cache and re-read from it when its
  /// levels are dropped (with a cache directory), else whole and fixed. Alpha stays whole.
  std::shared_ptr<const MipMap> decoded_pyramid(const ImageData& image, const std::string& cache_file);
  std::string mip_cache_file(const std::string& key_path, int64_t size, int64_t mtime, ColorSpace space) const;
  /// Erases entries whose pixels and pyramids no texture holds any more, every 256 new
  /// entries: a long run adds generated images (plates, signs) every frame, and the maps must
  /// not grow with them. Called with m_mutex held.
  void sweep_expired();
  uint64_t m_loads = 0, m_hits = 0, m_mip_written = 0, m_mip_opened = 0;
  uint64_t m_new_entries = 0;
  std::string m_mip_dir;
  mutable std::mutex m_mutex;
};

}  // namespace sg
