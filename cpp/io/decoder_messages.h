// What image decoders said while reading a file: damage (an error) or harmless metadata
// warnings (printed, the image is used).
//
// Format libraries report a damaged file in two ways. Some fail the read (libpng's IDAT
// errors, OpenEXR's "unexpected end of file"). Others only warn and return pixels: libjpeg's
// "Premature end of JPEG file" fills the rows it never received with grey, and OpenImageIO
// still reports success (it records the warning with its errors). Such an image must never
// become a texture, a photo or a depth map. So after a successful read every message of the
// decoder counts as damage, except the few known to concern metadata alone (k_harmless):
// libpng's "iCCP: known incorrect sRGB profile" (a colour profile's checksum, the pixels are
// intact), libjpeg's "extraneous bytes before marker" (padding between segments), libtiff's
// unknown tags. Anything unknown is damage: a false alarm names the file and its message,
// a missed one silently poisons training data.
//
// NOTE: libjpeg passes a file's first warning to the application's output_message and only
// counts the later ones (jerror.c, emit_message with trace_level 0), so a JPEG whose first
// warning is harmless hides the later ones ("Premature end of JPEG file" among them), and
// OpenImageIO 2.4 gives no access to the count. jpeg_structure_damage therefore walks a JPEG's
// segments itself: a file cut anywhere before its end-of-image marker is found whatever the
// decoder said first.
#pragma once

#include <cctype>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace sg {

struct DecoderVerdict {
  std::vector<std::string> damage;    ///< messages that mean the pixels are not the file's
  std::vector<std::string> harmless;  ///< metadata warnings: the pixels are intact
};

namespace detail {
inline std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}
inline std::string trim(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}
}  // namespace detail

/// Lower-case substrings of decoder messages that concern metadata only.
inline const std::vector<std::string>& harmless_decoder_messages() {
  static const std::vector<std::string> k_harmless = {
      "known incorrect srgb profile",    // libpng: an sRGB ICC profile with a known bad checksum
      "iccp:",                           // libpng: other colour-profile chunk warnings
      "extraneous bytes before marker",  // libjpeg: padding between segments
      "unknown jfif revision",           // libjpeg: a newer JFIF header version
      "unknown field with tag",          // libtiff: a private tag
      "ascii value for tag",             // libtiff: a text tag without its terminating NUL
  };
  return k_harmless;
}

/// Splits `text` (messages separated by newlines) into damage and harmless warnings; empty
/// lines are dropped, duplicates kept once.
inline DecoderVerdict classify_decoder_messages(const std::string& text) {
  DecoderVerdict v;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = detail::trim(text.substr(start, end - start));
    start = end + 1;
    if (line.empty()) continue;
    std::string low = detail::lower(line);
    bool harmless = false;
    for (const std::string& h : harmless_decoder_messages())
      if (low.find(h) != std::string::npos) harmless = true;
    auto& into = harmless ? v.harmless : v.damage;
    bool seen = false;
    for (const std::string& s : into) seen = seen || s == line;
    if (!seen) into.push_back(line);
  }
  return v;
}

/// `lines` joined by "; ".
inline std::string join_messages(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += (out.empty() ? "" : "; ") + l;
  return out;
}

/// Walks a JPEG's marker segments (ITU-T T.81 B.1: markers 0xFFxx, segments with a 16-bit
/// length, entropy-coded data after SOS in which 0xFF is stuffed as 0xFF00 and RSTn markers
/// stand alone) and returns what is wrong with the structure: empty when the end-of-image
/// marker (EOI) is reached; else a message saying where the file ends or breaks. Bytes between
/// segments (libjpeg's harmless "extraneous bytes") and data after EOI are ignored. Linear in
/// the file's size, no allocation.
inline std::string jpeg_structure_damage(const unsigned char* data, size_t size) {
  if (size < 2 || data[0] != 0xFF || data[1] != 0xD8) return "no JPEG start-of-image marker";
  size_t pos = 2;
  bool in_frame = false;
  const std::string cut = "the file ends before its end-of-image marker (truncated at byte " + std::to_string(size) + ")";
  while (true) {
    while (pos < size && data[pos] != 0xFF) ++pos;  // extraneous bytes between segments
    while (pos < size && data[pos] == 0xFF) ++pos;  // fill bytes
    if (pos >= size) return cut;
    const unsigned m = data[pos++];
    if (m == 0xD9) return in_frame ? std::string() : "end-of-image marker before any scan";
    // TEM, RSTn: no length; FF00 between segments is skipped like libjpeg's extraneous bytes.
    if (m == 0x00 || m == 0x01 || (m >= 0xD0 && m <= 0xD7)) continue;
    if (m == 0xD8) return "a second start-of-image marker at byte " + std::to_string(pos - 2);
    if (pos + 2 > size) return cut;
    const size_t length = (size_t(data[pos]) << 8) | data[pos + 1];
    if (length < 2) return "a segment of length " + std::to_string(length) + " at byte " + std::to_string(pos);
    if (pos + length > size) return cut;
    pos += length;
    if (m != 0xDA) continue;
    in_frame = true;
    // Entropy-coded data: up to the next marker other than stuffing (FF00) and RSTn.
    while (true) {
      while (pos < size && data[pos] != 0xFF) ++pos;
      if (pos + 1 >= size) return cut;
      const unsigned next = data[pos + 1];
      if (next == 0x00 || (next >= 0xD0 && next <= 0xD7) || next == 0xFF) {
        pos += next == 0xFF ? 1 : 2;
        continue;
      }
      break;  // a marker: the scan ended
    }
  }
}

}  // namespace sg
