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

Distribution2D::Distribution2D(const std::vector<float>& weights, size_t nu, size_t nv) : m_nu(nu), m_nv(nv) {
  if (nu == 0 || nv == 0 || weights.size() != nu * nv)
    throw Error("Distribution2D: expected " + std::to_string(nu) + " x " + std::to_string(nv) + " weights, got " +
                std::to_string(weights.size()));
  m_conditional.reserve(nv);
  std::vector<float> row_sums(nv);
  for (size_t y = 0; y < nv; ++y) {
    std::vector<float> row(weights.begin() + ptrdiff_t(y * nu), weights.begin() + ptrdiff_t((y + 1) * nu));
    m_conditional.emplace_back(row);
    row_sums[y] = float(m_conditional.back().total());
    m_total += m_conditional.back().total();
  }
  m_marginal = Distribution1D(row_sums);
}

namespace {
/// (i + r) / n for a cell index i and a remapped sample r in [0, 1), nudged back into
/// cell i when float rounding carried it across the cell's edge.
float coordinate_in_cell(size_t i, float r, size_t n) {
  float x = std::min((float(i) + r) / float(n), k_one_minus_epsilon);
  while (x > 0.f && Distribution2D::cell_index(x, n) > i) x = std::nextafter(x, 0.f);
  while (x < k_one_minus_epsilon && Distribution2D::cell_index(x, n) < i) x = std::nextafter(x, 1.f);
  return x;
}
}  // namespace

Vec2f Distribution2D::sample(const Vec2f& u, float* pdf) const {
  float pmf_y, pmf_x, ry, rx;
  size_t iy = m_marginal.sample(u.y, &pmf_y, &ry);
  size_t ix = m_conditional[iy].sample(u.x, &pmf_x, &rx);
  if (pdf) *pdf = pdf_cell(ix, iy);
  return {coordinate_in_cell(ix, rx, m_nu), coordinate_in_cell(iy, ry, m_nv)};
}

float Distribution2D::pdf(const Vec2f& p) const { return pdf_cell(cell_index(p.x, m_nu), cell_index(p.y, m_nv)); }

}  // namespace sg
