#include "texture/image_cache.h"

#include <filesystem>

namespace sg {

namespace fs = std::filesystem;

ImageCache::ImageCache(Loader loader) : m_loader(std::move(loader)) {
  if (!m_loader) m_loader = [](const std::string& path, ColorSpace space) { return load_image(path, space); };
}

std::string ImageCache::resolve(const std::string& path) {
  std::error_code ec;
  fs::path abs = fs::absolute(fs::path(path), ec);
  if (ec) return path;
  fs::path canon = fs::weakly_canonical(abs, ec);
  return (ec ? abs.lexically_normal() : canon).string();
}

std::shared_ptr<const MipMap> ImageCache::get(const std::string& path, ColorSpace space) {
  const std::string key_path = resolve(path);
  std::error_code ec;
  int64_t size = int64_t(fs::file_size(key_path, ec));
  if (ec) size = -1;
  auto time = fs::last_write_time(key_path, ec);
  int64_t mtime = ec ? 0 : int64_t(time.time_since_epoch().count());

  std::lock_guard<std::mutex> lock(m_mutex);
  Entry& e = m_entries[{key_path, int(space)}];
  if (auto mip = e.mipmap.lock()) {
    if (e.size == size && e.mtime == mtime) {
      ++m_hits;
      return mip;
    }
  }
  // Decoded with the caller's spelling of the path so that errors name what the user wrote.
  auto mip = std::make_shared<const MipMap>(m_loader(path, space));
  ++m_loads;
  e.mipmap = mip;
  e.size = size;
  e.mtime = mtime;
  return mip;
}

uint64_t ImageCache::loads() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_loads;
}

uint64_t ImageCache::hits() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_hits;
}

}  // namespace sg
