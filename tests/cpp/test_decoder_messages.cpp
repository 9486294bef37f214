// Decoder messages and JPEG structure (io/decoder_messages.h), and image reads that refuse a
// damaged file even where the decoder returned pixels (io/image_io.cpp): every truncation of
// a real JPEG is an error, harmless metadata warnings are not.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "io/decoder_messages.h"
#include "io/image_io.h"

using namespace sg;

namespace {

std::vector<unsigned char> bytes_of(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<unsigned char>(std::istreambuf_iterator<char>(f), {});
}

void write_bytes(const std::string& path, const std::vector<unsigned char>& b, size_t n) {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(b.data()), std::streamsize(n));
}

std::string temp_dir() {
  auto d = std::filesystem::temp_directory_path() / ("sg_decoder_" + std::to_string(getpid()));
  std::filesystem::create_directories(d);
  return d.string();
}

/// A 96 x 64 JPEG with detail in every block (so that every cut loses pixels).
std::string write_test_jpeg(const std::string& dir) {
  ImageData img;
  img.width = 96;
  img.height = 64;
  img.channels = 3;
  img.pixels.resize(size_t(img.width) * img.height * 3);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 3; ++c)
        img.pixels[(size_t(y) * img.width + x) * 3 + c] = float(((x * 7 + y * 13 + c * 5) % 17) / 16.0);
  std::string path = dir + "/test.jpg";
  save_image(path, img, 8);
  return path;
}

}  // namespace

TEST(decoder_messages, known_metadata_warnings_are_harmless_everything_else_is_damage) {
  DecoderVerdict v = classify_decoder_messages(
      "libpng warning: iCCP: known incorrect sRGB profile\n"
      "JPEG error: Corrupt JPEG data: 3 extraneous bytes before marker 0xdb (\"a.jpg\")\n\n"
      "JPEG error: Premature end of JPEG file (\"a.jpg\")\n"
      "libpng warning: IDAT: Too much image data\n"
      "  JPEG error: Premature end of JPEG file (\"a.jpg\")  \n");
  ASSERT_EQ(v.harmless.size(), 2u);
  EXPECT_EQ(v.harmless[0], "libpng warning: iCCP: known incorrect sRGB profile");
  ASSERT_EQ(v.damage.size(), 2u);  // the repeated line once
  EXPECT_EQ(v.damage[0], "JPEG error: Premature end of JPEG file (\"a.jpg\")");
  EXPECT_EQ(v.damage[1], "libpng warning: IDAT: Too much image data");
  EXPECT_TRUE(classify_decoder_messages("\n \n").damage.empty());
  EXPECT_EQ(join_messages({"a", "b"}), "a; b");
}

TEST(decoder_messages, jpeg_structure_of_hand_made_files) {
  // SOI, APP0 (length 4), SOS (length 3), entropy data with stuffing and a restart, EOI.
  std::vector<unsigned char> ok = {0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x04, 0x12, 0x34, 0xFF, 0xDA, 0x00, 0x03, 0x01,
                                   0x55, 0xFF, 0x00, 0x66, 0xFF, 0xD0, 0x77, 0xFF, 0xD9};
  EXPECT_EQ(jpeg_structure_damage(ok.data(), ok.size()), "");
  // Data after EOI and bytes between segments are not damage.
  std::vector<unsigned char> trailing = ok;
  trailing.insert(trailing.end(), {0x00, 0x11, 0xFF});
  EXPECT_EQ(jpeg_structure_damage(trailing.data(), trailing.size()), "");
  std::vector<unsigned char> extraneous = ok;
  extraneous.insert(extraneous.begin() + 8, {0x01, 0x02, 0x03});
  EXPECT_EQ(jpeg_structure_damage(extraneous.data(), extraneous.size()), "");
  // Every cut before the end is damage.
  for (size_t n = 0; n < ok.size(); ++n) EXPECT_NE(jpeg_structure_damage(ok.data(), n), "") << n;
  // A segment longer than the file, a zero length, EOI before any scan.
  std::vector<unsigned char> long_segment = {0xFF, 0xD8, 0xFF, 0xE0, 0x40, 0x00, 0x00, 0xFF, 0xD9};
  EXPECT_NE(jpeg_structure_damage(long_segment.data(), long_segment.size()), "");
  std::vector<unsigned char> zero = {0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x00, 0xFF, 0xD9};
  EXPECT_NE(jpeg_structure_damage(zero.data(), zero.size()), "");
  std::vector<unsigned char> no_scan = {0xFF, 0xD8, 0xFF, 0xD9};
  EXPECT_NE(jpeg_structure_damage(no_scan.data(), no_scan.size()), "");
}

TEST(decoder_messages, every_truncation_of_a_real_jpeg_is_refused) {
  const std::string dir = temp_dir();
  const std::string path = write_test_jpeg(dir);
  const std::vector<unsigned char> full = bytes_of(path);
  ASSERT_GT(full.size(), 600u);
  EXPECT_EQ(jpeg_structure_damage(full.data(), full.size()), "");
  ImageData whole = load_image_in_process(path, ColorSpace::Auto);
  EXPECT_EQ(whole.width, 96);
  EXPECT_EQ(whole.warnings, "");
  // The structure walk at every length; the whole read (OpenImageIO and libjpeg) at every 37th.
  const std::string cut = dir + "/cut.jpg";
  int reads = 0;
  for (size_t n = 0; n + 2 <= full.size(); ++n) {
    ASSERT_NE(jpeg_structure_damage(full.data(), n), "") << n;
    if (n % 37 != 0 && n + 2 != full.size()) continue;
    write_bytes(cut, full, n);
    try {
      load_image_in_process(cut, ColorSpace::Auto);
      ADD_FAILURE() << "a JPEG cut to " << n << " of " << full.size() << " bytes was read";
    } catch (const FileError& e) {
      EXPECT_NE(std::string(e.what()).find("cut.jpg"), std::string::npos) << e.what();
      ++reads;
    }
  }
  EXPECT_GT(reads, 10);
  // Cut after the scan data started: the decoder itself returns pixels (grey rows) and says
  // "Premature end"; the read is refused, naming the damage.
  write_bytes(cut, full, full.size() - 40);
  try {
    load_image_in_process(cut, ColorSpace::Auto);
    FAIL() << "read";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("damaged or truncated image"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(decoder_messages, a_harmless_warning_does_not_hide_a_truncation) {
  const std::string dir = temp_dir();
  const std::vector<unsigned char> full = bytes_of(write_test_jpeg(dir));
  // 3 extraneous bytes after the first segment: libjpeg's first (harmless) warning.
  const size_t after_app = 4 + ((size_t(full[4]) << 8) | full[5]);
  ASSERT_EQ(full[2], 0xFF);
  std::vector<unsigned char> padded(full.begin(), full.begin() + long(after_app));
  padded.insert(padded.end(), {0x00, 0x01, 0x02});
  padded.insert(padded.end(), full.begin() + long(after_app), full.end());
  const std::string p = dir + "/padded.jpg";
  write_bytes(p, padded, padded.size());
  ImageData img = load_image_in_process(p, ColorSpace::Auto);
  EXPECT_NE(img.warnings.find("extraneous bytes"), std::string::npos) << img.warnings;
  // The same file cut: libjpeg reports only its first warning, the structure walk finds the cut.
  write_bytes(p, padded, padded.size() - 40);
  EXPECT_THROW(load_image_in_process(p, ColorSpace::Auto), FileError);
  std::filesystem::remove_all(dir);
}
