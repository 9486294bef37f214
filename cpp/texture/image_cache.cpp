#include "texture/image_cache.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
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

namespace {

uint64_t fnv1a(const void* data, size_t n, uint64_t h) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

bool same_pixels(const ImageData& a, const ImageData& b) {
  return a.width == b.width && a.height == b.height && a.channels == b.channels && a.pixels == b.pixels;
}

/// sRGB EOTF on the colour channels (not alpha): what load_image does for sRGB files.
ImageData srgb_decoded(const ImageData& in) {
  ImageData out = in;
  int cc = out.channels == 2 ? 1 : std::min(out.channels, 3);
  for (size_t k = 0; k < size_t(out.width) * out.height; ++k)
    for (int c = 0; c < cc; ++c) {
      float& v = out.pixels[k * out.channels + c];
      v = v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
    }
  return out;
}

}  // namespace

std::string ImageCache::add_memory(std::shared_ptr<const ImageData> pixels, bool integer_source) {
  int dims[3] = {pixels->width, pixels->height, pixels->channels};
  uint64_t h = fnv1a(dims, sizeof dims, 0xcbf29ce484222325ull);
  h = fnv1a(pixels->pixels.data(), pixels->pixels.size() * sizeof(float), h);
  char buf[40];
  std::snprintf(buf, sizeof buf, "memory:%016llx%s", static_cast<unsigned long long>(h), integer_source ? "i" : "");
  std::lock_guard<std::mutex> lock(m_mutex);
  for (int n = 0;; ++n) {
    std::string key = n ? std::string(buf) + "-" + std::to_string(n) : std::string(buf);
    Memory& m = m_memory[key];
    auto alive = m.pixels.lock();
    // A new key, an expired one, or the same content (a hash collision gets the next suffix).
    if (!alive || same_pixels(*alive, *pixels)) {
      if (!alive) {
        m.pixels = pixels;
        m.integer_source = integer_source;
      }
      return key;
    }
  }
}

std::shared_ptr<const MipMap> ImageCache::get(const std::string& path, ColorSpace space) {
  if (is_memory_key(path)) {
    std::lock_guard<std::mutex> lock(m_mutex);
    auto it = m_memory.find(path);
    std::shared_ptr<const ImageData> px = it == m_memory.end() ? nullptr : it->second.pixels.lock();
    if (!px) throw FileError(path, "no such in-memory image (add it with Scene.add_image_texture)");
    Entry& e = m_entries[{path, int(space)}];
    if (auto mip = e.mipmap.lock()) {
      ++m_hits;
      return mip;
    }
    bool srgb = space == ColorSpace::SRGB || (space == ColorSpace::Auto && it->second.integer_source);
    auto mip = std::make_shared<const MipMap>(srgb ? srgb_decoded(*px) : *px);
    e.mipmap = mip;
    return mip;
  }
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
