// Loads the OpenImageIO plugin (libsynthgen_oiio.so) on first use; see image_io.h.
#include <cmath>
#include <cstdio>
#include <set>
#include <filesystem>
#include <mutex>

#include "core/error.h"
#include "core/isolate.h"
#include "io/image_io.h"
#include "io/plugin_loader.h"

namespace sg {

namespace {

const ImageIoApi* g_api = nullptr;
std::string g_load_error;

void load_plugin() {
  std::string errors;
  g_api = load_plugin_api<ImageIoApi>("libsynthgen_oiio.so", "SYNTHGEN_IMAGE_IO_PLUGIN", "synthgen_image_io_api",
                                      k_image_io_api_version, "image", &errors);
  if (!g_api) g_load_error = "cannot load the OpenImageIO plugin libsynthgen_oiio.so:" + errors;
}

const ImageIoApi& api() {
  static std::once_flag once;
  std::call_once(once, load_plugin);
  if (!g_api) throw Error(g_load_error);
  return *g_api;
}

}  // namespace

void load_image_plugin() { api(); }

namespace {

/// A file a reader may open: it exists and is a regular file (a directory sent libheif,
/// through OpenImageIO's format probing, into an endless allocation; a FIFO or a device
/// would block or never end). Found by fuzz_plugin_params.
void check_regular_file(const std::string& path, const char* what) {
  std::error_code ec;
  auto st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st)) throw FileError(path, "file not found");
  if (std::filesystem::is_directory(st)) throw FileError(path, std::string("is a directory, not ") + what);
  if (!std::filesystem::is_regular_file(st))
    throw FileError(path, std::string("is not a regular file (a device, FIFO or socket), not ") + what);
}

}  // namespace

void report_image_warnings(const std::string& what, const std::string& warnings) {
  if (warnings.empty()) return;
  static std::mutex mutex;
  static std::set<std::string> said;
  std::lock_guard<std::mutex> lock(mutex);
  size_t start = 0;
  while (start < warnings.size()) {
    size_t end = std::min(warnings.find('\n', start), warnings.size());
    std::string line = warnings.substr(start, end - start);
    start = end + 1;
    if (line.empty() || said.size() > 10000 || !said.insert(what + '\n' + line).second) continue;
    std::fprintf(stderr, "synthgen: warning: %s: %s (a metadata warning of the decoder: the pixels are intact)\n",
                 what.c_str(), line.c_str());
  }
}

static void check_finite(const ImageData& img, const std::string& what) {
  for (float v : img.pixels)
    if (!std::isfinite(v))
      throw FileError(what, "image contains non-finite pixel values (NaN or infinity), which textures and "
                            "environment maps cannot hold");
}

ImageData load_image_in_process(const std::string& path, ColorSpace space, bool allow_nonfinite) {
  check_regular_file(path, "an image");
  ImageData img;
  std::string err;
  if (!api().load(path.c_str(), int(space), &img, &err)) throw FileError(path, err);
  if (!allow_nonfinite) check_finite(img, path);
  return img;
}

void write_image_data(Writer& w, const ImageData& image) {
  w.pod(int32_t(image.width));
  w.pod(int32_t(image.height));
  w.pod(int32_t(image.channels));
  w.vec(image.pixels);
  w.str(image.format);
  w.pod(int32_t(image.orientation));
  w.pod(image.exif_focal_mm);
  w.pod(image.exif_focal_35mm);
  w.str(image.warnings);
}

ImageData read_image_data(Reader& r, const std::string& what) {
  ImageData img;
  img.width = r.pod<int32_t>();
  img.height = r.pod<int32_t>();
  img.channels = r.pod<int32_t>();
  img.pixels = r.vec<float>();
  img.format = r.str();
  img.orientation = r.pod<int32_t>();
  img.exif_focal_mm = r.pod<float>();
  img.exif_focal_35mm = r.pod<float>();
  img.warnings = r.str();
  if (img.orientation < 1 || img.orientation > 8 || !std::isfinite(img.exif_focal_mm) ||
      !std::isfinite(img.exif_focal_35mm))
    throw FileError(what, "malformed image from the isolated reader (its EXIF fields)");
  if (img.width < 0 || img.height < 0 || img.channels < 0 ||
      img.pixels.size() != size_t(img.width) * size_t(img.height) * size_t(img.channels))
    throw FileError(what, "malformed image from the isolated reader");
  return img;
}

std::vector<char> load_image_bytes(const std::string& path, ColorSpace space, bool allow_nonfinite) {
  Writer w;
  write_image_data(w, load_image_in_process(path, space, allow_nonfinite));
  return std::move(w.bytes);
}

ImageData load_image(const std::string& path, ColorSpace space, bool allow_nonfinite) {
  check_regular_file(path, "an image");
  const char* names[] = {"auto", "srgb", "linear"};
  Bytes bytes = read_isolated(path, {"image", path, names[int(space)], allow_nonfinite ? "nonfinite" : "finite"},
                              [&] { return load_image_bytes(path, space, allow_nonfinite); });
  Reader r(bytes, path);
  ImageData img = read_image_data(r, path);
  if (!r.done()) throw FileError(path, "malformed image from the isolated reader (trailing data)");
  report_image_warnings(path, img.warnings);
  return img;
}

ImageData load_image_from_memory(const void* data, size_t size, const std::string& format_hint,
                                 const std::string& what) {
  ImageData img;
  std::string err;
  if (!api().load_memory(data, size, format_hint.c_str(), &img, &err)) throw FileError(what, err);
  check_finite(img, what);
  report_image_warnings(what, img.warnings);
  return img;
}

void save_image(const std::string& path, const ImageData& image, int bits) {
  std::string err;
  if (!api().save(path.c_str(), &image, bits, &err)) throw FileError(path, err);
}

void save_mip_file(const std::string& path, const std::vector<ImageData>& levels, const std::vector<float>& average) {
  std::string err;
  if (!api().save_mip(path.c_str(), levels.data(), int(levels.size()), average.data(), int(average.size()), &err))
    throw FileError(path, err);
}

MipFileHeader load_mip_file(const std::string& path, int first, int count, std::vector<ImageData>* levels,
                            int chbegin, int chend) {
  MipFileHeader h;
  std::vector<ImageData> tmp;
  std::string err;
  if (!api().load_mip(path.c_str(), first, count, chbegin, chend, &h, levels ? levels : &tmp, &err))
    throw FileError(path, err);
  return h;
}

std::vector<std::vector<float>> load_mip_rects(const std::string& path, int level, const std::vector<TexelRect>& rects,
                                               int chbegin, int chend) {
  std::vector<std::vector<float>> out;
  std::string err;
  if (!api().load_mip_rects(path.c_str(), level, rects.data(), int(rects.size()), chbegin, chend, &out, &err))
    throw FileError(path, err);
  return out;
}

}  // namespace sg
