// Test helpers: chi-square goodness-of-fit test, its CDF (regularized incomplete gamma
// function), adaptive Simpson quadrature to turn a pdf into expected bin counts, and
// double-precision direction parameterizations used for binning.
//
// No external libraries: the incomplete gamma function follows the classic series /
// continued-fraction split (Numerical Recipes, 3rd ed., sec. 6.2), the merging of
// low-expectation cells follows Mitsuba's ChiSquareTest (mitsuba/python/chi2.py).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace sgtest {

constexpr double k_pi_d = 3.14159265358979323846;

// ------------------------------------------------------------------------------------
// Significance level.
//
// Every chi-square test of the suite uses the same per-test level: an overall
// significance of 0.01 Bonferroni-corrected for the number of chi-square tests in the
// whole suite (test_sampling, test_diffuse, test_emissive, test_area, test_sun,
// test_environment, test_coated, test_mix, test_conductor, test_dielectric, test_principled;
// 115 at the time of writing: sampling 12, diffuse 7, emissive 6, area 1, sun 4, environment
// 1, coated 13, mix 5, conductor 26, dielectric 20, principled 20; since then environment 2,
// light_selection +3, homogeneous +6, tracking +6, twilight +2).
// k_chi2_test_count is an upper bound on that number; a larger count
// only makes each test more conservative (Bonferroni stays valid). With this level the
// probability that a correct implementation fails *any* chi-square test of the suite,
// over the choice of seeds, is at most 1%.
// ------------------------------------------------------------------------------------
constexpr double k_chi2_overall_significance = 0.01;
constexpr int k_chi2_test_count = 140;  // + 5 in test_rng.cpp
constexpr double k_chi2_alpha = k_chi2_overall_significance / k_chi2_test_count;

// ------------------------------------------------------------------------------------
// Regularized incomplete gamma functions.
// ------------------------------------------------------------------------------------

/// Regularized lower incomplete gamma P(a, x) by its power series (converges for x < a + 1).
inline double gamma_p_series(double a, double x) {
  double ap = a, sum = 1.0 / a, del = sum;
  for (int n = 0; n < 100000; ++n) {
    ap += 1.0;
    del *= x / ap;
    sum += del;
    if (std::fabs(del) < std::fabs(sum) * 1e-16) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

/// Regularized upper incomplete gamma Q(a, x) by its continued fraction (modified Lentz),
/// converges for x >= a + 1.
inline double gamma_q_cf(double a, double x) {
  const double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1.0 / d;
    double del = d * c;
    h *= del;
    if (std::fabs(del - 1.0) < 1e-16) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

/// Q(a, x) = Gamma(a, x) / Gamma(a).
inline double gamma_q(double a, double x) {
  if (x <= 0.0) return 1.0;
  if (x < a + 1.0) return 1.0 - gamma_p_series(a, x);
  return gamma_q_cf(a, x);
}

/// P(a, x) = 1 - Q(a, x).
inline double gamma_p(double a, double x) {
  if (x <= 0.0) return 0.0;
  if (x < a + 1.0) return gamma_p_series(a, x);
  return 1.0 - gamma_q_cf(a, x);
}

/// CDF of the chi-square distribution with `dof` degrees of freedom.
inline double chi2_cdf(double x, double dof) { return gamma_p(0.5 * dof, 0.5 * x); }
/// Survival function (p-value of a statistic x).
inline double chi2_sf(double x, double dof) { return gamma_q(0.5 * dof, 0.5 * x); }

// ------------------------------------------------------------------------------------
// Chi-square test.
// ------------------------------------------------------------------------------------

struct Chi2Result {
  bool ok = false;
  double statistic = 0.0;
  int dof = 0;
  double p_value = 0.0;
  size_t pooled_cells = 0;
  std::string message;
};

/// Pearson chi-square test of observed counts against expected counts.
/// As in Mitsuba: cells are visited in order of increasing expectation; cells with an
/// expected count below `min_expected` are pooled, and the pool keeps absorbing cells
/// until its own expectation reaches `min_expected`. A sample in a cell whose expected
/// count is exactly zero fails the test outright.
inline Chi2Result chi2_test(const std::vector<double>& observed, const std::vector<double>& expected,
                            double alpha = k_chi2_alpha, double min_expected = 5.0) {
  Chi2Result r;
  std::ostringstream msg;
  if (observed.size() != expected.size() || observed.empty()) {
    r.message = "chi2_test: size mismatch";
    return r;
  }
  std::vector<size_t> idx(observed.size());
  std::iota(idx.begin(), idx.end(), size_t(0));
  std::stable_sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  double pooled_obs = 0.0, pooled_exp = 0.0, stat = 0.0;
  int dof = 0;
  for (size_t i : idx) {
    if (expected[i] == 0.0 && observed[i] > 0.0) {
      msg << "cell " << i << " has " << observed[i] << " samples but expected frequency 0";
      r.message = msg.str();
      return r;
    }
    if (expected[i] < min_expected || (pooled_exp > 0.0 && pooled_exp < min_expected)) {
      pooled_obs += observed[i];
      pooled_exp += expected[i];
      ++r.pooled_cells;
    } else {
      double d = observed[i] - expected[i];
      stat += d * d / expected[i];
      ++dof;
    }
  }
  if (pooled_exp > 0.0) {
    double d = pooled_obs - pooled_exp;
    stat += d * d / pooled_exp;
    ++dof;
  } else if (pooled_obs > 0.0) {
    msg << "pooled cells have " << pooled_obs << " samples but expected frequency 0";
    r.message = msg.str();
    return r;
  }
  dof -= 1;
  if (dof < 1) {
    r.message = "chi2_test: fewer than two cells with a usable expectation";
    return r;
  }
  r.statistic = stat;
  r.dof = dof;
  r.p_value = chi2_sf(stat, dof);
  r.ok = r.p_value >= alpha;
  msg << "chi2 = " << stat << ", dof = " << dof << ", p = " << r.p_value << " (alpha = " << alpha << ", "
      << r.pooled_cells << " cells pooled)";
  if (!r.ok) {
    // Show the worst cells to make a failure diagnosable.
    std::vector<size_t> worst(observed.size());
    std::iota(worst.begin(), worst.end(), size_t(0));
    auto score = [&](size_t i) {
      double e = std::max(expected[i], 1.0);
      return (observed[i] - expected[i]) * (observed[i] - expected[i]) / e;
    };
    std::sort(worst.begin(), worst.end(), [&](size_t a, size_t b) { return score(a) > score(b); });
    msg << "; worst cells (index: observed / expected):";
    for (size_t k = 0; k < std::min<size_t>(8, worst.size()); ++k)
      msg << " " << worst[k] << ": " << observed[worst[k]] << " / " << expected[worst[k]] << ";";
  }
  r.message = msg.str();
  return r;
}

// ------------------------------------------------------------------------------------
// Adaptive Simpson quadrature (1D and nested 2D).
// ------------------------------------------------------------------------------------

namespace detail {
template <class F>
double simpson_rec(const F& f, double a, double b, double fa, double fm, double fb, double whole, double eps,
                   int depth, int min_depth) {
  double m = 0.5 * (a + b), lm = 0.5 * (a + m), rm = 0.5 * (m + b);
  double flm = f(lm), frm = f(rm);
  double left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
  double right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
  double delta = left + right - whole;
  if (depth <= 0 || (min_depth <= 0 && std::fabs(delta) <= 15.0 * eps)) return left + right + delta / 15.0;
  return simpson_rec(f, a, m, fa, flm, fm, left, 0.5 * eps, depth - 1, min_depth - 1) +
         simpson_rec(f, m, b, fm, frm, fb, right, 0.5 * eps, depth - 1, min_depth - 1);
}
}  // namespace detail

/// Integral of f over [a, b] to absolute tolerance `eps`. `min_depth` forces a minimum
/// subdivision so that features between the first five nodes are not missed.
template <class F>
double integrate_1d(const F& f, double a, double b, double eps, int max_depth = 18, int min_depth = 2) {
  double fa = f(a), fb = f(b), fm = f(0.5 * (a + b));
  double whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
  return detail::simpson_rec(f, a, b, fa, fm, fb, whole, eps, max_depth, min_depth);
}

/// Integral of f(x, y) over [x0, x1] x [y0, y1] by nested adaptive Simpson.
template <class F>
double integrate_2d(const F& f, double x0, double x1, double y0, double y1, double eps, int max_depth = 14,
                    int min_depth = 2) {
  double inner_eps = eps / (x1 - x0);
  auto g = [&](double x) {
    return integrate_1d([&](double y) { return f(x, y); }, y0, y1, inner_eps, max_depth, min_depth);
  };
  return integrate_1d(g, x0, x1, eps, max_depth, min_depth);
}

// ------------------------------------------------------------------------------------
// 2D histograms over a rectangular parameter domain.
// ------------------------------------------------------------------------------------

struct Grid2D {
  int nx, ny;
  double x0, x1, y0, y1;
  size_t size() const { return size_t(nx) * size_t(ny); }
  /// Cell index of (x, y), or -1 outside the domain.
  long cell(double x, double y) const {
    if (!(x >= x0 && x <= x1 && y >= y0 && y <= y1)) return -1;
    int ix = std::min(nx - 1, int((x - x0) / (x1 - x0) * nx));
    int iy = std::min(ny - 1, int((y - y0) / (y1 - y0) * ny));
    return long(iy) * nx + ix;
  }
  double cx0(int ix) const { return x0 + (x1 - x0) * ix / nx; }
  double cx1(int ix) const { return x0 + (x1 - x0) * (ix + 1) / nx; }
  double cy0(int iy) const { return y0 + (y1 - y0) * iy / ny; }
  double cy1(int iy) const { return y0 + (y1 - y0) * (iy + 1) / ny; }
};

/// Expected counts of `n_samples` samples per cell: n_samples * integral of the density
/// `density(x, y)` (already including the Jacobian of the parameterization) over each cell.
/// `cell_eps` is the absolute quadrature tolerance per cell, in units of probability.
template <class F>
std::vector<double> expected_counts(const Grid2D& g, const F& density, double n_samples, double cell_eps = 1e-9,
                                    int max_depth = 14) {
  std::vector<double> e(g.size());
  for (int iy = 0; iy < g.ny; ++iy)
    for (int ix = 0; ix < g.nx; ++ix)
      e[size_t(iy) * g.nx + ix] =
          n_samples * integrate_2d(density, g.cx0(ix), g.cx1(ix), g.cy0(iy), g.cy1(iy), cell_eps, max_depth);
  return e;
}

inline double sum(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

// ------------------------------------------------------------------------------------
// Double-precision direction parameterizations.
// ------------------------------------------------------------------------------------

struct DVec3 {
  double x = 0, y = 0, z = 0;
};
inline void PrintTo(const DVec3& v, std::ostream* os) { *os << "(" << v.x << ", " << v.y << ", " << v.z << ")"; }
inline double ddot(const DVec3& a, const DVec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline DVec3 dcross(const DVec3& a, const DVec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline DVec3 dnormalize(const DVec3& a) {
  double l = std::sqrt(ddot(a, a));
  return {a.x / l, a.y / l, a.z / l};
}

/// Orthonormal frame around a unit axis, built independently of sg::Frame.
struct DFrame {
  DVec3 s, t, n;
  explicit DFrame(DVec3 axis) {
    n = dnormalize(axis);
    DVec3 h = std::fabs(n.x) < 0.6 ? DVec3{1, 0, 0} : DVec3{0, 1, 0};
    s = dnormalize(dcross(h, n));
    t = dcross(n, s);
  }
  DVec3 to_world(double lx, double ly, double lz) const {
    return {s.x * lx + t.x * ly + n.x * lz, s.y * lx + t.y * ly + n.y * lz, s.z * lx + t.z * ly + n.z * lz};
  }
  DVec3 to_local(const DVec3& v) const { return {ddot(v, s), ddot(v, t), ddot(v, n)}; }
};

inline double wrap_phi(double phi) {
  if (phi < 0.0) phi += 2.0 * k_pi_d;
  if (phi >= 2.0 * k_pi_d) phi -= 2.0 * k_pi_d;
  return phi;
}

/// Sphere parameterized by (z = cos theta in [-1, 1], phi in [0, 2 pi)) around the frame
/// axis; d(omega) = dz dphi, so the Jacobian is 1.
inline DVec3 sphere_dir(const DFrame& f, double z, double phi) {
  double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return f.to_world(r * std::cos(phi), r * std::sin(phi), z);
}
inline void sphere_coords(const DFrame& f, const DVec3& d, double* z, double* phi) {
  DVec3 l = f.to_local(d);
  *z = std::max(-1.0, std::min(1.0, l.z));
  *phi = wrap_phi(std::atan2(l.y, l.x));
}

/// Cone-local parameterization (tau = theta / theta_ref, phi) around the frame axis;
/// d(omega) = sin(theta) d(theta) d(phi) = theta_ref sin(tau theta_ref) d(tau) d(phi).
/// theta is recovered from atan2(|xy|, z) so that it is accurate for tiny angles.
inline DVec3 cone_dir(const DFrame& f, double theta_ref, double tau, double phi) {
  double th = tau * theta_ref;
  return f.to_world(std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi), std::cos(th));
}
inline double cone_jacobian(double theta_ref, double tau) { return theta_ref * std::sin(tau * theta_ref); }
inline void cone_coords(const DFrame& f, double theta_ref, const DVec3& d, double* tau, double* phi) {
  DVec3 l = f.to_local(d);
  *tau = std::atan2(std::hypot(l.x, l.y), l.z) / theta_ref;
  *phi = wrap_phi(std::atan2(l.y, l.x));
}

}  // namespace sgtest
