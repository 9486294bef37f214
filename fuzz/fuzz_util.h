// Shared by the fuzz targets: files are read in this process with a smaller image limit, a
// private temporary directory (also their $SYNTHGEN_CACHE), writing bytes to a file.
//
// NOTE: SYNTHGEN_NO_ISOLATION: synthgen reads untrusted files in synthgen-reader, a separate
// process (core/isolate.h); the targets read them here instead, so that the sanitizers see
// our code around assimp and OpenImageIO, and a loop is a libFuzzer timeout.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace fuzz {

#ifndef SG_FUZZ_ISOLATED
inline const int k_in_process = setenv("SYNTHGEN_NO_ISOLATION", "1", 1);
#endif
// Images of at most 4096^2 pixels (synthgen's own limit is 16384^2, 4 GiB of floats): the
// same checks, within libFuzzer's 2 GiB memory limit.
inline const int k_max_pixels = setenv("SYNTHGEN_MAX_IMAGE_PIXELS", "16777216", 1);

/// A directory of this process's own, created once.
inline const std::string& temp_dir() {
  static const std::string dir = [] {
    std::string d = (std::filesystem::temp_directory_path() / ("synthgen-fuzz-" + std::to_string(getpid()))).string();
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

// Files a journal embeds are written to the resource store ($SYNTHGEN_CACHE/resources): the
// process's own directory, not the user's cache.
inline const int k_cache = setenv("SYNTHGEN_CACHE", (temp_dir() + "/cache").c_str(), 1);

inline std::string write_file(const std::string& name, const uint8_t* data, size_t size) {
  std::string path = temp_dir() + "/" + name;
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  return path;
}

/// Writes an input "XML[\0BIN\0SIDECAR]" as the files `name` and `name`.bin (empty without
/// the separator); returns the XML file's path.
inline std::string write_with_sidecar(const std::string& name, const uint8_t* data, size_t size) {
  static const char k_sep[] = "\0BIN\0";
  const uint8_t* sep = nullptr;
  for (size_t i = 0; i + 5 <= size; ++i)
    if (std::memcmp(data + i, k_sep, 5) == 0) {
      sep = data + i;
      break;
    }
  const size_t xml_size = sep ? size_t(sep - data) : size;
  std::string path = write_file(name, data, xml_size);
  const uint8_t* bin = sep ? sep + 5 : data + size;
  write_file(name + ".bin", bin, size_t(data + size - bin));
  return path;
}

}  // namespace fuzz
