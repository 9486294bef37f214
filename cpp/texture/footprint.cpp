#include "texture/footprint.h"

#include <algorithm>
#include <cmath>

#include "texture/mipmap.h"

namespace sg {

namespace {

thread_local FootprintRecorder* t_recorder = nullptr;

/// A lookup's rho_L for every level of `mip` (NaN: the footprint says nothing).
std::vector<float> level_rho(const MipMap& mip, const Vec2f& a, const Vec2f& b) {
  std::vector<float> rho(size_t(mip.levels()));
  for (int l = 0; l < mip.levels(); ++l) {
    float w = float(mip.width(l)), h = float(mip.height(l));
    rho[size_t(l)] = std::max(std::hypot(a.x * w, a.y * h), std::hypot(b.x * w, b.y * h));
  }
  return rho;
}

void add(FootprintRecorder::Use& u, const std::vector<float>& rho) {
  if (u.min_rho.empty()) u.min_rho.assign(rho.size(), k_inf);
  for (size_t l = 0; l < rho.size() && l < u.min_rho.size(); ++l)
    if (rho[l] >= 0.f) u.min_rho[l] = std::min(u.min_rho[l], rho[l]);  // NaN footprints say nothing
  ++u.lookups;
}

void merge_use(FootprintRecorder::Use& into, const FootprintRecorder::Use& from) {
  if (into.min_rho.empty()) into.min_rho.assign(from.min_rho.size(), k_inf);
  for (size_t l = 0; l < from.min_rho.size() && l < into.min_rho.size(); ++l)
    into.min_rho[l] = std::min(into.min_rho[l], from.min_rho[l]);
  into.lookups += from.lookups;
  if (into.cells.size() < from.cells.size()) into.cells.resize(from.cells.size());
  for (size_t k = 0; k < from.cells.size(); ++k) {
    if (into.cells[k].empty()) into.cells[k] = from.cells[k];
    else
      for (size_t i = 0; i < from.cells[k].size() && i < into.cells[k].size(); ++i) into.cells[k][i] |= from.cells[k][i];
  }
}

/// The cells (of `cell` texels, `count` of them over `n` texels) holding a texel of the
/// image-unit interval [lo, hi] wrapped by `wrap`; empty when that is every cell.
std::vector<int> cell_span(double lo, double hi, int n, int cell, int count, WrapMode wrap) {
  if (!(lo <= hi) || !std::isfinite(lo) || !std::isfinite(hi)) return {};
  if (wrap == WrapMode::Repeat) {
    const double f = std::floor(lo);
    lo -= f;
    hi -= f;
  } else if (wrap == WrapMode::Mirror) {
    const double f = 2.0 * std::floor(0.5 * lo);
    lo -= f;
    hi -= f;
  } else {
    lo = std::min(std::max(lo, 0.0), 1.0);
    hi = std::min(std::max(hi, 0.0), 1.0);
  }
  const long long x0 = (long long)std::floor(lo * n), x1 = (long long)std::floor(hi * n);
  if (x1 - x0 + 1 >= (long long)n) return {};
  // NOTE: the interval's texels, wrapped, in steps of one cell plus both sides of every
  // seam (multiples of n, where the wrapped index jumps): no cell the interval touches is
  // skipped, the image's last, narrower cell included.
  std::vector<long long> points;
  for (long long x = x0; x < x1; x += cell) points.push_back(x);
  points.push_back(x1);
  for (long long k = (x0 + n - 1) / n; k * n <= x1 + 1; ++k) {
    if (k * n - 1 >= x0) points.push_back(k * n - 1);
    if (k * n <= x1) points.push_back(k * n);
  }
  std::vector<int> out;
  for (long long x : points) {
    long long i = x;
    if (wrap == WrapMode::Clamp) i = std::min(std::max(i, 0LL), (long long)n - 1);
    else if (wrap == WrapMode::Mirror) {
      const long long m = ((i % (2LL * n)) + 2LL * n) % (2LL * n);
      i = m < n ? m : 2LL * n - 1 - m;
    } else {
      i = ((i % n) + n) % n;
    }
    out.push_back(std::min(int(i / cell), count - 1));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void mark_cells(FootprintRecorder::Use& u, const MipMap& mip, const Vec2f& st, const Vec2f& a, const Vec2f& b,
                float rho0, WrapMode wrap) {
  constexpr int tile = MipMap::k_tile;
  // The level the lookup reads, half a level finer (lambda = log2 rho_0).
  const float lambda = rho0 > 1.f ? std::log2(rho0) : 0.f;
  const int k = std::min(int(std::max(0.f, std::floor(lambda - 0.5f))), mip.levels() - 1);
  if (u.cells.size() < size_t(mip.levels())) u.cells.resize(size_t(mip.levels()));
  std::vector<uint8_t>& cells = u.cells[size_t(k)];
  const int cx = mip.tiles_x(k), cy = mip.tiles_y(k);
  if (cells.empty()) cells.assign(size_t(cx) * size_t(cy), 0);
  const int w = mip.width(k), h = mip.height(k);
  // Half the footprint's extent (its full width, to be safe) plus two texels of level k.
  const double hs = std::max(std::fabs(a.x), std::fabs(b.x)) + 2.0 / w;
  const double ht = std::max(std::fabs(a.y), std::fabs(b.y)) + 2.0 / h;
  std::vector<int> xs = cell_span(double(st.x) - hs, double(st.x) + hs, w, tile, cx, wrap);
  std::vector<int> ys = cell_span(double(st.y) - ht, double(st.y) + ht, h, tile, cy, wrap);
  if (xs.empty())
    for (int i = 0; i < cx; ++i) xs.push_back(i);
  if (ys.empty())
    for (int i = 0; i < cy; ++i) ys.push_back(i);
  for (int y : ys)
    for (int x : xs) cells[size_t(y) * size_t(cx) + size_t(x)] = 1;
}

}  // namespace

int FootprintRecorder::Use::needed_level() const {
  int level = 0;
  for (size_t l = 0; l < min_rho.size(); ++l)
    if (min_rho[l] >= 1.f) level = int(l);
    else break;
  return level;
}

void FootprintRecorder::record(const Texture* texture, const MipMap& mip, Vec2f a, Vec2f b, const float m[4],
                               Vec2f st, WrapMode wrap) {
  if (a.x == 0.f && a.y == 0.f && b.x == 0.f && b.y == 0.f) {
    a = Vec2f(m[0] * hit_a.x + m[1] * hit_a.y, m[2] * hit_a.x + m[3] * hit_a.y);
    b = Vec2f(m[0] * hit_b.x + m[1] * hit_b.y, m[2] * hit_b.x + m[3] * hit_b.y);
  }
  const std::vector<float> rho = level_rho(mip, a, b);
  Use& u = by_mip[&mip];
  add(u, rho);
  mark_cells(u, mip, st, a, b, rho.empty() ? 0.f : rho[0], wrap);
  if (texture) add(by_texture[texture], rho);
}

std::vector<uint8_t> FootprintRecorder::Use::tiles(const MipMap& mip, int level) const {
  const int tx = mip.tiles_x(level), ty = mip.tiles_y(level), wl = mip.width(level), hl = mip.height(level);
  std::vector<uint8_t> out(size_t(tx) * size_t(ty), 0);
  for (int k = 0; k <= level && k < int(cells.size()); ++k) {
    const std::vector<uint8_t>& c = cells[size_t(k)];
    if (c.empty()) continue;
    const int cx = mip.tiles_x(k), cy = mip.tiles_y(k), wk = mip.width(k), hk = mip.height(k);
    // Tile i of level L covers image coordinates [i k_tile / w_L, (i + 1) k_tile / w_L), cell c
    // of level k [c k_tile / w_k, (c + 1) k_tile / w_k): the cells overlapping the tile.
    for (int j = 0; j < ty; ++j) {
      const int c0y = std::min(cy - 1, int((long long)j * hk / hl));
      const int c1y = std::min(cy - 1, int(((long long)(j + 1) * hk + hl - 1) / hl) - 1);
      for (int i = 0; i < tx; ++i) {
        uint8_t& o = out[size_t(j) * size_t(tx) + size_t(i)];
        if (o) continue;
        const int c0x = std::min(cx - 1, int((long long)i * wk / wl));
        const int c1x = std::min(cx - 1, int(((long long)(i + 1) * wk + wl - 1) / wl) - 1);
        for (int y = c0y; y <= c1y && !o; ++y)
          for (int x = c0x; x <= c1x && !o; ++x) o = c[size_t(y) * size_t(cx) + size_t(x)];
      }
    }
  }
  return out;
}

void FootprintRecorder::record_uv(const Texture* texture, const Vec2f& uv, float footprint) {
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return;
  UvUse& u = by_uv[texture];
  const float f = std::isfinite(footprint) && footprint >= 0.f ? footprint : 0.f;
  // A footprint of 0 (a point lookup) says nothing about the resolution, only where it fell.
  if (f > 0.f) u.min_footprint = std::min(u.min_footprint, f);
  u.lo = Vec2f(std::min(u.lo.x, uv.x - f), std::min(u.lo.y, uv.y - f));
  u.hi = Vec2f(std::max(u.hi.x, uv.x + f), std::max(u.hi.y, uv.y + f));
  ++u.lookups;
}

void FootprintRecorder::merge(const FootprintRecorder& other) {
  for (const auto& [tex, use] : other.by_uv) {
    UvUse& u = by_uv[tex];
    u.min_footprint = std::min(u.min_footprint, use.min_footprint);
    u.lo = Vec2f(std::min(u.lo.x, use.lo.x), std::min(u.lo.y, use.lo.y));
    u.hi = Vec2f(std::max(u.hi.x, use.hi.x), std::max(u.hi.y, use.hi.y));
    u.lookups += use.lookups;
  }
  for (const auto& [mip, use] : other.by_mip) merge_use(by_mip[mip], use);
  for (const auto& [tex, use] : other.by_texture) merge_use(by_texture[tex], use);
}

std::atomic<int> g_footprint_recorders{0};

FootprintRecorder* thread_footprint_recorder() { return t_recorder; }

ScopedFootprintRecorder::ScopedFootprintRecorder(FootprintRecorder* recorder) : m_previous(t_recorder) {
  t_recorder = recorder;
  g_footprint_recorders.fetch_add(1, std::memory_order_relaxed);
}
ScopedFootprintRecorder::~ScopedFootprintRecorder() {
  t_recorder = m_previous;
  g_footprint_recorders.fetch_sub(1, std::memory_order_relaxed);
}

}  // namespace sg
