#include "integrator/adaptive.h"

#include <algorithm>
#include <cmath>

namespace sg {

double pixel_squared_error(const Film& film, size_t i, float exposure) {
  const uint32_t n = film.sample_count[i];
  if (n < 2) return 1.0;
  const double n_e = double((n + 1) / 2), n_o = double(n / 2);
  const double factor = 1.0 / (double(n) * (1.0 / n_e + 1.0 / n_o));
  double total = 0.0;
  for (int c = 0; c < 3; ++c) {
    const double ua = double(film.rgb_even[3 * i + c]) * exposure, ub = double(film.rgb_odd[3 * i + c]) * exposure;
    const double a = std::clamp(ua, 0.0, 1.0), b = std::clamp(ub, 0.0, 1.0);
    // NOTE: see synthgen.post.quality.estimate_noise: where one half saturates and the other
    // does not, clamping hides part of the spread; the estimate is doubled there.
    const bool one = (ua > 1.0) != (ub > 1.0);
    total += (a - b) * (a - b) * factor * (one ? 2.0 : 1.0);
  }
  return total / 3.0;
}

double estimated_mse(const Film& film, float exposure) {
  const size_t n_pixels = size_t(film.width) * film.height;
  if (n_pixels == 0 || film.sample_count.size() != n_pixels) return -1.0;
  double total = 0.0;
  for (size_t i = 0; i < n_pixels; ++i) {
    if (film.sample_count[i] < 2) return -1.0;
    total += pixel_squared_error(film, i, exposure);
  }
  return total / double(n_pixels);
}

bool AdaptiveStop::keep_going(const Film& film, std::vector<uint8_t>* active) {
  const double mse = estimated_mse(film, m_s.exposure);
  m_psnr = mse > 0.0 ? -10.0 * std::log10(mse) : (mse == 0.0 ? 1e3 : 0.0);
  if (m_s.target_psnr > 0.f && mse >= 0.0 && m_psnr >= double(m_s.target_psnr)) return false;
  const uint32_t w = film.width, h = film.height;
  if (!(m_s.noise_threshold > 0.f)) {
    active->assign(size_t(w) * h, 1);
    return true;
  }
  m_error.resize(size_t(w) * h);
  for (size_t i = 0; i < m_error.size(); ++i) m_error[i] = pixel_squared_error(film, i, m_s.exposure);
  m_noisy.assign(size_t(w) * h, 0);
  const double t2 = double(m_s.noise_threshold) * double(m_s.noise_threshold);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (!(*active)[i]) continue;
      double sum = 0.0;
      int n = 0;
      for (uint32_t yy = y ? y - 1 : 0; yy <= std::min(y + 1, h - 1); ++yy)
        for (uint32_t xx = x ? x - 1 : 0; xx <= std::min(x + 1, w - 1); ++xx, ++n) sum += m_error[size_t(yy) * w + xx];
      m_noisy[i] = sum >= t2 * n;
    }
  bool any = false;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      uint8_t on = 0;
      for (uint32_t yy = y ? y - 1 : 0; yy <= std::min(y + 1, h - 1) && !on; ++yy)
        for (uint32_t xx = x ? x - 1 : 0; xx <= std::min(x + 1, w - 1) && !on; ++xx)
          on = m_noisy[size_t(yy) * w + xx];
      // A pixel that has stopped stays stopped (its sample count would otherwise skip rounds).
      on = on && (*active)[size_t(y) * w + x];
      (*active)[size_t(y) * w + x] = on;
      any = any || on;
    }
  return any;
}

}  // namespace sg
