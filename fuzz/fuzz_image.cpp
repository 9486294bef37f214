// Fuzz target: image loading (io/image_io.cpp through OpenImageIO: files with the colour
// conversion of load_image, or memory as for embedded textures; then our mip-map pyramid
// and filtered lookups). The first byte picks the format (png, jpg, exr, hdr, tga, bmp) and,
// in its high bit, file or memory. The decoding runs in this process so that the sanitizers
// see our code; in synthgen load_image runs it in synthgen-reader (core/isolate.h).
// OpenImageIO and the format libraries are uninstrumented: we fuzz our code around them.
#include <string>

#include "core/error.h"
#include "fuzz_util.h"
#include "io/image_io.h"
#include "texture/mipmap.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* k_hint[] = {"png", "jpg", "exr", "hdr", "tga", "bmp"};
  const char* hint = k_hint[(data[0] & 0x7f) % 6];
  try {
    sg::ImageData img;
    if (data[0] & 0x80) {
      std::string path = fuzz::write_file(std::string("image.") + hint, data + 1, size - 1);
      img = sg::load_image_in_process(path, sg::ColorSpace::Auto);
    } else {
      img = sg::load_image_from_memory(data + 1, size - 1, hint, "fuzz");
    }
    sg::MipMap mip(img);
    for (float u : {0.f, 0.3f, 0.99f})
      for (float w : {0.f, 0.01f, 0.5f}) mip.lookup(u, 1.f - u, w, sg::WrapMode::Repeat);
  } catch (const sg::Error&) {
  }
  return 0;
}
