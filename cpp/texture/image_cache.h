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
  uint64_t m_loads = 0, m_hits = 0;
  mutable std::mutex m_mutex;
};

}  // namespace sg
