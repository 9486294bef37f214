// Reduced NFOR denoiser (film/denoise.h). Every image lives in a Planes buffer: one padded
// plane per channel, the border replicated (clamp to edge), so that the NL-means patch and
// window loops run over contiguous memory without bounds checks; neighbours outside the image
// get weight 0. Work is split into fixed 32 x 16 tiles and every output pixel is computed by
// the same sequence of float operations whatever thread runs its tile: the result does not
// depend on the number of threads.
#include "film/denoise.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/error.h"

namespace sg {

namespace {

/// 8 floats in one SIMD register (GCC / Clang vector extension).
typedef float V8 __attribute__((vector_size(32)));
typedef float V16 __attribute__((vector_size(64)));

constexpr int k_tile_w = 32;
constexpr int k_tile_h = 16;
/// Regression unknowns: x, y, depth, normal (3), mean albedo, and the constant -- last, so
/// that the estimate at the window's centre comes out of the forward substitution alone.
constexpr int k_dims = 8;
/// Prefiltered feature channels: albedo (3), normal (3), normalised depth.
constexpr int k_feature_channels = 7;
constexpr float k_dist_eps = 1e-10f;
constexpr float k_dist_clamp = 1e4f;
/// Neighbours whose weight is below this are skipped by the regression.
constexpr float k_min_weight = 1e-4f;
/// Neighbours at least this heavy bound the regression's output (see regress()).
constexpr float k_range_weight = 1e-2f;
/// The spread excess of clamped outliers adds at most this fraction to a pixel. Measured on
/// the default scene's sun caustic sample (one pixel of 1217 where the reference has < 2):
/// denoised / raw 64 spp relMSE 4.64 at 1, 1.22 at 0.25, 0.84 at 0.1, 0.66 at 0; the other
/// regression scenes and every mean are unchanged to 0.01%.
constexpr float k_spread_cap = 0.1f;
/// Input radiance beyond this is clamped (keeps squared differences finite in float).
constexpr float k_max_radiance = 1e9f;

struct TileRect {
  int x0, y0, w, h;
};

/// A multi-channel image, one plane per channel, each padded by `pad` pixels on every side.
struct Planes {
  int channels = 0, width = 0, height = 0, pad = 0, stride = 0;
  size_t plane_size = 0;
  /// Not value-initialised: every user writes what it reads (allocate(..., true) zeroes).
  std::unique_ptr<float[]> data;

  void allocate(int c, int w, int h, int p, bool zero = false) {
    channels = c;
    width = w;
    height = h;
    pad = p;
    stride = w + 2 * p;
    plane_size = size_t(stride) * size_t(h + 2 * p);
    data.reset(new float[size_t(c) * plane_size]);
    if (zero) std::fill(data.get(), data.get() + size_t(c) * plane_size, 0.f);
  }
  float* plane(int c) { return data.get() + size_t(c) * plane_size; }
  const float* plane(int c) const { return data.get() + size_t(c) * plane_size; }
  void copy_from(const Planes& o) {
    allocate(o.channels, o.width, o.height, o.pad);
    std::copy(o.data.get(), o.data.get() + size_t(channels) * plane_size, data.get());
  }
  /// Index into a plane of pixel (x, y); x, y may lie in the padding.
  size_t index(int x, int y) const { return size_t(y + pad) * size_t(stride) + size_t(x + pad); }

  /// Replicates the outermost pixels into the padding.
  void fill_border() {
    for (int c = 0; c < channels; ++c) {
      float* p = plane(c);
      for (int y = 0; y < height; ++y) {
        float* row = p + index(0, y);
        std::fill(row - pad, row, row[0]);
        std::fill(row + width, row + width + pad, row[width - 1]);
      }
      const float* top = p + index(-pad, 0);
      const float* bottom = p + index(-pad, height - 1);
      for (int y = 1; y <= pad; ++y) {
        std::copy(top, top + stride, p + index(-pad, -y));
        std::copy(bottom, bottom + stride, p + index(-pad, height - 1 + y));
      }
    }
  }
};

template <class Fn>
void for_each_tile(int w, int h, Fn&& fn) {
  const int tx = (w + k_tile_w - 1) / k_tile_w, ty = (h + k_tile_h - 1) / k_tile_h;
  tbb::parallel_for(tbb::blocked_range<int>(0, tx * ty, 1), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i != r.end(); ++i) {
      TileRect t;
      t.x0 = (i % tx) * k_tile_w;
      t.y0 = (i / tx) * k_tile_h;
      t.w = std::min(k_tile_w, w - t.x0);
      t.h = std::min(k_tile_h, h - t.y0);
      fn(t);
    }
  });
}

/// exp(-x) for x >= 0, a few 1e-7 relative error. NOTE: Cephes' exp2f: 2^t = 2^round(t) *
/// 2^f, f in [-1/2, 1/2], 2^f by its degree-6 polynomial, 2^round(t) built in the exponent
/// bits; a loop of these vectorises where std::exp does not (no -ffast-math here).
inline float exp_neg(float x) {
  const float t = -std::min(x, 87.f) * 1.44269504088896341f;
  // NOTE: round to nearest by adding and subtracting 1.5 * 2^23 (|t| < 2^22): std::floor
  // keeps GCC from vectorising the loop; without -ffast-math the sum is not folded away.
  const float r = (t + 12582912.f) - 12582912.f;
  const float f = t - r;
  float p = 1.535336188319500e-4f;
  p = p * f + 1.339887440266574e-3f;
  p = p * f + 9.618437357674640e-3f;
  p = p * f + 5.550332471162809e-2f;
  p = p * f + 2.402264791363012e-1f;
  p = p * f + 6.931472028550421e-1f;
  p = p * f + 1.f;
  const int32_t bits = (int32_t(r) + 127) << 23;
  float scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}

/// Scratch of one tile's distance computation.
struct DistanceScratch {
  std::vector<float> patch, rows;
};

/// The NL-means distance between the patches of every pixel p of tile `t` and of p + (ox, oy),
/// in guide `g` with per-channel variance `v`, into out[(y - t.y0) * t.w + x - t.x0].
/// NOTE: Rousselle, Knaus & Zwicker 2012 ("Adaptive rendering with non-local means
/// filtering", the variance-cancelled distance of their NL-means), as used by NFOR (Bitterli
/// et al. 2016, sec. 5.2): per pixel and channel d = ((u_p - u_q)^2 - (Var_p + min(Var_p,
/// Var_q))) / (eps + Var_p + Var_q), averaged over channels and over the (2F+1)^2 patch
/// (a separable box sum: the per-offset "shifted image" evaluation that shares each pixel's
/// term among the patches covering it). Computed with k = 1; for bandwidth k the distance is
/// this / k^2 (exact up to eps / k^2).
void patch_distances(const Planes& g, const Planes& v, const TileRect& t, int ox, int oy, int F,
                     DistanceScratch& s, float* out) {
  const int pw = t.w + 2 * F, ph = t.h + 2 * F;
  s.patch.resize(size_t(pw) * ph);
  s.rows.resize(size_t(t.w) * ph);
  const ptrdiff_t shift = ptrdiff_t(oy) * g.stride + ox;
  for (int yy = 0; yy < ph; ++yy) {
    float* dst = s.patch.data() + size_t(yy) * pw;
    std::fill(dst, dst + pw, 0.f);
    const size_t p0 = g.index(t.x0 - F, t.y0 - F + yy);
    for (int c = 0; c < g.channels; ++c) {
      const float* gp = g.plane(c) + p0;
      const float* gq = gp + shift;
      const float* vp = v.plane(c) + p0;
      const float* vq = vp + shift;
      for (int x = 0; x < pw; ++x) {
        const float d = gp[x] - gq[x];
        const float num = d * d - (vp[x] + std::min(vp[x], vq[x]));
        dst[x] += num / (k_dist_eps + vp[x] + vq[x]);
      }
    }
  }
  for (int yy = 0; yy < ph; ++yy) {
    const float* src = s.patch.data() + size_t(yy) * pw;
    float* dst = s.rows.data() + size_t(yy) * t.w;
    std::copy(src, src + t.w, dst);
    for (int i = 1; i <= 2 * F; ++i)
      for (int x = 0; x < t.w; ++x) dst[x] += src[x + i];
  }
  const float scale = 1.f / (float(g.channels) * float((2 * F + 1) * (2 * F + 1)));
  for (int y = 0; y < t.h; ++y) {
    float* dst = out + size_t(y) * t.w;
    const float* src = s.rows.data() + size_t(y) * t.w;
    std::copy(src, src + t.w, dst);
    for (int j = 1; j <= 2 * F; ++j) {
      const float* r = src + size_t(j) * t.w;
      for (int x = 0; x < t.w; ++x) dst[x] += r[x];
    }
    for (int x = 0; x < t.w; ++x) dst[x] = std::min(dst[x] * scale, k_dist_clamp);
  }
}

/// NL-means weights exp(-max(0, d) / k^2) of one offset over a tile, 0 where p + (ox, oy)
/// leaves the image. NOTE: the distance is clamped at 0 (Rousselle et al. 2012: the
/// variance cancellation can make it negative; a patch is never nearer than itself).
void offset_weights(const float* dist, const TileRect& t, int ox, int oy, int width, int height, float inv_k2,
                    float* w) {
  const int n = t.w * t.h;
  for (int i = 0; i < n; ++i) w[i] = exp_neg(std::max(dist[i], 0.f) * inv_k2);
  const int xb = std::max(0, -ox - t.x0), xe = std::min(t.w, width - ox - t.x0);
  for (int y = 0; y < t.h; ++y) {
    float* row = w + size_t(y) * t.w;
    const int gy = t.y0 + y + oy;
    if (gy < 0 || gy >= height || xb >= xe) {
      std::fill(row, row + t.w, 0.f);
      continue;
    }
    std::fill(row, row + std::max(xb, 0), 0.f);
    std::fill(row + std::min(std::max(xe, 0), t.w), row + t.w, 0.f);
  }
}

/// Zeroth-order NL-means: out = the weighted mean of `img` over a (2R+1)^2 window, weights from
/// `g` (variance `v`), patches (2F+1)^2, bandwidth k. Writes out's interior (not its border).
void nlmeans(const Planes& img, const Planes& g, const Planes& v, int F, int R, float k, Planes& out) {
  const int W = img.width, H = img.height, C = img.channels;
  const float inv_k2 = 1.f / (k * k);
  struct Scratch {
    DistanceScratch d;
    std::vector<float> dist, w, acc;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  for_each_tile(W, H, [&](const TileRect& t) {
    Scratch& s = scratch.local();
    const int n = t.w * t.h;
    s.dist.resize(n);
    s.w.resize(n);
    s.acc.assign(size_t(C + 1) * n, 0.f);
    float* sum_w = s.acc.data() + size_t(C) * n;
    for (int oy = -R; oy <= R; ++oy) {
      for (int ox = -R; ox <= R; ++ox) {
        patch_distances(g, v, t, ox, oy, F, s.d, s.dist.data());
        offset_weights(s.dist.data(), t, ox, oy, W, H, inv_k2, s.w.data());
        for (int y = 0; y < t.h; ++y) {
          const float* wr = s.w.data() + size_t(y) * t.w;
          float* sw = sum_w + size_t(y) * t.w;
          for (int x = 0; x < t.w; ++x) sw[x] += wr[x];
          const size_t q0 = img.index(t.x0 + ox, t.y0 + y + oy);
          for (int c = 0; c < C; ++c) {
            const float* src = img.plane(c) + q0;
            float* a = s.acc.data() + size_t(c) * n + size_t(y) * t.w;
            for (int x = 0; x < t.w; ++x) a[x] += wr[x] * src[x];
          }
        }
      }
    }
    for (int c = 0; c < C; ++c) {
      for (int y = 0; y < t.h; ++y) {
        float* dst = out.plane(c) + out.index(t.x0, t.y0 + y);
        const float* a = s.acc.data() + size_t(c) * n + size_t(y) * t.w;
        const float* sw = sum_w + size_t(y) * t.w;
        // The centre's own weight is 1 (distance <= 0), so sum_w >= 1.
        for (int x = 0; x < t.w; ++x) dst[x] = a[x] / sw[x];
      }
    }
  });
}

/// 3 x 3 box mean of each channel (clamped border) into out's interior.
void box3(const Planes& in, Planes& out) {
  for (int c = 0; c < in.channels; ++c) {
    const float* p = in.plane(c);
    float* o = out.plane(c);
    const ptrdiff_t st = in.stride;
    tbb::parallel_for(tbb::blocked_range<int>(0, in.height, 16), [&](const tbb::blocked_range<int>& r) {
      for (int y = r.begin(); y != r.end(); ++y) {
        const float* src = p + in.index(0, y);
        float* dst = o + out.index(0, y);
        for (int x = 0; x < in.width; ++x) {
          float s = 0.f;
          for (int j = -1; j <= 1; ++j)
            s += src[x + j * st - 1] + src[x + j * st] + src[x + j * st + 1];
          dst[x] = s * (1.f / 9.f);
        }
      }
    });
  }
}

/// Normal equations of up to k_batch regressions (two candidates of one tile row), one lane
/// per system (structure of arrays, so that the solve vectorises across systems).
constexpr int k_batch = 2 * k_tile_w;
struct Systems {
  alignas(64) float m[k_dims][k_dims][k_batch];
  alignas(64) float r[3][k_dims][k_batch];
  alignas(64) float out[3][k_batch];
};

/// Solves (m + ridge) beta = r (three right-hand sides) of the first `count` systems by
/// Cholesky and writes beta's constant term (the last unknown) to out; a system that is not
/// positive definite gets the weighted mean (the zeroth-order estimate) instead.
/// NOTE: float: the ridge (times the sum of weights, on features scaled to about [-1, 1])
/// bounds the condition number near 1e3, so float keeps about 4 digits; the same
/// operations in every lane whatever the batch, so the result does not depend on threads.
void solve_batch(Systems& s, int count, float ridge) {
  alignas(64) float L[k_dims][k_dims][k_batch];
  alignas(64) float inv[k_dims][k_batch];
  alignas(64) float ok[k_batch];
  alignas(64) float acc[k_batch];
  const int n = count;
  for (int l = 0; l < n; ++l) ok[l] = 1.f;
  for (int i = 0; i < k_dims; ++i) {
    for (int j = 0; j <= i; ++j) {
      for (int l = 0; l < n; ++l) acc[l] = s.m[i][j][l];
      for (int k = 0; k < j; ++k)
        for (int l = 0; l < n; ++l) acc[l] -= L[i][k][l] * L[j][k][l];
      if (j < i) {
        for (int l = 0; l < n; ++l) L[i][j][l] = acc[l] * inv[j][l];
      } else {
        const float lambda = i < k_dims - 1 ? ridge : 0.f;
        for (int l = 0; l < n; ++l) {
          const float total = s.m[k_dims - 1][k_dims - 1][l];
          const float d = acc[l] + lambda * total;
          const bool good = d > 1e-6f * total;
          ok[l] = good ? ok[l] : 0.f;
          inv[i][l] = 1.f / std::sqrt(good ? d : 1.f);
        }
      }
    }
  }
  for (int c = 0; c < 3; ++c) {
    alignas(64) float z[k_dims][k_batch];
    for (int i = 0; i < k_dims; ++i) {
      for (int l = 0; l < n; ++l) acc[l] = s.r[c][i][l];
      for (int k = 0; k < i; ++k)
        for (int l = 0; l < n; ++l) acc[l] -= L[i][k][l] * z[k][l];
      for (int l = 0; l < n; ++l) z[i][l] = acc[l] * inv[i][l];
    }
    // NOTE: with the constant as the last unknown, L^T beta = z gives it directly.
    for (int l = 0; l < n; ++l) {
      const float beta = z[k_dims - 1][l] * inv[k_dims - 1][l];
      const float mean = s.r[c][k_dims - 1][l] / s.m[k_dims - 1][k_dims - 1][l];
      s.out[c][l] = (ok[l] != 0.f && std::isfinite(beta)) ? beta : mean;
    }
  }
}

/// First-order regression of one half (img, 3 planes) on the features X (8
/// floats per padded pixel, same layout as the planes), weights from the other half (guide
/// g, variance v), at bandwidths k and k / 2: into out_k[0] (k) and out_k[1] (k / 2), 3
/// planes each.
/// NOTE: NFOR (Bitterli et al. 2016, sec. 4 and 5.2): per pixel p, minimise
/// sum_q w_pq (y_q - beta^T x_q)^2 over the window, with x_q = the features of q minus those
/// of p (and 1): the estimate at p is beta's constant term. Unlike Tungsten's collaborative
/// variant only the centre is reconstructed (one solve per pixel, no gather of windows).
void regress(const Planes& img, const float* X, const Planes& g, const Planes& v,
             const DenoiseSettings& st, Planes* out_k) {
  const int W = g.width, H = g.height, R = st.radius, F = st.patch_radius;
  const int side = 2 * R + 1, n_off = side * side;
  const float inv_k2 = 1.f / (st.k * st.k);
  std::vector<ptrdiff_t> shifts(n_off);
  for (int oy = -R; oy <= R; ++oy)
    for (int ox = -R; ox <= R; ++ox) shifts[size_t((oy + R) * side + ox + R)] = ptrdiff_t(oy) * g.stride + ox;
  struct Scratch {
    DistanceScratch d;
    std::vector<float> dist, w;
    std::unique_ptr<Systems> sys{new Systems};
    float lo[3][k_tile_w], hi[3][k_tile_w];
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  for_each_tile(W, H, [&](const TileRect& t) {
    Scratch& s = scratch.local();
    Systems& sys = *s.sys;
    const int n = t.w * t.h;
    s.dist.resize(n);
    s.w.resize(size_t(n_off) * n);
    for (int oy = -R; oy <= R; ++oy) {
      for (int ox = -R; ox <= R; ++ox) {
        patch_distances(g, v, t, ox, oy, F, s.d, s.dist.data());
        offset_weights(s.dist.data(), t, ox, oy, W, H, inv_k2,
                       s.w.data() + size_t((oy + R) * side + ox + R) * n);
      }
    }
    for (int y = 0; y < t.h; ++y) {
      for (int x = 0; x < t.w; ++x) {
        const int i = y * t.w + x;
        const size_t p = g.index(t.x0 + x, t.y0 + y);
        V8 xc;
        std::memcpy(&xc, &X[p * k_dims], sizeof xc);
        xc[k_dims - 1] = 0.f;  // the constant column stays 1
        // Both candidates at once: lanes 0-7 accumulate with weight w (bandwidth k), lanes
        // 8-15 with w^4 (k / 2).
        V16 m[k_dims], r[3];
        for (int a = 0; a < k_dims; ++a) m[a] = V16{};
        for (int c = 0; c < 3; ++c) r[c] = V16{};
        float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                       std::numeric_limits<float>::max()};
        float hi[3] = {-lo[0], -lo[0], -lo[0]};
        for (int o = 0; o < n_off; ++o) {
          const float w1 = s.w[size_t(o) * n + i];
          if (w1 < k_min_weight) continue;
          // NOTE: the weight at bandwidth k / 2 is exp(-d / (k/2)^2) = (exp(-d / k^2))^4.
          const float w2 = (w1 * w1) * (w1 * w1);
          const size_t q = size_t(ptrdiff_t(p) + shifts[size_t(o)]);
          const float yq[3] = {img.plane(0)[q], img.plane(1)[q], img.plane(2)[q]};
          V8 d;
          std::memcpy(&d, &X[q * k_dims], sizeof d);
          d -= xc;
          const V8 wd1 = w1 * d, wd2 = w2 * d;
          const V16 wd = __builtin_shufflevector(wd1, wd2, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
          // Full (symmetric) normal matrices, one 16-wide row (both candidates) per unknown.
          for (int a = 0; a < k_dims; ++a) m[a] += d[a] * wd;
          for (int c = 0; c < 3; ++c) r[c] += yq[c] * wd;
          if (w1 >= k_range_weight)
            for (int c = 0; c < 3; ++c) {
              lo[c] = std::min(lo[c], yq[c]);
              hi[c] = std::max(hi[c], yq[c]);
            }
        }
        // Candidate k into lane x, candidate k / 2 into lane t.w + x.
        for (int a = 0; a < k_dims; ++a)
          for (int b = 0; b < k_dims; ++b) {
            sys.m[a][b][x] = m[a][b];
            sys.m[a][b][t.w + x] = m[a][b + 8];
          }
        for (int c = 0; c < 3; ++c) {
          for (int b = 0; b < k_dims; ++b) {
            sys.r[c][b][x] = r[c][b];
            sys.r[c][b][t.w + x] = r[c][b + 8];
          }
          s.lo[c][x] = lo[c];
          s.hi[c][x] = hi[c];
        }
      }
      solve_batch(sys, 2 * t.w, st.ridge);
      // NOTE: not in NFOR: the regression may extrapolate where a feature changes little and
      // its slope is ill-determined; the estimate is kept within the range of the values of
      // the neighbours of weight >= 1e-2 (the centre among them).
      for (int cand = 0; cand < 2; ++cand)
        for (int c = 0; c < 3; ++c) {
          float* dst = out_k[cand].plane(c) + out_k[cand].index(t.x0, t.y0 + y);
          for (int x = 0; x < t.w; ++x)
            dst[x] = std::min(std::max(sys.out[c][cand * t.w + x], s.lo[c][x]), s.hi[c][x]);
        }
    }
  });
}

/// fn(y) for every row y in [y0, y1), rows in parallel (each row's result independent of the
/// others: no reduction across rows).
template <class Fn>
void for_rows(int y0, int y1, Fn&& fn) {
  tbb::parallel_for(tbb::blocked_range<int>(y0, y1, 8), [&](const tbb::blocked_range<int>& r) {
    for (int y = r.begin(); y != r.end(); ++y) fn(y);
  });
}

inline float finite_or(float v, float fallback) { return std::isfinite(v) ? v : fallback; }

}  // namespace

void denoise(const DenoiseInput& in, const DenoiseSettings& st, float* out_rgb) {
  if (in.width == 0 || in.height == 0) throw Error("denoise: the image is empty (width or height 0)");
  for (int h = 0; h < 2; ++h)
    if (!in.rgb[h] || !in.albedo[h] || !in.normal[h] || !in.depth[h])
      throw Error("denoise: a radiance or feature buffer is missing (null)");
  if (!out_rgb) throw Error("denoise: no output buffer");
  if (st.radius < 1 || st.radius > 20)
    throw Error("denoise: radius must be in [1, 20], got " + std::to_string(st.radius));
  if (st.patch_radius < 0 || st.patch_radius > 10)
    throw Error("denoise: patch_radius must be in [0, 10], got " + std::to_string(st.patch_radius));
  if (st.feature_radius < 0 || st.feature_radius > 20)
    throw Error("denoise: feature_radius must be in [0, 20], got " + std::to_string(st.feature_radius));
  if (st.selection_radius < 0 || st.selection_radius > 20)
    throw Error("denoise: selection_radius must be in [0, 20], got " + std::to_string(st.selection_radius));
  if (!(st.k > 0.f) || !std::isfinite(st.k)) throw Error("denoise: k must be positive");
  if (!(st.albedo_floor >= 0.f) || !std::isfinite(st.albedo_floor))
    throw Error("denoise: albedo_floor must be >= 0");
  if (!(st.ridge >= 0.f) || !std::isfinite(st.ridge)) throw Error("denoise: ridge must be >= 0");
  if (!(st.firefly_ratio >= 0.f) || !std::isfinite(st.firefly_ratio))
    throw Error("denoise: firefly_ratio must be >= 0");

  const int W = int(in.width), H = int(in.height);
  const size_t n = size_t(W) * size_t(H);
  const int pad = std::max({st.radius + st.patch_radius, st.feature_radius + 3, st.selection_radius + 1, 1});

  // --- Features: albedo (3), normal (3), normalised depth, per half.
  // NOTE: not in NFOR: depth is mapped to d / (d + s), s the median depth of the image, so
  // that the background (+inf) is the finite value 1 and far geometry does not dominate.
  std::vector<float> finite_depths;
  finite_depths.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const float a = in.depth[0][i], b = in.depth[1][i];
    const float d = 0.5f * (a + b);
    if (std::isfinite(d) && d > 0.f) finite_depths.push_back(d);
  }
  float depth_scale = 1.f;
  if (!finite_depths.empty()) {
    auto mid = finite_depths.begin() + ptrdiff_t(finite_depths.size() / 2);
    std::nth_element(finite_depths.begin(), mid, finite_depths.end());
    depth_scale = std::max(*mid, 1e-6f);
  }
  std::vector<float>().swap(finite_depths);

  Planes feat[2];
  for (int h = 0; h < 2; ++h) {
    feat[h].allocate(k_feature_channels, W, H, pad);
    for_rows(0, H, [&](int y) {
      for (int x = 0; x < W; ++x) {
        const size_t i = size_t(y) * W + x, p = feat[h].index(x, y);
        for (int c = 0; c < 3; ++c) {
          feat[h].plane(c)[p] = std::max(finite_or(in.albedo[h][3 * i + c], 0.f), 0.f);
          feat[h].plane(3 + c)[p] = std::min(std::max(finite_or(in.normal[h][3 * i + c], 0.f), -1.f), 1.f);
        }
        const float d = in.depth[h][i];
        feat[h].plane(6)[p] = (std::isfinite(d) && d > 0.f) ? d / (d + depth_scale) : 1.f;
      }
    });
    feat[h].fill_border();
  }
  const bool split_features =
      in.albedo[0] != in.albedo[1] || in.normal[0] != in.normal[1] || in.depth[0] != in.depth[1];
  if (split_features && st.feature_radius > 0) {
    // NOTE: NFOR sec. 5.1 (feature prefiltering): each half's features are NL-means filtered
    // with weights from the other half (patches 7 x 7, window (2 feature_radius + 1)^2, k 0.5), the
    // variance being that of a half, estimated as (A - B)^2 / 2 (3 x 3 mean).
    Planes diff, var;
    diff.allocate(k_feature_channels, W, H, pad);
    var.allocate(k_feature_channels, W, H, pad);
    for (int c = 0; c < k_feature_channels; ++c) {
      const float* a = feat[0].plane(c);
      const float* b = feat[1].plane(c);
      float* o = diff.plane(c);
      for (size_t i = 0; i < diff.plane_size; ++i) o[i] = 0.5f * (a[i] - b[i]) * (a[i] - b[i]);
    }
    box3(diff, var);
    var.fill_border();
    Planes filtered[2];
    for (int h = 0; h < 2; ++h) {
      filtered[h].allocate(k_feature_channels, W, H, pad);
      nlmeans(feat[h], feat[1 - h], var, 3, st.feature_radius, 0.5f, filtered[h]);
      filtered[h].fill_border();
    }
    feat[0] = std::move(filtered[0]);
    feat[1] = std::move(filtered[1]);
  }

  // --- Demodulation: radiance / max(albedo, floor), the albedo being the halves' mean.
  // NOTE: albedo demodulation (as Bako et al. 2017, "Kernel-predicting convolutional
  // networks", do for the diffuse part, and Schied et al. 2017, SVGF): texture is divided
  // out before filtering and multiplied back after, so the filter
  // sees the smooth irradiance and the texture stays sharp. The floor keeps black albedo
  // (background, emitters) finite; the same divisor is used both ways, so a noise-free
  // image is returned unchanged.
  Planes divisor;
  divisor.allocate(3, W, H, pad);
  for (int c = 0; c < 3; ++c) {
    float* o = divisor.plane(c);
    const float* a = feat[0].plane(c);
    const float* b = feat[1].plane(c);
    for (size_t i = 0; i < divisor.plane_size; ++i)
      o[i] = st.albedo_floor > 0.f ? std::max(0.5f * (a[i] + b[i]), st.albedo_floor) : 1.f;
  }
  Planes rad[2];
  for (int h = 0; h < 2; ++h) {
    rad[h].allocate(3, W, H, pad);
    for (int c = 0; c < 3; ++c) {
      float* o = rad[h].plane(c);
      const float* dv = divisor.plane(c);
      for_rows(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
          const size_t i = size_t(y) * W + x, p = rad[h].index(x, y);
          const float v = std::min(std::max(finite_or(in.rgb[h][3 * i + c], 0.f), -k_max_radiance), k_max_radiance);
          o[p] = v / dv[p];
        }
      });
    }
    rad[h].fill_border();
  }

  // --- Outliers (fireflies): each half is clamped against the other half's neighbourhood.
  // NOTE: not in NFOR, whose cross filtering spreads a firefly of one half over the window
  // (and the first-order fit may amplify it). A value of half A above
  // firefly_ratio * max(3 x 3 of B) + the image mean of B is clamped there; what was cut (in
  // radiance) is added back spread over a (2 * radius + 1)^2 box, so the energy -- the image
  // mean -- is kept up to k_spread_cap (an energy-preserving take on outlier rejection, cf.
  // Zirr, Hanika & Dachsbacher 2018, "Re-weighting firefly samples", which spreads rather
  // than discards the outliers' energy). Signal that both halves see is not clamped.
  Planes residual;
  residual.allocate(3, W, H, pad, true);
  if (st.firefly_ratio > 0.f) {
    Planes clamped[2];
    for (int h = 0; h < 2; ++h) {
      clamped[h].copy_from(rad[h]);
      for (int c = 0; c < 3; ++c) {
        const float* o = rad[1 - h].plane(c);
        double sum = 0.0;
        for (int y = 0; y < H; ++y)
          for (int x = 0; x < W; ++x) sum += double(o[rad[h].index(x, y)]);
        const float floor_c = float(sum / double(n));
        const float* a = rad[h].plane(c);
        const float* dv = divisor.plane(c);
        float* dst = clamped[h].plane(c);
        float* res = residual.plane(c);
        const ptrdiff_t stv = rad[h].stride;
        for_rows(0, H, [&](int y) {
          for (int x = 0; x < W; ++x) {
            const size_t p = rad[h].index(x, y);
            float m = o[p];
            for (int j = -1; j <= 1; ++j)
              for (int i = -1; i <= 1; ++i) m = std::max(m, o[ptrdiff_t(p) + j * stv + i]);
            const float limit = st.firefly_ratio * m + floor_c;
            if (a[p] > limit) {
              res[p] += 0.5f * (a[p] - limit) * dv[p];
              dst[p] = limit;
            }
          }
        });
      }
      clamped[h].fill_border();
    }
    rad[0] = std::move(clamped[0]);
    rad[1] = std::move(clamped[1]);
    // Spread: separable box of radius `radius` (border replicated).
    residual.fill_border();
    Planes tmp;
    tmp.allocate(3, W, H, pad);
    const int r = std::min(st.radius, pad);
    const float norm = 1.f / float((2 * r + 1) * (2 * r + 1));
    for (int c = 0; c < 3; ++c) {
      const float* src = residual.plane(c);
      float* t = tmp.plane(c);
      for_rows(-pad, H + pad, [&](int y) {
        for (int x = 0; x < W; ++x) {
          float s = 0.f;
          const size_t p = residual.index(x, y);
          for (int i = -r; i <= r; ++i) s += src[ptrdiff_t(p) + i];
          t[p] = s;
        }
      });
    }
    for (int c = 0; c < 3; ++c) {
      const float* t = tmp.plane(c);
      float* dst = residual.plane(c);
      for_rows(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
          float s = 0.f;
          const size_t p = residual.index(x, y);
          for (int j = -r; j <= r; ++j) s += t[ptrdiff_t(p) + ptrdiff_t(j) * residual.stride];
          dst[p] = s * norm;
        }
      });
    }
  }

  // --- Variance of one half (demodulated).
  Planes var;
  var.allocate(3, W, H, pad);
  if (in.variance) {
    for (int c = 0; c < 3; ++c) {
      const float* dv = divisor.plane(c);
      for_rows(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
          const size_t i = size_t(y) * W + x, p = var.index(x, y);
          const float v = std::max(finite_or(in.variance[3 * i + c], 0.f), 0.f);
          // A half has half the samples: twice the variance of the mean.
          var.plane(c)[p] = 2.f * v / (dv[p] * dv[p]);
        }
      });
    }
  } else {
    // NOTE: the dual-buffer estimate (Rousselle et al. 2012): E[(A - B)^2] = 2 Var(half),
    // averaged over 3 x 3 pixels to tame its chi-square noise.
    Planes diff;
    diff.allocate(3, W, H, pad);
    for (int c = 0; c < 3; ++c) {
      const float* a = rad[0].plane(c);
      const float* b = rad[1].plane(c);
      float* o = diff.plane(c);
      for (size_t i = 0; i < diff.plane_size; ++i) o[i] = 0.5f * (a[i] - b[i]) * (a[i] - b[i]);
    }
    box3(diff, var);
  }
  var.fill_border();

  // --- Regression features, 8 per padded pixel: x / R, y / R, depth, normal, mean albedo, 1
  // (one set when both halves share their features).
  const bool same_features = !(split_features && st.feature_radius > 0);
  std::unique_ptr<float[]> X[2];
  const size_t padded = feat[0].plane_size;
  const float inv_r = 1.f / float(st.radius);
  for (int h = 0; h < (same_features ? 1 : 2); ++h) {
    X[h].reset(new float[padded * k_dims]);
    for_rows(-pad, H + pad, [&](int y) {
      for (int x = -pad; x < W + pad; ++x) {
        const size_t p = feat[h].index(x, y);
        float* f = &X[h][p * k_dims];
        f[0] = float(x) * inv_r;
        f[1] = float(y) * inv_r;
        f[2] = feat[h].plane(6)[p];
        f[3] = feat[h].plane(3)[p];
        f[4] = feat[h].plane(4)[p];
        f[5] = feat[h].plane(5)[p];
        f[6] = (feat[h].plane(0)[p] + feat[h].plane(1)[p] + feat[h].plane(2)[p]) * (1.f / 3.f);
        f[7] = 1.f;
      }
    });
  }
  for (auto& f : feat) f.data.reset();
  const float* features[2] = {X[0].get(), same_features ? X[0].get() : X[1].get()};

  // --- Cross-filtered regression: half A with weights from B (and B's features), and back.
  // NOTE: NFOR sec. 5.2: the weights of one half come from the other, so a half's filtered
  // value is not correlated with its own noise through its weights.
  Planes cand[2][2];  // [half][bandwidth k, k / 2]
  for (int h = 0; h < 2; ++h) {
    for (int b = 0; b < 2; ++b) cand[h][b].allocate(3, W, H, pad);
    regress(rad[h], features[1 - h], rad[1 - h], var, st, cand[h]);
  }

  // --- Error of each candidate, from the halves.
  // NOTE: NFOR sec. 5.3: with B independent of the filtered A, E[(A_f - B)^2] = MSE(A_f) +
  // Var(B); so MSE(A_f) ~ (A_f - B)^2 - Var(B), and likewise for B_f. The output is
  // (A_f + B_f) / 2, whose squared error is ((a^2 + b^2) / 2 - ((a - b) / 2)^2) with a, b
  // the halves' errors: hence the last term -(A_f - B_f)^2 / 4.
  Planes mse, mean_rad, mean_var;
  mse.allocate(6, W, H, pad);
  mean_rad.allocate(3, W, H, pad);
  mean_var.allocate(3, W, H, pad);
  for (int c = 0; c < 3; ++c) {
    const float* a = rad[0].plane(c);
    const float* b = rad[1].plane(c);
    const float* v = var.plane(c);
    for (size_t i = 0; i < mse.plane_size; ++i) {
      mean_rad.plane(c)[i] = 0.5f * (a[i] + b[i]);
      mean_var.plane(c)[i] = 0.5f * v[i];
    }
    for (int bw = 0; bw < 2; ++bw) {
      const float* fa = cand[0][bw].plane(c);
      const float* fb = cand[1][bw].plane(c);
      float* o = mse.plane(3 * bw + c);
      for_rows(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
          const size_t p = mse.index(x, y);
          const float ea = (fa[p] - b[p]) * (fa[p] - b[p]) - v[p];
          const float eb = (fb[p] - a[p]) * (fb[p] - a[p]) - v[p];
          const float dab = fa[p] - fb[p];
          o[p] = 0.5f * (ea + eb) - 0.25f * dab * dab;
        }
      });
    }
  }
  mse.fill_border();
  // NOTE: NFOR sec. 5.3: the error estimates and then the binary selection map are NL-means
  // filtered (patches 3 x 3, k 1) guided by the mean image before the per-pixel blend.
  Planes mse_f, select, select_f;
  mse_f.allocate(6, W, H, pad);
  nlmeans(mse, mean_rad, mean_var, 1, st.selection_radius, 1.f, mse_f);
  select.allocate(3, W, H, pad);
  for (int c = 0; c < 3; ++c)
    for_rows(0, H, [&](int y) {
      for (int x = 0; x < W; ++x) {
        const size_t p = select.index(x, y);
        select.plane(c)[p] = mse_f.plane(3 + c)[p] < mse_f.plane(c)[p] ? 1.f : 0.f;
      }
    });
  select.fill_border();
  select_f.allocate(3, W, H, pad);
  nlmeans(select, mean_rad, mean_var, 1, st.selection_radius, 1.f, select_f);

  // --- Blend the candidates, average the halves.
  Planes blended, blend_var;
  blended.allocate(3, W, H, pad);
  blend_var.allocate(3, W, H, pad);
  for (int c = 0; c < 3; ++c)
    for_rows(0, H, [&](int y) {
      for (int x = 0; x < W; ++x) {
        const size_t p = select_f.index(x, y);
        const float s = select_f.plane(c)[p];
        const float a = cand[0][0].plane(c)[p] + s * (cand[0][1].plane(c)[p] - cand[0][0].plane(c)[p]);
        const float b = cand[1][0].plane(c)[p] + s * (cand[1][1].plane(c)[p] - cand[1][0].plane(c)[p]);
        blended.plane(c)[p] = 0.5f * (a + b);
        blend_var.plane(c)[p] = 0.25f * (a - b) * (a - b);
      }
    });
  if (st.second_pass) {
    // NOTE: NFOR sec. 5.4 (second pass): the averaged result is filtered once more by the
    // same regression, guided by itself, its variance estimated as (A_f - B_f)^2 / 4 (3 x 3
    // mean here), on the features of the even half.
    blended.fill_border();
    Planes smooth_var;
    smooth_var.allocate(3, W, H, pad);
    blend_var.fill_border();
    box3(blend_var, smooth_var);
    smooth_var.fill_border();
    Planes second[2];
    for (auto& b : second) b.allocate(3, W, H, pad);
    regress(blended, features[0], blended, smooth_var, st, second);
    blended = std::move(second[0]);
  }
  for (auto& f : X) f.reset();

  // --- Remodulate, add the outliers back.
  for_rows(0, H, [&](int y) {
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x, p = blended.index(x, y);
      for (int c = 0; c < 3; ++c) {
        const float filtered = std::max(blended.plane(c)[p] * divisor.plane(c)[p], 0.f);
        // NOTE: the spread outliers add at most k_spread_cap x the pixel's filtered value: the
        // excess of an outlier too strong to spread without a visible blotch (a caustic path
        // found by one sample in thousands) is dropped -- biased, like all outlier rejection,
        // but only for values far beyond what the other half sees.
        float v = filtered + std::min(residual.plane(c)[p], k_spread_cap * filtered);
        if (!std::isfinite(v)) v = 0.5f * (rad[0].plane(c)[p] + rad[1].plane(c)[p]) * divisor.plane(c)[p];
        out_rgb[3 * i + c] = std::isfinite(v) ? std::max(v, 0.f) : 0.f;
      }
    }
  });
}

}  // namespace sg
