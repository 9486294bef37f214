// The OpenImageIO plugin (libsynthgen_oiio.so); see image_io.h.
#include "io/image_io.h"

#include "io/decoder_messages.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <mutex>
#include <string>

namespace {

using sg::ImageData;

/// The largest image synthgen decodes: 16384^2 pixels (268 Mpixel) and 4 values per pixel on
/// average (4 GiB of floats); larger headers are refused before any allocation (a corrupt or
/// hostile file cannot ask for more). $SYNTHGEN_MAX_IMAGE_PIXELS lowers the pixel limit (the
/// fuzz targets run under a 2 GiB memory limit).
double max_pixels() {
  static const double v = [] {
    const char* e = std::getenv("SYNTHGEN_MAX_IMAGE_PIXELS");
    double d = e ? std::strtod(e, nullptr) : 0.0;
    return d >= 1.0 && d < double(1 << 28) ? d : double(1 << 28);
  }();
  return v;
}

/// Captures what format libraries (libpng, libjpeg) print to stderr while it lives, so their
/// messages never reach the user's terminal unexplained: they are judged with the decoder's own
/// (io/decoder_messages.h) and become the read's error or its warnings.
/// NOTE: fd 2 is process-wide: reads are serialised while it is redirected.
class StderrCapture {
 public:
  StderrCapture() : m_lock(mutex()) {
    std::fflush(stderr);
    m_file = std::tmpfile();
    m_saved = dup(2);
    if (m_file && m_saved >= 0) m_active = dup2(fileno(m_file), 2) >= 0;
  }
  ~StderrCapture() { restore(); if (m_file) std::fclose(m_file); }
  /// Restores stderr; returns what was printed (lines, at most 4 kB).
  std::string restore() {
    if (!m_active) return m_text;
    std::fflush(stderr);
    dup2(m_saved, 2);
    close(m_saved);
    m_active = false;
    std::rewind(m_file);
    char buf[512];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, m_file)) > 0 && m_text.size() < 4096) m_text.append(buf, n);
    return m_text;
  }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> m_lock;
  std::FILE* m_file = nullptr;
  int m_saved = -1;
  bool m_active = false;
  std::string m_text;
};

/// One line: format libraries' errors come with newlines (empty lines dropped, "; " between).
std::string one_line(const std::string& s) {
  std::string out, line;
  auto flush = [&] {
    while (!line.empty() && (line.back() == ';' || line.back() == ' ' || line.back() == '\r')) line.pop_back();
    size_t a = line.find_first_not_of(' ');
    if (a != std::string::npos) out += (out.empty() ? "" : "; ") + line.substr(a);
    line.clear();
  };
  for (char c : s) {
    if (c == '\n') flush();
    else line += c;
  }
  flush();
  return out;
}

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
  const double pixels = double(img->width) * img->height;
  if (pixels > max_pixels() || img->channels > 64 || pixels * img->channels > 4.0 * max_pixels()) {
    *error = "image of " + std::to_string(img->width) + " x " + std::to_string(img->height) + " pixels x " +
             std::to_string(img->channels) + " channels is larger than synthgen reads (at most " +
             std::to_string((unsigned long long)max_pixels()) + " pixels (16384 x 16384), 4 values per pixel on "
             "average, 64 channels)";
    return false;
  }
  img->pixels.resize(size_t(img->width) * img->height * img->channels);
  // One thread: synthgen parallelizes across frames and files (core/isolate.h readers).
  in->threads(1);
  if (!in->read_image(0, 0, 0, img->channels, OIIO::TypeDesc::FLOAT, img->pixels.data())) {
    *error = "cannot decode image (" + one_line(in->geterror()) + ")";
    return false;
  }
  // A read that succeeded may still have been told of damage (libjpeg's "Premature end of JPEG
  // file" fills the missing rows with grey): judged by finish_read with the captured stderr.
  img->warnings = in->geterror();
  *is_float = spec.format.basetype == OIIO::TypeDesc::FLOAT || spec.format.basetype == OIIO::TypeDesc::HALF ||
              spec.format.basetype == OIIO::TypeDesc::DOUBLE;
  *alpha_channel = spec.alpha_channel;
  img->format = in->format_name();
  int orientation = spec.get_int_attribute("Orientation", 1);
  img->orientation = orientation >= 1 && orientation <= 8 ? orientation : 1;
  auto positive = [](float f) { return std::isfinite(f) && f > 0.f && f < 1e5f ? f : 0.f; };
  img->exif_focal_mm = positive(spec.get_float_attribute("Exif:FocalLength", 0.f));
  img->exif_focal_35mm = positive(spec.get_float_attribute("Exif:FocalLengthIn35mmFilm", 0.f));
  return true;  // non-finite values are checked by the core where they are not allowed
}

/// The bytes of `path` (a JPEG to check: io/decoder_messages.h).
bool read_file(const char* path, std::vector<unsigned char>* out, std::string* error) {
  std::FILE* f = std::fopen(path, "rb");
  if (!f) {
    *error = "cannot open the file again to check its structure";
    return false;
  }
  unsigned char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) out->insert(out->end(), buf, buf + n);
  const bool ok = !std::ferror(f);
  std::fclose(f);
  if (!ok) *error = "cannot read the file again to check its structure";
  return ok;
}

/// After read_all: the decoder's messages (in img->warnings) and what the format libraries
/// printed (`printed`) judged (io/decoder_messages.h), and a JPEG's structure (`jpeg`: its
/// bytes, else null): damage fails the read, harmless metadata warnings stay in img->warnings
/// (one line each).
bool finish_read(ImageData* img, const std::string& printed, const std::vector<unsigned char>* jpeg,
                 std::string* error) {
  sg::DecoderVerdict v = sg::classify_decoder_messages(img->warnings + "\n" + OIIO::geterror() + "\n" + printed);
  img->warnings.clear();
  if (jpeg) {
    std::string structure = sg::jpeg_structure_damage(jpeg->data(), jpeg->size());
    if (!structure.empty()) v.damage.push_back("JPEG structure: " + structure);
  }
  if (!v.damage.empty()) {
    *error = "damaged or truncated image: the decoder reported '" + sg::join_messages(v.damage) +
             "' (the pixels it returned are not the file's picture)";
    img->pixels.clear();
    return false;
  }
  for (const std::string& w : v.harmless) img->warnings += (img->warnings.empty() ? "" : "\n") + w;
  return true;
}

bool load(const char* path, int space, ImageData* img, std::string* error) {
  try {
    StderrCapture quiet;
    (void)OIIO::geterror();  // a message left by an earlier file is not this one's
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
      std::string err = one_line(OIIO::geterror() + "\n" + quiet.restore());
      *error = "cannot read image (" + (err.empty() ? std::string("unknown error") : err) + ")";
      return false;
    }
    bool is_float;
    int alpha;
    if (!read_all(in.get(), img, &is_float, &alpha, error)) {
      std::string printed = one_line(quiet.restore());
      if (!printed.empty() && error->find(printed) == std::string::npos) *error += " [" + printed + "]";
      return false;
    }
    in->close();
    img->warnings += "\n" + in->geterror();
    std::vector<unsigned char> jpeg;
    if (img->format == "jpeg" && !read_file(path, &jpeg, error)) return false;
    if (!finish_read(img, quiet.restore(), img->format == "jpeg" ? &jpeg : nullptr, error)) return false;
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
  } catch (const std::bad_alloc&) {
    *error = "out of memory while decoding the image";
    return false;
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
    StderrCapture quiet;
    (void)OIIO::geterror();  // a message left by an earlier file is not this one's
    auto in = OIIO::ImageInput::open(std::string("embedded.") + hint, &config, &reader);
    if (!in) {
      *error = "cannot decode embedded image (" + one_line(OIIO::geterror()) + ")";
      return false;
    }
    bool is_float;
    int alpha;
    if (!read_all(in.get(), img, &is_float, &alpha, error)) return false;
    in->close();
    img->warnings += "\n" + in->geterror();
    std::vector<unsigned char> jpeg;
    if (img->format == "jpeg") jpeg.assign(static_cast<const unsigned char*>(data), static_cast<const unsigned char*>(data) + size);
    return finish_read(img, quiet.restore(), img->format == "jpeg" ? &jpeg : nullptr, error);
  } catch (const std::bad_alloc&) {
    *error = "out of memory while decoding the image";
    return false;
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
  } catch (const std::bad_alloc&) {
    *error = "out of memory while decoding the image";
    return false;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}

/// The file's attribute naming the format (a file that lacks it is not a synthgen mip file).
constexpr const char* k_mip_tag = "synthgen:mipfile";

bool save_mip(const char* path, const ImageData* levels, int count, const float* average, int average_count,
              std::string* error) {
  try {
    if (count < 1) {
      *error = "no levels to write";
      return false;
    }
    auto out = OIIO::ImageOutput::create(path);
    if (!out || !out->supports("mipmap") || !out->supports("tiles")) {
      *error = "no tiled, mip-mapped image writer for this file extension";
      return false;
    }
    OIIO::ImageSpec spec(levels[0].width, levels[0].height, levels[0].channels, OIIO::TypeDesc::FLOAT);
    spec.tile_width = spec.tile_height = 64;
    spec.attribute("compression", "zip");
    spec.attribute("textureformat", "Plain Texture");
    spec.attribute("openexr:levelmode", 1);     // MIPMAP_LEVELS
    spec.attribute("openexr:roundingmode", 0);  // ROUND_DOWN: halve, rounding down
    spec.attribute(k_mip_tag, 1);
    spec.attribute("synthgen:average", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, average_count), average);
    if (!out->open(path, spec, OIIO::ImageOutput::Create)) {
      *error = "cannot open for writing (" + out->geterror() + ")";
      return false;
    }
    for (int l = 0; l < count; ++l) {
      if (l > 0) {
        OIIO::ImageSpec ls = spec;
        ls.width = ls.full_width = levels[l].width;
        ls.height = ls.full_height = levels[l].height;
        if (!out->open(path, ls, OIIO::ImageOutput::AppendMIPLevel)) {
          *error = "cannot add mip level " + std::to_string(l) + " (" + out->geterror() + ")";
          return false;
        }
      }
      if (!out->write_image(OIIO::TypeDesc::FLOAT, levels[l].pixels.data())) {
        *error = "cannot write mip level " + std::to_string(l) + " (" + out->geterror() + ")";
        return false;
      }
    }
    if (!out->close()) {
      *error = "cannot finish the file (" + out->geterror() + ")";
      return false;
    }
    return true;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}

/// Opens a file written by save_mip (null with `error` set when it cannot be opened or is not
/// such a file).
std::unique_ptr<OIIO::ImageInput> open_mip(const char* path, std::string* error) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    *error = "cannot open (" + OIIO::geterror() + ")";
    return nullptr;
  }
  if (in->spec().get_int_attribute(k_mip_tag, 0) != 1) {
    *error = "not a synthgen mip file";
    return nullptr;
  }
  return in;
}

bool load_mip(const char* path, int first, int count, int chbegin, int chend, sg::MipFileHeader* header,
              std::vector<ImageData>* levels, std::string* error) {
  try {
    auto in = open_mip(path, error);
    if (!in) return false;
    const OIIO::ImageSpec& spec0 = in->spec();
    header->channels = spec0.nchannels;
    header->widths.clear();
    header->heights.clear();
    for (int l = 0; in->seek_subimage(0, l); ++l) {
      header->widths.push_back(in->spec().width);
      header->heights.push_back(in->spec().height);
    }
    const OIIO::ParamValue* avg = spec0.find_attribute("synthgen:average");
    header->average.clear();
    if (avg && avg->type().basetype == OIIO::TypeDesc::FLOAT)
      for (int i = 0; i < int(avg->type().basevalues()) && i < 4; ++i)
        header->average.push_back(static_cast<const float*>(avg->data())[i]);
    if (header->channels < 1 || header->channels > 4 || header->widths.empty()) {
      *error = "malformed mip file header";
      return false;
    }
    levels->clear();
    if (chend < 0) chend = header->channels;
    if (count > 0 && (chbegin < 0 || chbegin >= chend || chend > header->channels)) {
      *error = "no channels " + std::to_string(chbegin) + " to " + std::to_string(chend);
      return false;
    }
    for (int l = first; l < first + count; ++l) {
      if (l < 0 || l >= int(header->widths.size()) || !in->seek_subimage(0, l)) {
        *error = "no mip level " + std::to_string(l);
        return false;
      }
      ImageData img;
      img.width = in->spec().width;
      img.height = in->spec().height;
      img.channels = chend - chbegin;
      img.pixels.resize(size_t(img.width) * img.height * img.channels);
      if (!in->read_image(0, l, chbegin, chend, OIIO::TypeDesc::FLOAT, img.pixels.data())) {
        *error = "cannot read mip level " + std::to_string(l) + " (" + in->geterror() + ")";
        return false;
      }
      levels->push_back(std::move(img));
    }
    return true;
  } catch (const std::bad_alloc&) {
    *error = "out of memory while reading the file";
    return false;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}

bool load_mip_rects(const char* path, int level, const sg::TexelRect* rects, int count, int chbegin, int chend,
                    std::vector<std::vector<float>>* out, std::string* error) {
  try {
    auto in = open_mip(path, error);
    if (!in) return false;
    if (!in->seek_subimage(0, level)) {
      *error = "no mip level " + std::to_string(level);
      return false;
    }
    const OIIO::ImageSpec& spec = in->spec();
    if (chbegin < 0 || chbegin >= chend || chend > spec.nchannels) {
      *error = "no channels " + std::to_string(chbegin) + " to " + std::to_string(chend);
      return false;
    }
    out->clear();
    for (int i = 0; i < count; ++i) {
      const sg::TexelRect& r = rects[i];
      if (r.x0 < 0 || r.y0 < 0 || r.x1 > spec.width || r.y1 > spec.height || r.x0 >= r.x1 || r.y0 >= r.y1) {
        *error = "texel rectangle outside mip level " + std::to_string(level);
        return false;
      }
      std::vector<float> px(size_t(r.x1 - r.x0) * size_t(r.y1 - r.y0) * size_t(chend - chbegin));
      // NOTE: on tile boundaries (and the image's edges) read_tiles decodes exactly the tiles
      // of the rectangle (OpenImageIO ImageInput::read_tiles); other rectangles are refused.
      const bool aligned = spec.tile_width > 0 && r.x0 % spec.tile_width == 0 && r.y0 % spec.tile_height == 0 &&
                           (r.x1 % spec.tile_width == 0 || r.x1 == spec.width) &&
                           (r.y1 % spec.tile_height == 0 || r.y1 == spec.height);
      if (!aligned) {
        *error = "texel rectangle not on the file's tiles";
        return false;
      }
      if (!in->read_tiles(0, level, r.x0, r.x1, r.y0, r.y1, 0, 1, chbegin, chend, OIIO::TypeDesc::FLOAT, px.data())) {
        *error = "cannot read tiles of mip level " + std::to_string(level) + " (" + in->geterror() + ")";
        return false;
      }
      out->push_back(std::move(px));
    }
    return true;
  } catch (const std::bad_alloc&) {
    *error = "out of memory while reading the file";
    return false;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}

const sg::ImageIoApi k_api = {sg::k_image_io_api_version, &load, &load_memory, &save, &save_mip, &load_mip,
                              &load_mip_rects};

}  // namespace

extern "C" __attribute__((visibility("default"))) const sg::ImageIoApi* synthgen_image_io_api() { return &k_api; }
