// Fuzz target: a photo read as synthgen reads users' photos (background.photos, calibrate):
// the file decoded with the colour conversion of load_image, its result written as the bytes
// synthgen-reader sends and read back as the parent checks them (io/image_io.h), and the
// damage rules of io/decoder_messages.h. The first byte picks the format (jpg, png, exr, tif,
// bmp, hdr). Seeds (tools/make_fuzz_seeds.py) are truncated and corrupted JPEG, PNG and EXR
// files. Beyond crashes it checks that a JPEG accepted as intact has a whole structure (its
// end-of-image marker is reached) and that an accepted image's pixels are all there.
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "core/isolate.h"
#include "fuzz_util.h"
#include "io/decoder_messages.h"
#include "io/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* k_ext[] = {"jpg", "png", "exr", "tif", "bmp", "hdr"};
  const char* ext = k_ext[data[0] % 6];
  std::string path = fuzz::write_file(std::string("photo.") + ext, data + 1, size - 1);
  try {
    const std::vector<char> bytes = sg::load_image_bytes(path, sg::ColorSpace::Auto);
    sg::Reader r(bytes, path);
    sg::ImageData img = sg::read_image_data(r, path);
    if (!r.done()) std::abort();  // the protocol's own output must parse exactly
    if (img.width <= 0 || img.height <= 0 || img.channels <= 0 ||
        img.pixels.size() != size_t(img.width) * img.height * img.channels)
      std::abort();
    if (img.format == "jpeg" && !sg::jpeg_structure_damage(data + 1, size - 1).empty()) std::abort();
  } catch (const sg::Error&) {
  }
  return 0;
}
