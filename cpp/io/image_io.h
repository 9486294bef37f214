// Image reading and writing through OpenImageIO (the only file using its API: image_io.cpp).
#pragma once

#include <string>
#include <vector>

namespace sg {

enum class ColorSpace { Auto, SRGB, Linear };

/// Float pixels, row-major, top row first, `channels` interleaved values per pixel.
struct ImageData {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;
};

/// Reads an image. With ColorSpace::Auto, 8/16-bit integer formats (PNG, JPEG, TIFF)
/// are treated as sRGB-encoded and decoded to linear; float formats (EXR, HDR) as linear.
/// Throws sg::FileError naming the file on failure.
ImageData load_image(const std::string& path, ColorSpace space);

/// Writes float pixels; 8/16-bit formats are chosen by `bits` (0 = float).
void save_image(const std::string& path, const ImageData& image, int bits);

}  // namespace sg
