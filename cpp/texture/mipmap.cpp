#include "texture/mipmap.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace sg {

WrapMode parse_wrap_mode(const std::string& s, const std::string& context) {
  if (s == "repeat") return WrapMode::Repeat;
  if (s == "clamp") return WrapMode::Clamp;
  if (s == "mirror") return WrapMode::Mirror;
  throw Error(context + ": 'wrap' must be repeat, clamp or mirror, got '" + s + "'");
}

namespace {

struct Tap {
  int index;
  float weight;
};

/// Filter taps reducing n texels to m along one axis.
/// NOTE: exact area-weighted box filter: output texel i covers the input interval
/// [i n/m, (i+1) n/m) and averages the input texels by their overlap with it. For n = 2m
/// this is the usual 2-tap box; for odd n = 2m+1 it is the 3-tap polyphase box filter of
/// Guthe & Heckbert, "Non-Power-of-Two Mipmap Creation" (NVIDIA TR-01838-001, 2003),
/// weights ((m-i), m, (i+1)) / (2m+1). The intervals partition [0, n), so the mean is
/// preserved exactly and no texel outside the image is needed (any wrap mode).
std::vector<std::vector<Tap>> box_taps(int n, int m) {
  std::vector<std::vector<Tap>> taps(static_cast<size_t>(m));
  const double scale = double(n) / double(m);
  for (int i = 0; i < m; ++i) {
    double a = i * scale, b = (i + 1) * scale;
    int j0 = std::max(0, int(std::floor(a))), j1 = std::min(n, int(std::ceil(b)));
    for (int j = j0; j < j1; ++j) {
      double overlap = std::min(b, j + 1.0) - std::max(a, double(j));
      if (overlap > 1e-9) taps[size_t(i)].push_back({j, float(overlap / scale)});
    }
  }
  return taps;
}

inline int wrap_index(int i, int n, WrapMode wrap) {
  if (i >= 0 && i < n) return i;  // the common case, without divisions
  switch (wrap) {
    case WrapMode::Clamp: return std::min(std::max(i, 0), n - 1);
    case WrapMode::Mirror: {
      int period = 2 * n;
      int m = ((i % period) + period) % period;
      return m < n ? m : period - 1 - m;
    }
    default: return ((i % n) + n) % n;
  }
}

/// Brings an image coordinate into a small range with the same wrapped value, so that
/// texel indices never overflow an int (uvs of tiled meshes can be large).
inline float reduce_coordinate(float s, WrapMode wrap) {
  if (!std::isfinite(s)) return 0.f;
  switch (wrap) {
    case WrapMode::Clamp: return std::min(std::max(s, -1.f), 2.f);
    case WrapMode::Mirror: return s - 2.f * std::floor(0.5f * s);  // period 2
    default: return s - std::floor(s);                               // period 1
  }
}

}  // namespace

MipMap::MipMap(const ImageData& image) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.pixels.size() < size_t(image.width) * image.height * image.channels)
    throw Error("image texture: the image has no pixels");
  m_channels = image.channels >= 3 ? 3 : 1;
  if (image.channels == 2 || image.channels >= 4) {
    const int ac = image.channels == 2 ? 1 : 3;
    ImageData a;
    a.width = image.width;
    a.height = image.height;
    a.channels = 1;
    a.pixels.resize(size_t(image.width) * image.height);
    for (size_t i = 0; i < a.pixels.size(); ++i) a.pixels[i] = image.pixels[i * image.channels + ac];
    m_alpha = std::make_shared<const MipMap>(a);
  }
  Level base;
  base.width = image.width;
  base.height = image.height;
  const size_t n = size_t(image.width) * image.height;
  base.data.resize(n * m_channels);
  double acc[3] = {0, 0, 0};
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < m_channels; ++c) {
      float v = image.pixels[i * image.channels + c];
      base.data[i * m_channels + c] = v;
      acc[c] += v;
    }
  if (m_channels == 1) m_average = Color(float(acc[0] / n));
  else m_average = Color(float(acc[0] / n), float(acc[1] / n), float(acc[2] / n));
  m_levels.push_back(std::move(base));

  // Levels halve each dimension (rounding down, at least 1) until 1 x 1, the OpenGL rule.
  const int nc = m_channels;
  while (m_levels.back().width > 1 || m_levels.back().height > 1) {
    const Level& src = m_levels.back();
    Level dst;
    dst.width = std::max(1, src.width / 2);
    dst.height = std::max(1, src.height / 2);
    auto tx = box_taps(src.width, dst.width), ty = box_taps(src.height, dst.height);
    // Separable: rows first (src.height x dst.width), then columns.
    std::vector<float> tmp(size_t(src.height) * dst.width * nc, 0.f);
    for (int y = 0; y < src.height; ++y)
      for (int x = 0; x < dst.width; ++x)
        for (const Tap& t : tx[size_t(x)])
          for (int c = 0; c < nc; ++c)
            tmp[(size_t(y) * dst.width + x) * nc + c] += t.weight * src.data[(size_t(y) * src.width + t.index) * nc + c];
    dst.data.assign(size_t(dst.height) * dst.width * nc, 0.f);
    for (int y = 0; y < dst.height; ++y)
      for (const Tap& t : ty[size_t(y)])
        for (int x = 0; x < dst.width; ++x)
          for (int c = 0; c < nc; ++c)
            dst.data[(size_t(y) * dst.width + x) * nc + c] += t.weight * tmp[(size_t(t.index) * dst.width + x) * nc + c];
    m_levels.push_back(std::move(dst));
  }
  set_tail();
}

MipMap::MipMap(std::vector<int> widths, std::vector<int> heights, int channels, const Color& average,
               MipSource source, std::shared_ptr<const MipMap> alpha)
    : m_channels(channels), m_average(average), m_alpha(std::move(alpha)), m_source(std::move(source)) {
  if (widths.empty() || widths.size() != heights.size() || (channels != 1 && channels != 3) || !m_source)
    throw Error("image texture: malformed lazy pyramid");
  for (size_t l = 0; l < widths.size(); ++l) {
    // Sizes must follow the halving rule (a file that disagrees is not a pyramid of ours).
    int w = l ? std::max(1, widths[l - 1] / 2) : widths[0], h = l ? std::max(1, heights[l - 1] / 2) : heights[0];
    if (widths[l] != w || heights[l] != h || w < 1 || h < 1)
      throw Error("image texture: mip level " + std::to_string(l) + " has the wrong size");
    Level lv;
    lv.width = w;
    lv.height = h;
    m_levels.push_back(std::move(lv));
  }
  if (m_levels.back().width != 1 || m_levels.back().height != 1)
    throw Error("image texture: the pyramid does not end at 1 x 1");
  if (m_alpha && (m_alpha->width(0) != widths[0] || m_alpha->height(0) != heights[0]))
    throw Error("image texture: the alpha channel's size differs from the image's");
  set_tail();
  m_first = m_resident = levels();  // nothing resident yet
  use_levels(m_tail);
}

void MipMap::set_tail() {
  m_tail = levels() - 1;
  while (m_tail > 0 && std::max(width(m_tail - 1), height(m_tail - 1)) <= k_tail_texels) --m_tail;
}

namespace {

/// The texels of rectangle `r` of a row-major level `width` texels wide, row-major over `r`.
std::vector<float> cut_tile(const std::vector<float>& level, int width, int channels, const TexelRect& r) {
  std::vector<float> tile;
  tile.reserve(size_t(r.x1 - r.x0) * size_t(r.y1 - r.y0) * size_t(channels));
  for (int y = r.y0; y < r.y1; ++y)
    tile.insert(tile.end(), level.begin() + (size_t(y) * width + r.x0) * channels,
                level.begin() + (size_t(y) * width + r.x1) * channels);
  return tile;
}

}  // namespace

TexelRect MipMap::tile_rect(int level, size_t t) const {
  const size_t tx = size_t(tiles_x(level));
  TexelRect r;
  r.x0 = int(t % tx) * k_tile;
  r.y0 = int(t / tx) * k_tile;
  r.x1 = std::min(width(level), r.x0 + k_tile);
  r.y1 = std::min(height(level), r.y0 + k_tile);
  return r;
}

void MipMap::make_whole(int first) const {
  for (int l = first; l < levels(); ++l) {
    m_levels[size_t(l)].used.clear();
    if (!m_levels[size_t(l)].data.empty()) continue;
    int end = l;  // a run of levels without whole data: read back together
    while (end < levels() && m_levels[size_t(end)].data.empty()) ++end;
    if (!m_source) throw Error("image texture: mip level " + std::to_string(l) + " is not resident and has no source");
    std::vector<std::vector<float>> data = m_source(l, end - l);
    if (int(data.size()) != end - l) throw Error("image texture: the pyramid's source returned too few levels");
    for (int k = l; k < end; ++k) {
      std::vector<float>& d = data[size_t(k - l)];
      if (d.size() != size_t(width(k)) * height(k) * m_channels)
        throw Error("image texture: mip level " + std::to_string(k) + " read back with the wrong size");
      m_levels[size_t(k)].data = std::move(d);
      std::vector<std::vector<float>>().swap(m_levels[size_t(k)].tiles);
      m_levels[size_t(k)].used.clear();
    }
    l = end - 1;
  }
  m_resident = std::min(m_resident, first);
}

void MipMap::use_levels(int first) const {
  first = std::min(std::max(first, 0), m_tail);
  make_whole(first);
  m_first = first;
}

void MipMap::use_tiles(int first, const std::vector<uint8_t>& used) const {
  first = std::min(std::max(first, 0), m_tail);
  const size_t n = size_t(tiles_x(first)) * size_t(tiles_y(first));
  if (!used.empty() && used.size() != n)
    throw Error("image texture: " + std::to_string(used.size()) + " tile flags for mip level " + std::to_string(first) +
                " of " + std::to_string(n) + " tiles");
  if (used.empty() || first >= m_tail || std::all_of(used.begin(), used.end(), [](uint8_t u) { return u != 0; })) {
    use_levels(first);
    return;
  }
  make_whole(first + 1);
  Level& lv = m_levels[size_t(first)];
  if (lv.data.empty()) {
    if (lv.tiles.size() != n) lv.tiles.assign(n, {});
    std::vector<size_t> missing;
    for (size_t t = 0; t < n; ++t)
      if (used[t] && lv.tiles[t].empty()) missing.push_back(t);
    std::vector<std::vector<float>> read;  // the missing tiles from the tile source, in one pass
    if (m_tile_source && !missing.empty()) {
      std::vector<TexelRect> rects;
      for (size_t t : missing) rects.push_back(tile_rect(first, t));
      read = m_tile_source(first, rects);
      if (read.size() != missing.size()) throw Error("image texture: the tile source returned too few tiles");
    }
    std::vector<float> whole;  // the level, when tiles are cut from it (no tile source)
    for (size_t k = 0; k < missing.size(); ++k) {
      const size_t t = missing[k];
      const TexelRect r = tile_rect(first, t);
      const size_t texels = size_t(r.x1 - r.x0) * size_t(r.y1 - r.y0) * m_channels;
      if (m_tile_source) {
        lv.tiles[t] = std::move(read[k]);
      } else {
        if (whole.empty()) {
          if (!m_source) throw Error("image texture: mip level " + std::to_string(first) + " has no source");
          std::vector<std::vector<float>> d = m_source(first, 1);
          if (d.size() != 1 || d[0].size() != size_t(lv.width) * lv.height * m_channels)
            throw Error("image texture: mip level " + std::to_string(first) + " read back with the wrong size");
          whole = std::move(d[0]);
        }
        lv.tiles[t] = cut_tile(whole, lv.width, m_channels, r);
      }
      if (lv.tiles[t].size() != texels)
        throw Error("image texture: a tile of mip level " + std::to_string(first) + " read back with the wrong size");
    }
  }
  lv.used = used;
  m_first = first;
  m_resident = std::min(m_resident, first);
}

int MipMap::used_tiles() const {
  if (m_first >= levels()) return 0;
  const std::vector<uint8_t>& u = m_levels[size_t(m_first)].used;
  return int(std::count_if(u.begin(), u.end(), [](uint8_t x) { return x != 0; }));
}

int MipMap::resident_tiles() const {
  if (m_first >= levels()) return 0;
  const auto& tiles = m_levels[size_t(m_first)].tiles;
  return int(std::count_if(tiles.begin(), tiles.end(), [](const std::vector<float>& t) { return !t.empty(); }));
}

void MipMap::drop_unused() const {
  if (!m_source) return;
  for (int l = m_resident; l < std::min(m_first, levels()); ++l) {
    std::vector<float>().swap(m_levels[size_t(l)].data);
    std::vector<std::vector<float>>().swap(m_levels[size_t(l)].tiles);
  }
  m_resident = std::max(m_resident, m_first);
  if (m_first >= levels()) return;
  Level& f = m_levels[size_t(m_first)];
  if (f.used.empty()) return;
  if (!f.data.empty()) {  // whole, read in part: keep the used tiles only
    f.tiles.assign(f.used.size(), {});
    for (size_t t = 0; t < f.used.size(); ++t)
      if (f.used[t]) f.tiles[t] = cut_tile(f.data, f.width, m_channels, tile_rect(m_first, t));
    std::vector<float>().swap(f.data);
  }
  for (size_t t = 0; t < f.used.size() && t < f.tiles.size(); ++t)
    if (!f.used[t]) std::vector<float>().swap(f.tiles[t]);
}

void MipMap::make_resident(int first) const {
  use_levels(first);
  drop_unused();
}

const float* MipMap::texel_ptr(const Level& l, size_t x, size_t y) const {
  if (l.used.empty()) return &l.data[(y * size_t(l.width) + x) * m_channels];
  const size_t tx = x / k_tile, ty = y / k_tile, t = ty * ((size_t(l.width) + k_tile - 1) / k_tile) + tx;
  if (!l.used[t]) return nullptr;
  if (!l.data.empty()) return &l.data[(y * size_t(l.width) + x) * m_channels];
  const size_t tw = std::min(size_t(k_tile), size_t(l.width) - tx * k_tile);
  return &l.tiles[t][((y - ty * k_tile) * tw + (x - tx * k_tile)) * m_channels];
}

Color MipMap::texel(int level, int x, int y, WrapMode wrap) const {
  level = std::max(level, m_first);
  const Level& l = m_levels[size_t(level)];
  const size_t xi = size_t(wrap_index(x, l.width, wrap)), yi = size_t(wrap_index(y, l.height, wrap));
  const float* p = texel_ptr(l, xi, yi);
  if (!p) {  // a tile the frame does not use: the texel of the next coarser level over it
    const Level& c = m_levels[size_t(level + 1)];
    return texel(level + 1, std::min(int(xi) * c.width / l.width, c.width - 1),
                 std::min(int(yi) * c.height / l.height, c.height - 1), wrap);
  }
  if (m_channels == 1) return Color(p[0]);
  return Color(p[0], p[1], p[2]);
}

Color MipMap::bilinear(int level, float s, float t, WrapMode wrap) const {
  level = std::max(level, m_first);
  const Level& l = m_levels[size_t(level)];
  float x = reduce_coordinate(s, wrap) * float(l.width) - 0.5f;
  float y = reduce_coordinate(t, wrap) * float(l.height) - 0.5f;
  float fx = std::floor(x), fy = std::floor(y);
  float ax = x - fx, ay = y - fy;
  int x0 = int(fx), y0 = int(fy);
  size_t xa = size_t(wrap_index(x0, l.width, wrap)), xb = size_t(wrap_index(x0 + 1, l.width, wrap));
  size_t ya = size_t(wrap_index(y0, l.height, wrap)), yb = size_t(wrap_index(y0 + 1, l.height, wrap));
  const float w00 = (1.f - ax) * (1.f - ay), w10 = ax * (1.f - ay), w01 = (1.f - ax) * ay, w11 = ax * ay;
  const float *p00, *p10, *p01, *p11;
  if (l.used.empty()) {  // the common case: a whole level
    const float* d = l.data.data();
    const size_t nc = size_t(m_channels), ra = ya * size_t(l.width), rb = yb * size_t(l.width);
    p00 = d + nc * (ra + xa);
    p10 = d + nc * (ra + xb);
    p01 = d + nc * (rb + xa);
    p11 = d + nc * (rb + xb);
  } else {
    p00 = texel_ptr(l, xa, ya);
    p10 = texel_ptr(l, xb, ya);
    p01 = texel_ptr(l, xa, yb);
    p11 = texel_ptr(l, xb, yb);
    // A texel in a tile the frame does not use: the lookup reads the next coarser level.
    if (!p00 || !p10 || !p01 || !p11) return bilinear(level + 1, s, t, wrap);
  }
  if (m_channels == 1) return Color(w00 * *p00 + w10 * *p10 + w01 * *p01 + w11 * *p11);
  return Color(w00 * p00[0] + w10 * p10[0] + w01 * p01[0] + w11 * p11[0],
               w00 * p00[1] + w10 * p10[1] + w01 * p01[1] + w11 * p11[1],
               w00 * p00[2] + w10 * p10[2] + w01 * p01[2] + w11 * p11[2]);
}

Color MipMap::lookup(float s, float t, float width, WrapMode wrap) const {
  // NOTE: mip level lambda = log2(rho), rho = footprint in texels = width * max(W, H)
  // (Akenine-Moller et al., "Texture Level of Detail Strategies for Real-Time Ray
  // Tracing", Ray Tracing Gems ch. 20, 2019, eq. (1); mip-mapping after Williams,
  // "Pyramidal Parametrics", SIGGRAPH 1983). Trilinear: linear blend of the bilinear
  // lookups in levels floor(lambda) and floor(lambda) + 1.
  const Level& l0 = m_levels[0];
  float texels = width * float(std::max(l0.width, l0.height));
  if (!(texels > 1.f)) return bilinear(m_first, s, t, wrap);  // also catches NaN
  const int top = levels() - 1;
  float lambda = std::log2(texels);
  if (!(lambda < float(top))) return bilinear(top, s, t, wrap);
  // Finer than the finest resident level: that level (docs/texture_lod.md).
  if (lambda < float(m_first)) return bilinear(m_first, s, t, wrap);
  int k = int(lambda);
  float f = lambda - float(k);
  return bilinear(k, s, t, wrap) * (1.f - f) + bilinear(k + 1, s, t, wrap) * f;
}

Color MipMap::lookup_ellipse(float s, float t, const Vec2f& a, const Vec2f& b, WrapMode wrap) const {
  // NOTE: principal axes of the footprint ellipse from two conjugate axis vectors: the
  // ellipse {a cos(phi) + b sin(phi)} is {x : x^T C^-1 x = 1} with C = a a^T + b b^T
  // (Heckbert, "Fundamentals of Texture Mapping and Image Warping", MS thesis, UC Berkeley
  // 1989, EWA filter: the conic of the Jacobian J = [a b] is C = J J^T). The eigenvalues of
  // C are the squared principal axis lengths (full widths, like a and b).
  if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y))
    return lookup(s, t, k_inf, wrap);  // unbounded footprint (inf * 0 would make NaNs): the average
  float p = a.x * a.x + b.x * b.x, q = a.x * a.y + b.x * b.y, r = a.y * a.y + b.y * b.y;
  float mean = 0.5f * (p + r);
  float d = std::sqrt(0.25f * (p - r) * (p - r) + q * q);
  float major = std::sqrt(std::max(mean + d, 0.f)), minor = std::sqrt(std::max(mean - d, 0.f));
  if (!std::isfinite(major)) return lookup(s, t, k_inf, wrap);  // overflow: the average
  // Magnification (the whole ellipse within a texel): bilinear in level 0, as lookup().
  const float texel = 1.f / float(std::max(m_levels[0].width, m_levels[0].height));
  if (major <= texel) return bilinear(m_first, s, t, wrap);
  // NOTE: Feline (McCormack, Perry, Farkas, Jouppi, "Feline: Fast Elliptical Lines for
  // Anisotropic Texture Mapping", SIGGRAPH 1999): n trilinear probes spaced along the
  // major axis, the mip level chosen from the minor axis; the eccentricity is clamped (here
  // to k_max_probes) by widening the minor axis, as pbrt clamps it for EWA. The probes
  // are weighted equally (a box along the major axis, matching the film's box pixel
  // filter; Feline uses Gaussian weights). A minor axis under one texel reads level 0
  // anyway, so probes one texel apart suffice there.
  minor = std::max({minor, major / float(k_max_probes), texel});
  int n = int(std::ceil(major / minor - 1e-3f));
  if (n <= 1) return lookup(s, t, major, wrap);
  // Unit eigenvector of the largest eigenvalue.
  float l1 = mean + d;
  Vec2f e1(q, l1 - p), e2(l1 - r, q);
  Vec2f e = (e1.x * e1.x + e1.y * e1.y) >= (e2.x * e2.x + e2.y * e2.y) ? e1 : e2;
  float el = std::sqrt(e.x * e.x + e.y * e.y);
  if (!(el > 0.f)) return lookup(s, t, major, wrap);
  e = e * (major / el);  // full major axis
  Color sum(0.f);
  for (int i = 0; i < n; ++i) {
    float o = (float(i) + 0.5f) / float(n) - 0.5f;  // probe centres spread over the major axis
    sum += lookup(s + o * e.x, t + o * e.y, minor, wrap);
  }
  return sum * (1.f / float(n));
}

uint64_t MipMap::bytes(int first_level) const {
  uint64_t n = 0;
  for (int l = std::max(first_level, 0); l < levels(); ++l)
    n += uint64_t(m_levels[size_t(l)].width) * uint64_t(m_levels[size_t(l)].height) * uint64_t(m_channels) * sizeof(float);
  return n + (m_alpha ? m_alpha->bytes(0) : 0);
}

uint64_t MipMap::bytes(int level, const std::vector<uint8_t>& used) const {
  if (used.empty() || level >= levels()) return bytes(level);
  uint64_t n = bytes(level + 1);
  for (size_t t = 0; t < used.size(); ++t) {
    if (!used[t]) continue;
    const TexelRect r = tile_rect(level, t);
    n += uint64_t(r.x1 - r.x0) * uint64_t(r.y1 - r.y0) * uint64_t(m_channels) * sizeof(float);
  }
  return n;
}

uint64_t MipMap::resident_bytes() const {
  uint64_t n = 0;
  for (const Level& l : m_levels) {
    n += l.data.size() * sizeof(float);
    for (const auto& t : l.tiles) n += t.size() * sizeof(float);
  }
  return n + (m_alpha ? m_alpha->resident_bytes() : 0);
}

}  // namespace sg
