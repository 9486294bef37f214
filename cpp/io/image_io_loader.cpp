// Loads the OpenImageIO plugin (libsynthgen_oiio.so) on first use; see image_io.h.
#include <dlfcn.h>

#include <filesystem>
#include <mutex>

#include "core/error.h"
#include "io/image_io.h"

namespace sg {

namespace {

const ImageIoApi* g_api = nullptr;
std::string g_load_error;

void load_plugin() {
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("SYNTHGEN_IMAGE_IO_PLUGIN")) candidates.push_back(env);
  Dl_info info;
  if (dladdr(reinterpret_cast<void*>(&load_plugin), &info) && info.dli_fname) {
    std::filesystem::path here = std::filesystem::path(info.dli_fname).parent_path();
    candidates.push_back((here / "libsynthgen_oiio.so").string());
  }
  candidates.push_back("libsynthgen_oiio.so");  // LD_LIBRARY_PATH / system
  std::string errors;
  for (const auto& c : candidates) {
    void* handle = dlopen(c.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* e = dlerror();
      errors += "\n  " + c + ": " + (e ? e : "unknown error");
      continue;
    }
    auto fn = reinterpret_cast<const ImageIoApi* (*)()>(dlsym(handle, "synthgen_image_io_api"));
    const ImageIoApi* api = fn ? fn() : nullptr;
    if (api && api->version == k_image_io_api_version) {
      g_api = api;
      return;
    }
    errors += "\n  " + c + ": not a compatible synthgen image plugin";
  }
  g_load_error = "cannot load the OpenImageIO plugin libsynthgen_oiio.so:" + errors;
}

const ImageIoApi& api() {
  static std::once_flag once;
  std::call_once(once, load_plugin);
  if (!g_api) throw Error(g_load_error);
  return *g_api;
}

}  // namespace

void load_image_plugin() { api(); }

ImageData load_image(const std::string& path, ColorSpace space) {
  ImageData img;
  std::string err;
  if (!api().load(path.c_str(), int(space), &img, &err)) throw FileError(path, err);
  return img;
}

ImageData load_image_from_memory(const void* data, size_t size, const std::string& format_hint,
                                 const std::string& what) {
  ImageData img;
  std::string err;
  if (!api().load_memory(data, size, format_hint.c_str(), &img, &err)) throw FileError(what, err);
  return img;
}

void save_image(const std::string& path, const ImageData& image, int bits) {
  std::string err;
  if (!api().save(path.c_str(), &image, bits, &err)) throw FileError(path, err);
}

}  // namespace sg
