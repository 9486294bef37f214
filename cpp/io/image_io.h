// Image reading and writing through OpenImageIO.
//
// OpenImageIO and its ~260 shared-library dependencies take a quarter of a second to
// load, so they are not linked into the core: image_io.cpp (the only file using the
// OIIO API) is built as the plugin `libsynthgen_oiio.so`, which image_io_loader.cpp
// opens with dlopen on the first image read or write. Scenes without image files
// never pay for it.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace sg {

enum class ColorSpace { Auto = 0, SRGB = 1, Linear = 2 };

/// Float pixels, row-major, top row first, `channels` interleaved values per pixel.
struct ImageData {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;
  // What the file says about itself (files read by load_image; empty / defaults otherwise).
  std::string format;          ///< OpenImageIO's format name ("jpeg", "png", "openexr", ...)
  int orientation = 1;         ///< EXIF orientation 1..8 (not applied to `pixels`)
  float exif_focal_mm = 0.f;   ///< EXIF FocalLength, millimetres (0: absent)
  float exif_focal_35mm = 0.f; ///< EXIF FocalLengthIn35mmFilm, millimetres (0: absent)
  /// The decoder's harmless metadata warnings, one a line (io/decoder_messages.h); a decoder's
  /// report of damage fails the read instead.
  std::string warnings;
};

/// Reads an image. With ColorSpace::Auto, 8/16-bit integer formats (PNG, JPEG, TIFF)
/// are treated as sRGB-encoded and decoded to linear; float formats (EXR, HDR) as linear.
/// Throws sg::FileError naming the file on failure, also when the decoder reported damage but
/// returned pixels (a truncated JPEG: io/decoder_messages.h); harmless metadata warnings are
/// in `warnings` and printed to stderr once per file and message ("synthgen: warning: ...").
///
/// The decoding runs in the synthgen-reader process (core/isolate.h) with time and memory
/// limits: a file that crashes or hangs a format library becomes a FileError, not a dead run.
///
/// Values that are not finite (NaN, infinity) are refused unless `allow_nonfinite` (data
/// images such as a depth map with +inf on background; never textures or environment maps).
ImageData load_image(const std::string& path, ColorSpace space, bool allow_nonfinite = false);

/// load_image in this process (what synthgen-reader runs; fuzz targets use it directly).
ImageData load_image_in_process(const std::string& path, ColorSpace space, bool allow_nonfinite = false);
/// load_image_in_process's result as the bytes synthgen-reader sends.
std::vector<char> load_image_bytes(const std::string& path, ColorSpace space, bool allow_nonfinite = false);

class Writer;
class Reader;
/// An image to and from the bytes of an isolated reader (core/isolate.h); reading checks
/// that the sizes agree and throws FileError(what) otherwise.
void write_image_data(Writer& w, const ImageData& image);
ImageData read_image_data(Reader& r, const std::string& what);

/// Decodes an image held in memory (e.g. embedded in a GLB file), without any colour
/// conversion. `format_hint` is a file extension such as "png". Throws sg::FileError
/// naming `what`.
ImageData load_image_from_memory(const void* data, size_t size, const std::string& format_hint,
                                 const std::string& what);

/// Writes float pixels; 8/16-bit formats are chosen by `bits` (0 = float).
void save_image(const std::string& path, const ImageData& image, int bits);

/// A tiled, mip-mapped float image file (OpenEXR, 64 x 64 tiles, zip): `levels[0]` is the
/// full image, each next level half the size (rounded down, at least 1: OpenEXR's
/// ROUND_DOWN mode, the rule of texture/mipmap.h), all with the same channels; `average` is
/// stored with it (metadata "synthgen:average", up to 4 values). The texture cache writes
/// the pyramids it builds this way once (texture/image_cache.h), then reads only the levels
/// a frame needs. Throws sg::FileError naming the file.
void save_mip_file(const std::string& path, const std::vector<ImageData>& levels, const std::vector<float>& average);

/// What a mip file holds: each level's size, the channels, the stored average.
struct MipFileHeader {
  int channels = 0;
  std::vector<int> widths, heights;
  std::vector<float> average;
};
/// Reads the header of a file written by save_mip_file, and channels [chbegin, chend) (-1:
/// to the last) of levels [first, first + count) into `levels` (none for count 0). Throws
/// sg::FileError naming the file when it cannot be read or is not such a file. Runs in this
/// process: the file is synthgen's own cache.
MipFileHeader load_mip_file(const std::string& path, int first, int count, std::vector<ImageData>* levels,
                            int chbegin = 0, int chend = -1);

/// A rectangle [x0, x1) x [y0, y1) of texels.
struct TexelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};
/// Reads channels [chbegin, chend) of rectangles `rects` of mip level `level` of a file written
/// by save_mip_file, one float vector per rectangle (row-major over the rectangle): with
/// rectangles on its 64 x 64 tiles only those tiles are decoded. Throws sg::FileError naming
/// the file.
std::vector<std::vector<float>> load_mip_rects(const std::string& path, int level, const std::vector<TexelRect>& rects,
                                               int chbegin, int chend);

/// Loads the OpenImageIO plugin now instead of at the first image read or write (a
/// one-time cost of about 0.2 s: OpenImageIO and its format libraries). Throws sg::Error
/// when the plugin cannot be loaded.
void load_image_plugin();

/// Prints each of `warnings` (one a line: ImageData::warnings) to stderr as "synthgen: warning:
/// WHAT: message", once per file and message in this process.
void report_image_warnings(const std::string& what, const std::string& warnings);

/// Function table exported by the plugin (C linkage; no exceptions cross it).
struct ImageIoApi {
  int version;
  bool (*load)(const char* path, int space, ImageData* out, std::string* error);
  bool (*load_memory)(const void* data, size_t size, const char* hint, ImageData* out, std::string* error);
  bool (*save)(const char* path, const ImageData* image, int bits, std::string* error);
  bool (*save_mip)(const char* path, const ImageData* levels, int count, const float* average, int average_count,
                   std::string* error);
  bool (*load_mip)(const char* path, int first, int count, int chbegin, int chend, MipFileHeader* header,
                   std::vector<ImageData>* levels, std::string* error);
  bool (*load_mip_rects)(const char* path, int level, const TexelRect* rects, int count, int chbegin, int chend,
                         std::vector<std::vector<float>>* out, std::string* error);
};
constexpr int k_image_io_api_version = 5;  // 5: ImageData::warnings

}  // namespace sg

extern "C" const sg::ImageIoApi* synthgen_image_io_api();
