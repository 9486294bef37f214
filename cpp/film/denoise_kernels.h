// Numerical kernels of the denoiser (film/denoise.cpp): planar images, tiled loops, NL-means
// weights, 3 x 3 box filtering and batched small least-squares solves. Internal to the denoiser.
#pragma once

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

namespace sg::denoise_detail {

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
/// Relative variance floor (patch_distances) of the NL-means filters of the error estimates and
/// of the selection map. Measured on the five regression scenes (docs/denoise.md): with the
/// regression's floor at 1e-3, 1e-3 / 3e-2 / 1e-1 here gave a geomean denoised / raw 64 spp
/// relMSE of 1.984 / 1.959 / 1.957 (seeds 71-73); 3e-2 / 1e-1: 2.016 / 2.003 (seeds 74-76).
constexpr float k_selection_floor = 3e-2f;
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
/// `floor` (>= 0) adds floor * (u_p^2 + u_q^2) to the denominator: a relative variance floor.
/// NOTE: not in Rousselle et al. or NFOR. Measured (docs/denoise.md): pixels the denoiser left
/// unfiltered -- no neighbour's patch within the variance-scaled distance, e.g. the Cornell box
/// light's corners, silhouettes against the noise-free sky -- held 48% (cbox) and 31% (sunlit)
/// of the denoised error; a floor of 1e-3 (differences below ~4.5% of the value count as
/// noise-level) lets them share with their nearest neighbours.
void patch_distances(const Planes& g, const Planes& v, const TileRect& t, int ox, int oy, int F,
                     DistanceScratch& s, float* out, float floor = 0.f) {
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
        dst[x] += num / (k_dist_eps + vp[x] + vq[x] + floor * (gp[x] * gp[x] + gq[x] * gq[x]));
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
/// `g` (variance `v`, relative floor `floor`: patch_distances), patches (2F+1)^2, bandwidth k.
/// Writes out's interior (not its border).
inline void nlmeans(const Planes& img, const Planes& g, const Planes& v, int F, int R, float k, Planes& out,
                    float floor = 0.f) {
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
        patch_distances(g, v, t, ox, oy, F, s.d, s.dist.data(), floor);
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
inline void box3(const Planes& in, Planes& out) {
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
inline void solve_batch(Systems& s, int count, float ridge) {
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
  // The normals (features 3-5) as planes, for the normal term of the weights.
  Planes normals;
  if (st.normal_weight > 0.f) {
    normals.allocate(3, W, H, g.pad);
    for (int c = 0; c < 3; ++c) {
      float* o = normals.plane(c);
      for (size_t i = 0; i < normals.plane_size; ++i) o[i] = X[i * k_dims + 3 + size_t(c)];
    }
  }
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
        float* w = s.w.data() + size_t((oy + R) * side + ox + R) * n;
        patch_distances(g, v, t, ox, oy, F, s.d, s.dist.data(), st.distance_floor);
        if (st.normal_weight > 0.f) {
          // NOTE: not in NFOR (its weights are the colour NL-means only): a bilateral normal
          // term, as in edge-avoiding filters (e.g. Schied et al. 2017, SVGF): the weight times
          // exp(-normal_weight |n_q - n_p|^2) on the regression's (sample-averaged) normals,
          // added to the distance (scaled by k^2) so that one exp gives both. Measured:
          // docs/denoise.md.
          const ptrdiff_t shift = ptrdiff_t(oy) * g.stride + ox;
          const float scale = st.normal_weight * st.k * st.k;
          for (int y = 0; y < t.h; ++y) {
            const size_t p0 = g.index(t.x0, t.y0 + y);
            float* dr = s.dist.data() + size_t(y) * t.w;
            const float* n0 = normals.plane(0) + p0;
            const float* n1 = normals.plane(1) + p0;
            const float* n2 = normals.plane(2) + p0;
            for (int x = 0; x < t.w; ++x) {
              const float d0 = n0[x + shift] - n0[x], d1 = n1[x + shift] - n1[x], d2 = n2[x + shift] - n2[x];
              dr[x] = std::max(dr[x], 0.f) + scale * (d0 * d0 + d1 * d1 + d2 * d2);
            }
          }
        }
        offset_weights(s.dist.data(), t, ox, oy, W, H, inv_k2, w);
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

}  // namespace sg::denoise_detail
