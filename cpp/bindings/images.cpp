// Python bindings of image reading (through the isolated reader, io/image_io.h).
#include <algorithm>
#include <cstring>

#include "bindings/convert.h"
#include "io/image_io.h"

namespace sg::bindings {

namespace {

/// Reads `path` with the GIL released; `function` names the caller in errors.
ImageData read(const std::string& path, const std::string& color_space, bool finite, const char* function) {
  ColorSpace space = color_space == "auto"     ? ColorSpace::Auto
                     : color_space == "srgb"   ? ColorSpace::SRGB
                     : color_space == "linear" ? ColorSpace::Linear
                                               : throw Error(std::string(function) + ": color_space must be 'auto', "
                                                             "'srgb' or 'linear', got '" + color_space + "'");
  py::gil_scoped_release release;
  return load_image(path, space, !finite);
}

py::array_t<float> pixels(const ImageData& img) {
  py::array_t<float> out({py::ssize_t(img.height), py::ssize_t(img.width), py::ssize_t(img.channels)});
  std::memcpy(out.mutable_data(), img.pixels.data(), img.pixels.size() * sizeof(float));
  return out;
}

}  // namespace

void bind_images(py::module_& m) {
  m.def(
      "read_image",
      [](const std::string& path, const std::string& color_space, bool finite) {
        return pixels(read(path, color_space, finite, "read_image"));
      },
      py::arg("path"), py::arg("color_space") = "auto", py::arg("finite") = true,
      "An image file as a float32 H x W x C array of linear values: 8- and 16-bit files (PNG, JPEG,\n"
      "TIFF) are sRGB-decoded unless color_space='linear'; float files (EXR, HDR) are kept; values\n"
      "must be finite unless finite=False (a depth map's +inf background). The file\n"
      "is decoded by synthgen-reader, a separate process with time and memory limits, so a corrupt\n"
      "or hostile file raises FileError naming it instead of crashing the caller.");

  m.def(
      "read_image_info",
      [](const std::string& path, const std::string& color_space) {
        ImageData img = read(path, color_space, true, "read_image_info");
        py::dict info;
        info["format"] = img.format;
        info["orientation"] = img.orientation;
        info["exif_focal_mm"] = img.exif_focal_mm;
        info["exif_focal_35mm"] = img.exif_focal_35mm;
        py::list warnings;
        for (size_t a = 0; a < img.warnings.size();) {
          size_t b = std::min(img.warnings.find('\n', a), img.warnings.size());
          if (b > a) warnings.append(img.warnings.substr(a, b - a));
          a = b + 1;
        }
        info["warnings"] = warnings;
        return py::make_tuple(pixels(img), info);
      },
      py::arg("path"), py::arg("color_space") = "auto",
      "read_image (finite values) and what the file says about itself: (pixels, {format, orientation:\n"
      "EXIF 1..8, not applied to the pixels; exif_focal_mm, exif_focal_35mm: 0 when absent; warnings:\n"
      "the decoder's harmless metadata warnings, also printed once to stderr}). A decoder's report of\n"
      "damage (a truncated or corrupt file) raises FileError even where the decoder returned pixels.");
}

}  // namespace sg::bindings
