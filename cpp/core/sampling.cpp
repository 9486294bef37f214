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
    build_guide();
    return;
  }
  for (size_t i = 0; i <= n; ++i) m_cdf[i] = float(cdf[i] / m_total);
  m_cdf[n] = 1.f;
  for (size_t i = 0; i < n; ++i) m_pmf[i] = float(double(weights[i]) / m_total);
  build_guide();
}

void Distribution1D::build_guide() {
  const size_t n = m_pmf.size();
  m_guide.clear();
  if (n < 16 || n >= (size_t(1) << 31)) return;  // a short search needs no guide
  m_guide.resize(n + 1);
  size_t i = 0;
  for (size_t j = 0; j <= n; ++j) {
    const float t = float(j) / float(n);
    while (i + 1 <= n && m_cdf[i + 1] <= t) ++i;
    m_guide[j] = uint32_t(i);
  }
}

size_t Distribution1D::sample(float u, float* pmf_out, float* u_remapped) const {
  if (m_pmf.size() == 1) {
    if (pmf_out) *pmf_out = 1.f;
    if (u_remapped) *u_remapped = u;
    return 0;
  }
  // Largest i with cdf[i] <= u, skipping zero-weight bins.
  // NOTE: a binary search over a long table (an environment map's rows and columns) mostly
  // missed the cache and mispredicted; the guide table narrows it to the entries between
  // cdf = j / G and (j + 1) / G (expected O(1) of them: Chen & Asau 1974; Devroye, "Non-Uniform
  // Random Variate Generation", 1986, sec. III.2.4). The range is checked to hold the answer
  // (cdf[lo] <= u < cdf[hi]), else the whole table is searched: the same index either way.
  auto first = m_cdf.begin(), last = m_cdf.end();
  if (!m_guide.empty() && u >= 0.f && u < 1.f) {
    const size_t g = m_guide.size() - 1;
    const size_t j = std::min(size_t(u * float(g)), g - 1);
    const size_t lo = m_guide[j], hi = size_t(m_guide[j + 1]) + 1;
    if (m_cdf[lo] <= u && (hi >= m_cdf.size() || m_cdf[hi] > u)) {
      first = m_cdf.begin() + ptrdiff_t(lo);
      last = m_cdf.begin() + ptrdiff_t(std::min(hi, m_cdf.size()));
    }
  }
  auto it = std::upper_bound(first, last, u);
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
