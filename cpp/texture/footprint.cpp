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
}

}  // namespace

int FootprintRecorder::Use::needed_level() const {
  int level = 0;
  for (size_t l = 0; l < min_rho.size(); ++l)
    if (min_rho[l] >= 1.f) level = int(l);
    else break;
  return level;
}

void FootprintRecorder::record(const Texture* texture, const MipMap& mip, Vec2f a, Vec2f b, const float m[4]) {
  if (a.x == 0.f && a.y == 0.f && b.x == 0.f && b.y == 0.f) {
    a = Vec2f(m[0] * hit_a.x + m[1] * hit_a.y, m[2] * hit_a.x + m[3] * hit_a.y);
    b = Vec2f(m[0] * hit_b.x + m[1] * hit_b.y, m[2] * hit_b.x + m[3] * hit_b.y);
  }
  const std::vector<float> rho = level_rho(mip, a, b);
  add(by_mip[&mip], rho);
  if (texture) add(by_texture[texture], rho);
}

void FootprintRecorder::merge(const FootprintRecorder& other) {
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
