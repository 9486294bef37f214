#include "io/image_io.h"

#include <OpenImageIO/imageio.h>

#include <cmath>

#include "core/error.h"

namespace sg {

static float srgb_to_linear(float c) {
  // NOTE: IEC 61966-2-1 sRGB electro-optical transfer function.
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

ImageData load_image(const std::string& path, ColorSpace space) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    std::string err = OIIO::geterror();
    throw FileError(path, "cannot read image (" + (err.empty() ? std::string("unknown error") : err) + ")");
  }
  const OIIO::ImageSpec& spec = in->spec();
  ImageData img;
  img.width = spec.width;
  img.height = spec.height;
  img.channels = spec.nchannels;
  if (img.width <= 0 || img.height <= 0 || img.channels <= 0)
    throw FileError(path, "image has no pixels");
  img.pixels.resize(size_t(img.width) * img.height * img.channels);
  if (!in->read_image(0, 0, 0, img.channels, OIIO::TypeDesc::FLOAT, img.pixels.data())) {
    std::string err = in->geterror();
    throw FileError(path, "cannot decode image (" + err + ")");
  }
  bool is_float = spec.format.basetype == OIIO::TypeDesc::FLOAT || spec.format.basetype == OIIO::TypeDesc::HALF ||
                  spec.format.basetype == OIIO::TypeDesc::DOUBLE;
  bool decode = space == ColorSpace::SRGB || (space == ColorSpace::Auto && !is_float);
  if (decode) {
    int colour_channels = std::min(img.channels, 3);
    if (spec.alpha_channel >= 0 && spec.alpha_channel < colour_channels) colour_channels = spec.alpha_channel;
    for (size_t p = 0; p < size_t(img.width) * img.height; ++p)
      for (int c = 0; c < colour_channels; ++c) {
        float& v = img.pixels[p * img.channels + c];
        v = srgb_to_linear(v);
      }
  }
  for (float v : img.pixels)
    if (!std::isfinite(v)) throw FileError(path, "image contains non-finite pixel values");
  return img;
}

void save_image(const std::string& path, const ImageData& image, int bits) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw FileError(path, "no image writer for this file extension (" + OIIO::geterror() + ")");
  OIIO::TypeDesc fmt = bits == 8 ? OIIO::TypeDesc::UINT8 : bits == 16 ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::FLOAT;
  OIIO::ImageSpec spec(image.width, image.height, image.channels, fmt);
  if (!out->open(path, spec)) throw FileError(path, "cannot open for writing (" + out->geterror() + ")");
  if (!out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data()))
    throw FileError(path, "cannot write image (" + out->geterror() + ")");
  out->close();
}

}  // namespace sg
