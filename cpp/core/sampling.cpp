#include "core/sampling.h"

#include <algorithm>

#include "core/error.h"

namespace sg {

Distribution1D::Distribution1D(const std::vector<float>& weights) {
  size_t n = weights.size();
  if (n == 0) return;
  std::vector<double> cdf(n + 1, 0.0);
  for (size_t i = 0; i < n; ++i) {
    if (!(weights[i] >= 0.f) || !std::isfinite(weights[i]))
      throw Error("Distribution1D: weight " + std::to_string(i) + " is negative or not finite");
    cdf[i + 1] = cdf[i] + weights[i];
  }
  m_total = cdf[n];
  m_cdf.resize(n + 1);
  m_pmf.resize(n);
  if (m_total <= 0.0) {
    // All-zero weights: fall back to uniform selection.
    for (size_t i = 0; i <= n; ++i) m_cdf[i] = float(double(i) / double(n));
    for (size_t i = 0; i < n; ++i) m_pmf[i] = 1.f / float(n);
    return;
  }
  for (size_t i = 0; i <= n; ++i) m_cdf[i] = float(cdf[i] / m_total);
  m_cdf[n] = 1.f;
  for (size_t i = 0; i < n; ++i) m_pmf[i] = float(double(weights[i]) / m_total);
}

size_t Distribution1D::sample(float u, float* pmf_out, float* u_remapped) const {
  if (m_pmf.size() == 1) {
    if (pmf_out) *pmf_out = 1.f;
    if (u_remapped) *u_remapped = u;
    return 0;
  }
  // Largest i with cdf[i] <= u, skipping zero-weight bins.
  auto it = std::upper_bound(m_cdf.begin(), m_cdf.end(), u);
  size_t i = size_t(std::max<ptrdiff_t>(0, (it - m_cdf.begin()) - 1));
  i = std::min(i, m_pmf.size() - 1);
  while (m_pmf[i] == 0.f && i + 1 < m_pmf.size()) ++i;
  while (m_pmf[i] == 0.f && i > 0) --i;
  if (pmf_out) *pmf_out = m_pmf[i];
  if (u_remapped) {
    float w = m_cdf[i + 1] - m_cdf[i];
    float r = w > 0.f ? (u - m_cdf[i]) / w : 0.f;
    *u_remapped = std::min(std::max(r, 0.f), k_one_minus_epsilon);
  }
  return i;
}

}  // namespace sg
