#include "texture/baked.h"

#include <algorithm>
#include <cmath>
#include <thread>
#include <vector>

namespace sg {

BakedTexture::BakedTexture(std::shared_ptr<Texture> inner) : m_inner(std::move(inner)) {}

namespace {

/// The uv footprint of a lookup (the larger of its width and its ellipse's axes).
float uv_footprint(const TexturePoint& q) {
  const float fa = std::sqrt(std::max(q.uv_axis_a.x * q.uv_axis_a.x + q.uv_axis_a.y * q.uv_axis_a.y,
                                      q.uv_axis_b.x * q.uv_axis_b.x + q.uv_axis_b.y * q.uv_axis_b.y));
  return std::max(q.uv_footprint, fa);
}

/// The smallest power of two >= x (at least 1).
int pow2_at_least(double x) {
  int n = 1;
  while (n < x && n < (1 << 30)) n *= 2;
  return n;
}

}  // namespace

bool BakedTexture::lookup(const Vec2f& uv, float fp, Color* out) const {
  if (!m_mip || !(uv.x >= m_inner_lo.x && uv.x <= m_inner_hi.x && uv.y >= m_inner_lo.y && uv.y <= m_inner_hi.y))
    return false;
  const float ex = m_hi.x - m_lo.x, ey = m_hi.y - m_lo.y;
  // Square texels: a footprint of fp uv units is fp / max(extent) image widths.
  *out = m_mip->lookup((uv.x - m_lo.x) / ex, (uv.y - m_lo.y) / ey, fp / std::max(ex, ey), WrapMode::Clamp);
  return true;
}

Color BakedTexture::eval_point(const TexturePoint& q) const {
  const float fp = uv_footprint(q);
  if (FootprintRecorder* r = active_footprint_recorder()) r->record_uv(this, q.uv, fp);
  Color c;
  if (lookup(q.uv, fp, &c)) return c;
  return m_inner->eval_point(q);
}

Color BakedTexture::eval(const Vec2f& uv, float footprint) const {
  if (FootprintRecorder* r = active_footprint_recorder()) r->record_uv(this, uv, footprint);
  Color c;
  if (lookup(uv, footprint, &c)) return c;
  return m_inner->eval(uv, footprint);
}

void BakedTexture::clear() const { m_mip.reset(); }

bool BakedTexture::bake(const FootprintRecorder::UvUse& use, int threads) const {
  if (use.lookups == 0 || !(use.min_footprint > 0.f) || !std::isfinite(use.min_footprint) ||
      !(use.lo.x <= use.hi.x) || !(use.lo.y <= use.hi.y)) {
    clear();
    return false;
  }
  // NOTE: one texel per smallest footprint (the estimate's guarantee, texture/footprint.h:
  // at least one texel per pixel), the side rounded up to a power of two; the rectangle grows
  // by two texels on every side so that the bilinear taps of lookups at its edge stay inside.
  const double texel0 = use.min_footprint;
  const double ex = double(use.hi.x) - use.lo.x + 4 * texel0, ey = double(use.hi.y) - use.lo.y + 4 * texel0;
  const int w = pow2_at_least(ex / texel0), h = pow2_at_least(ey / texel0);
  if (w > k_max_side || h > k_max_side) {
    clear();
    return false;
  }
  const double texel = std::max(ex / w, ey / h);  // square texels covering the rectangle
  const Vec2f lo(float(0.5 * (use.lo.x + use.hi.x) - 0.5 * w * texel),
                 float(0.5 * (use.lo.y + use.hi.y) - 0.5 * h * texel));
  const Vec2f hi(float(lo.x + w * texel), float(lo.y + h * texel));
  if (m_mip && m_mip->width(0) == w && m_mip->height(0) == h && m_lo.x == lo.x && m_lo.y == lo.y &&
      m_hi.x == hi.x && m_hi.y == hi.y)
    return true;  // the same image as the last frame's
  ImageData img;
  img.width = w;
  img.height = h;
  img.channels = 3;
  img.pixels.resize(size_t(w) * h * 3);
  const int n = std::max(1, std::min(threads > 0 ? threads : int(std::thread::hardware_concurrency()), h));
  auto rows = [&](int first) {
    for (int y = first; y < h; y += n)
      for (int x = 0; x < w; ++x) {
        TexturePoint q;
        q.uv = Vec2f(float(lo.x + (x + 0.5) * texel), float(lo.y + (y + 0.5) * texel));
        q.uv_footprint = float(texel);  // the texel's own width: the procedural filters itself to it
        const Color c = m_inner->eval_point(q);
        float* p = &img.pixels[(size_t(y) * w + x) * 3];
        p[0] = c.x;
        p[1] = c.y;
        p[2] = c.z;
      }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < n; ++i) pool.emplace_back(rows, i);
  rows(0);
  for (auto& t : pool) t.join();
  m_mip = std::make_shared<const MipMap>(img);
  m_lo = lo;
  m_hi = hi;
  m_inner_lo = Vec2f(float(lo.x + texel), float(lo.y + texel));
  m_inner_hi = Vec2f(float(hi.x - texel), float(hi.y - texel));
  return true;
}

std::shared_ptr<Texture> make_baked_texture(std::shared_ptr<Texture> inner) {
  return std::make_shared<BakedTexture>(std::move(inner));
}

}  // namespace sg
