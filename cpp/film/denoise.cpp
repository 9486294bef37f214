// Reduced NFOR denoiser (film/denoise.h). Every image lives in a Planes buffer: one padded
// plane per channel, the border replicated (clamp to edge), so that the NL-means patch and
// window loops run over contiguous memory without bounds checks; neighbours outside the image
// get weight 0. Work is split into fixed 32 x 16 tiles and every output pixel is computed by
// the same sequence of float operations whatever thread runs its tile: the result does not
// depend on the number of threads.
#include "film/denoise.h"
#include "film/denoise_kernels.h"

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

using namespace denoise_detail;

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
  if (!(st.distance_floor >= 0.f) || !std::isfinite(st.distance_floor))
    throw Error("denoise: distance_floor must be >= 0");
  if (!(st.normal_weight >= 0.f) || !std::isfinite(st.normal_weight))
    throw Error("denoise: normal_weight must be >= 0");

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
  nlmeans(mse, mean_rad, mean_var, 1, st.selection_radius, 1.f, mse_f, k_selection_floor);
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
  nlmeans(select, mean_rad, mean_var, 1, st.selection_radius, 1.f, select_f, k_selection_floor);

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
