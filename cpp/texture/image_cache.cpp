#include "texture/image_cache.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <unistd.h>

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

/// Colour levels read back from a mip cache file with `nc` colour channels (an alpha channel
/// after them is not read).
MipSource file_source(const std::string& cache_file, int nc) {
  return [cache_file, nc](int first, int count) {
    std::vector<ImageData> levels;
    load_mip_file(cache_file, first, count, &levels, 0, nc);
    std::vector<std::vector<float>> out;
    for (ImageData& l : levels) {
      if (l.channels != nc) throw FileError(cache_file, "mip level with the wrong number of channels");
      out.push_back(std::move(l.pixels));
    }
    return out;
  };
}

/// Tiles of colour levels read back from a mip cache file (only those tiles decode).
MipTileSource file_tile_source(const std::string& cache_file, int nc) {
  return [cache_file, nc](int level, const std::vector<TexelRect>& rects) {
    return load_mip_rects(cache_file, level, rects, 0, nc);
  };
}

}  // namespace

std::string ImageCache::add_memory(std::shared_ptr<const ImageData> pixels, bool integer_source) {
  int dims[3] = {pixels->width, pixels->height, pixels->channels};
  uint64_t h = fnv1a(dims, sizeof dims, 0xcbf29ce484222325ull);
  h = fnv1a(pixels->pixels.data(), pixels->pixels.size() * sizeof(float), h);
  char buf[40];
  std::snprintf(buf, sizeof buf, "memory:%016llx%s", static_cast<unsigned long long>(h), integer_source ? "i" : "");
  std::lock_guard<std::mutex> lock(m_mutex);
  sweep_expired();
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
    // Dropped levels are rebuilt from the pixels (the scene keeps them for save()).
    MipSource rebuild = [px, srgb](int first, int count) {
      MipMap full(srgb ? srgb_decoded(*px) : *px);
      std::vector<std::vector<float>> out;
      for (int l = first; l < first + count; ++l) out.push_back(full.level_data(l));
      return out;
    };
    auto mip = std::make_shared<MipMap>(srgb ? srgb_decoded(*px) : *px);
    mip->set_source(std::move(rebuild));
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
  std::shared_ptr<const MipMap> mip;
  const std::string cache_file = m_mip_dir.empty() ? std::string() : mip_cache_file(key_path, size, mtime, space);
  if (!cache_file.empty() && fs::exists(cache_file)) {
    try {
      MipFileHeader h = load_mip_file(cache_file, 0, 0, nullptr);
      const int nc = h.channels >= 3 ? 3 : 1;
      if (int(h.average.size()) == nc) {
        Color avg = nc == 1 ? Color(h.average[0]) : Color(h.average[0], h.average[1], h.average[2]);
        std::shared_ptr<const MipMap> alpha;
        if (h.channels == nc + 1) {
          // The alpha channel stays whole (cut-outs decide the labels): its pyramid is built
          // from level 0, as for a decoded image.
          std::vector<ImageData> a;
          load_mip_file(cache_file, 0, 1, &a, nc, nc + 1);
          alpha = std::make_shared<const MipMap>(a.at(0));
        }
        auto lazy = std::make_shared<MipMap>(h.widths, h.heights, nc, avg, file_source(cache_file, nc),
                                             std::move(alpha));
        lazy->set_tile_source(file_tile_source(cache_file, nc));
        mip = std::move(lazy);
        ++m_mip_opened;
      }
    } catch (const Error&) {
      mip = nullptr;  // unreadable or not ours: decoded again and rewritten below
    }
  }
  if (!mip) {
    // Decoded with the caller's spelling of the path so that errors name what the user wrote.
    mip = decoded_pyramid(m_loader(path, space), cache_file);
    ++m_loads;
  }
  e.mipmap = mip;
  e.size = size;
  e.mtime = mtime;
  return mip;
}

void ImageCache::sweep_expired() {
  if (++m_new_entries < 256) return;
  m_new_entries = 0;
  for (auto it = m_entries.begin(); it != m_entries.end();)
    it = it->second.mipmap.expired() ? m_entries.erase(it) : std::next(it);
  for (auto it = m_memory.begin(); it != m_memory.end();)
    it = it->second.pixels.expired() ? m_memory.erase(it) : std::next(it);
}

void ImageCache::set_mip_cache_dir(const std::string& dir) {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_mip_dir = dir;
}

std::string ImageCache::mip_cache_file(const std::string& key_path, int64_t size, int64_t mtime,
                                       ColorSpace space) const {
  // NOTE: "v1" is the pyramid's format (box filter of mipmap.cpp); a new filter needs a new tag.
  std::string key = key_path + "|" + std::to_string(size) + "|" + std::to_string(mtime) + "|" +
                    std::to_string(int(space)) + "|v1";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%016llx.exr",
                static_cast<unsigned long long>(fnv1a(key.data(), key.size(), 0xcbf29ce484222325ull)));
  return (fs::path(m_mip_dir) / buf).string();
}

std::shared_ptr<const MipMap> ImageCache::decoded_pyramid(const ImageData& image, const std::string& cache_file) {
  if (cache_file.empty()) return std::make_shared<const MipMap>(image);
  auto whole = std::make_shared<MipMap>(image);
  const int nc = whole->channels();
  const MipMap* alpha = whole->alpha();
  std::vector<ImageData> levels;
  for (int l = 0; l < whole->levels(); ++l) {
    ImageData d;
    d.width = whole->width(l);
    d.height = whole->height(l);
    d.channels = nc + (alpha ? 1 : 0);
    if (!alpha) {
      d.pixels = whole->level_data(l);
    } else {  // colour, then alpha, per texel
      const std::vector<float>& c = whole->level_data(l);
      const std::vector<float>& a = alpha->level_data(l);
      d.pixels.resize(size_t(d.width) * d.height * d.channels);
      for (size_t i = 0; i < a.size(); ++i) {
        for (int k = 0; k < nc; ++k) d.pixels[i * d.channels + k] = c[i * nc + k];
        d.pixels[i * d.channels + nc] = a[i];
      }
    }
    levels.push_back(std::move(d));
  }
  const Color a = whole->average();
  std::vector<float> avg = nc == 1 ? std::vector<float>{a.x} : std::vector<float>{a.x, a.y, a.z};
  std::error_code ec;
  fs::create_directories(m_mip_dir, ec);
  // Written under a temporary name and renamed: a reader never sees half a file.
  const std::string tmp = cache_file + ".tmp" + std::to_string(::getpid()) + ".exr";
  save_mip_file(tmp, levels, avg);
  fs::rename(tmp, cache_file, ec);
  if (ec) {
    fs::remove(tmp, ec);
    return whole;  // the pyramid stays whole (its levels cannot come back)
  }
  ++m_mip_written;
  whole->set_source(file_source(cache_file, nc));  // its levels can now be dropped and read back
  whole->set_tile_source(file_tile_source(cache_file, nc));
  return whole;
}

uint64_t ImageCache::mip_files_written() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_mip_written;
}

uint64_t ImageCache::mip_files_opened() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_mip_opened;
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
