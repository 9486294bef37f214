#include "texture/footprint.h"

#include <algorithm>
#include <cmath>

#include "texture/mipmap.h"

namespace sg {

namespace {

thread_local FootprintRecorder* t_recorder = nullptr;

void add(FootprintRecorder::Use& u, const MipMap& mip, const Vec2f& a, const Vec2f& b) {
  const int n = mip.levels();
  if (u.min_rho.empty()) u.min_rho.assign(size_t(n), k_inf);
  for (int l = 0; l < n && l < int(u.min_rho.size()); ++l) {
    float w = float(mip.width(l)), h = float(mip.height(l));
    float ra = std::hypot(a.x * w, a.y * h), rb = std::hypot(b.x * w, b.y * h);
    float rho = std::max(ra, rb);
    if (!(rho >= 0.f)) continue;  // NaN footprints say nothing
    float& m = u.min_rho[size_t(l)];
    m = std::min(m, rho);
  }
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
  add(by_mip[&mip], mip, a, b);
  if (texture) add(by_texture[texture], mip, a, b);
}

void FootprintRecorder::merge(const FootprintRecorder& other) {
  for (const auto& [mip, use] : other.by_mip) merge_use(by_mip[mip], use);
  for (const auto& [tex, use] : other.by_texture) merge_use(by_texture[tex], use);
}

FootprintRecorder* active_footprint_recorder() { return t_recorder; }

ScopedFootprintRecorder::ScopedFootprintRecorder(FootprintRecorder* recorder) : m_previous(t_recorder) {
  t_recorder = recorder;
}
ScopedFootprintRecorder::~ScopedFootprintRecorder() { t_recorder = m_previous; }

}  // namespace sg
