// The OpenImageIO plugin (libsynthgen_oiio.so); see image_io.h.
#include "io/image_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cmath>

namespace {

using sg::ImageData;

float srgb_to_linear(float c) {
  // NOTE: IEC 61966-2-1 sRGB electro-optical transfer function.
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

bool read_all(OIIO::ImageInput* in, ImageData* img, bool* is_float, int* alpha_channel, std::string* error) {
  const OIIO::ImageSpec& spec = in->spec();
  img->width = spec.width;
  img->height = spec.height;
  img->channels = spec.nchannels;
  if (img->width <= 0 || img->height <= 0 || img->channels <= 0) {
    *error = "image has no pixels";
    return false;
  }
  img->pixels.resize(size_t(img->width) * img->height * img->channels);
  if (!in->read_image(0, 0, 0, img->channels, OIIO::TypeDesc::FLOAT, img->pixels.data())) {
    *error = "cannot decode image (" + in->geterror() + ")";
    return false;
  }
  *is_float = spec.format.basetype == OIIO::TypeDesc::FLOAT || spec.format.basetype == OIIO::TypeDesc::HALF ||
              spec.format.basetype == OIIO::TypeDesc::DOUBLE;
  *alpha_channel = spec.alpha_channel;
  for (float v : img->pixels)
    if (!std::isfinite(v)) {
      *error = "image contains non-finite pixel values";
      return false;
    }
  return true;
}

bool load(const char* path, int space, ImageData* img, std::string* error) {
  try {
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
      std::string err = OIIO::geterror();
      *error = "cannot read image (" + (err.empty() ? std::string("unknown error") : err) + ")";
      return false;
    }
    bool is_float;
    int alpha;
    if (!read_all(in.get(), img, &is_float, &alpha, error)) return false;
    auto cs = sg::ColorSpace(space);
    bool decode = cs == sg::ColorSpace::SRGB || (cs == sg::ColorSpace::Auto && !is_float);
    if (decode) {
      int colour_channels = std::min(img->channels, 3);
      if (alpha >= 0 && alpha < colour_channels) colour_channels = alpha;
      for (size_t p = 0; p < size_t(img->width) * img->height; ++p)
        for (int c = 0; c < colour_channels; ++c) {
          float& v = img->pixels[p * img->channels + c];
          v = srgb_to_linear(v);
        }
    }
    return true;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}

bool load_memory(const void* data, size_t size, const char* hint, ImageData* img, std::string* error) {
  try {
    OIIO::Filesystem::IOMemReader reader(data, size);
    OIIO::ImageSpec config;
    // NOTE: OIIO 2.4's format readers pick the proxy up from the "oiio:ioproxy" config
    // attribute; the ioproxy argument of ImageInput::open alone does not reach them.
    void* proxy = &reader;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    auto in = OIIO::ImageInput::open(std::string("embedded.") + hint, &config, &reader);
    if (!in) {
      *error = "cannot decode embedded image (" + OIIO::geterror() + ")";
      return false;
    }
    bool is_float;
    int alpha;
    return read_all(in.get(), img, &is_float, &alpha, error);
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}

bool save(const char* path, const ImageData* image, int bits, std::string* error) {
  try {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) {
      *error = "no image writer for this file extension (" + OIIO::geterror() + ")";
      return false;
    }
    OIIO::TypeDesc fmt = bits == 8 ? OIIO::TypeDesc::UINT8 : bits == 16 ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::FLOAT;
    OIIO::ImageSpec spec(image->width, image->height, image->channels, fmt);
    if (!out->open(path, spec)) {
      *error = "cannot open for writing (" + out->geterror() + ")";
      return false;
    }
    if (!out->write_image(OIIO::TypeDesc::FLOAT, image->pixels.data())) {
      *error = "cannot write image (" + out->geterror() + ")";
      return false;
    }
    out->close();
    return true;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}

const sg::ImageIoApi k_api = {sg::k_image_io_api_version, &load, &load_memory, &save};

}  // namespace

extern "C" __attribute__((visibility("default"))) const sg::ImageIoApi* synthgen_image_io_api() { return &k_api; }
