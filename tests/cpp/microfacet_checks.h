// Test helpers for materials with Dirac lobes and transmission (test_conductor.cpp,
// test_dielectric.cpp), complementing material_checks.h:
// * check_sampling_mixed: chi-square of sample() against pdf() over the whole sphere where
//   Dirac samples are set aside (pdf() describes only the non-delta lobes, so it integrates
//   to 1 minus the probability of the Dirac lobes, and the chi-square checks that the
//   sampler produces non-delta samples exactly that often, cell by cell);
// * furnace_mc / furnace_quadrature: directional albedo from sample weights (Monte Carlo) and
//   from eval() (quadrature, independent of sample()), optionally undoing the radiance
//   scaling 1/eta^2 of refraction;
// * fresnel_conductor_ref: exact conductor Fresnel with std::complex in double.
#pragma once

#include <complex>

#include "material_checks.h"

namespace sgtest {

namespace detail {
/// Tensor 4-point Gauss-Legendre rule on [x0, x1] x [y0, y1].
template <class F>
double gauss_legendre_4x4(const F& f, double x0, double x1, double y0, double y1) {
  static const double k_nodes[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                    0.8611363115940526};
  static const double k_weights[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                      0.3478548451374538};
  double cx = 0.5 * (x0 + x1), hx = 0.5 * (x1 - x0), cy = 0.5 * (y0 + y1), hy = 0.5 * (y1 - y0), s = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) s += k_weights[i] * k_weights[j] * f(cx + hx * k_nodes[i], cy + hy * k_nodes[j]);
  return s * hx * hy;
}

template <class F>
double cubature_rec(const F& f, double x0, double x1, double y0, double y1, double whole, double eps, int depth) {
  double xm = 0.5 * (x0 + x1), ym = 0.5 * (y0 + y1);
  double q[4] = {gauss_legendre_4x4(f, x0, xm, y0, ym), gauss_legendre_4x4(f, xm, x1, y0, ym),
                 gauss_legendre_4x4(f, x0, xm, ym, y1), gauss_legendre_4x4(f, xm, x1, ym, y1)};
  double fine = q[0] + q[1] + q[2] + q[3];
  if (depth <= 0 || std::fabs(fine - whole) <= eps) return fine;
  return cubature_rec(f, x0, xm, y0, ym, q[0], 0.5 * eps, depth - 1) +
         cubature_rec(f, xm, x1, y0, ym, q[1], 0.5 * eps, depth - 1) +
         cubature_rec(f, x0, xm, ym, y1, q[2], 0.5 * eps, depth - 1) +
         cubature_rec(f, xm, x1, ym, y1, q[3], 0.5 * eps, depth - 1);
}
}  // namespace detail

/// Expected counts per cell like expected_counts (chi2.h), by adaptive 2D Gauss-Legendre
/// cubature: a cell's 4x4-point estimate is compared with the sum over its four quarters and
/// split until they agree to `cell_eps` (absolute, in units of probability). Agrees with
/// expected_counts at tolerance 1e-10 to < 0.1 counts per cell for 10^6 samples (measured on
/// conductor lobes) at a fraction of the cost. Its nodes are interior, so a density that is
/// non-zero only on a sliver along a cell edge can be missed: see check_sampling_mixed.
template <class F>
std::vector<double> expected_counts_cubature(const Grid2D& g, const F& density, double n_samples,
                                             double cell_eps = 1e-8, int max_depth = 8) {
  std::vector<double> e(g.size());
  for (int iy = 0; iy < g.ny; ++iy)
    for (int ix = 0; ix < g.nx; ++ix) {
      double x0 = g.cx0(ix), x1 = g.cx1(ix), y0 = g.cy0(iy), y1 = g.cy1(iy);
      double whole = detail::gauss_legendre_4x4(density, x0, x1, y0, y1);
      e[size_t(iy) * g.nx + ix] = n_samples * detail::cubature_rec(density, x0, x1, y0, y1, whole, cell_eps, max_depth);
    }
  return e;
}

struct MixedSamplingStats {
  int delta = 0;   ///< Dirac samples (not binned)
  int failed = 0;  ///< sample() returned false
};

/// Chi-square of the non-delta samples of mat.sample(si, wo) against mat.pdf(si, wo, .) on a
/// (cos theta, phi) grid around the geometric normal covering the whole sphere (so reflection
/// and transmission are tested together), plus the per-sample consistency checks of
/// check_sampling (returned pdf == pdf(), weight == eval / pdf on every 8th sample; unit
/// directions and finite weights on all). Dirac
/// samples must have eval == 0 and pdf() == 0 there (they are invisible to eval/pdf).
inline MixedSamplingStats check_sampling_mixed(const sg::Material& mat, const sg::SurfaceInteraction& si,
                                               const sg::Vec3f& wo, uint64_t seed, const std::string& what,
                                               int n_samples = 1000000, int nz = 32, int nphi = 64) {
  DFrame frame(to_d(si.ng));
  Grid2D g{nz, nphi, -1.0, 1.0, 0.0, 2.0 * k_pi_d};
  sg::Pcg32 rng(seed);
  std::vector<double> obs(g.size(), 0.0);
  MixedSamplingStats st;
  int n_bad_weight = 0, n_bad_pdf = 0, n_bad_dir = 0, n_bad_delta = 0;
  std::string first_problem;
  for (int i = 0; i < n_samples; ++i) {
    float u_lobe = rng.next_float();
    sg::Vec2f u = rng.next_2d();
    sg::BsdfSample bs;
    if (!mat.sample(si, wo, u_lobe, u, &bs)) {
      ++st.failed;
      continue;
    }
    if (!(std::fabs(sg::length(bs.wi) - 1.f) < 1e-5f) || !sg::is_finite(bs.weight)) {
      ++n_bad_dir;
      continue;
    }
    if (bs.flags & sg::k_bsdf_delta) {
      ++st.delta;
      if ((!sg::is_black(mat.eval(si, wo, bs.wi)) || mat.pdf(si, wo, bs.wi) != 0.f) && n_bad_delta++ == 0)
        first_problem += " a Dirac sample has non-zero eval/pdf;";
      continue;
    }
    double z, phi;
    sphere_coords(frame, to_d(bs.wi), &z, &phi);
    long c = g.cell(z, phi);
    if (c < 0) {
      ++n_bad_dir;
      continue;
    }
    obs[size_t(c)] += 1.0;
    if (i % 8 != 0) continue;  // eval/pdf consistency on every 8th sample (125000 of 10^6)
    sg::Color f = mat.eval(si, wo, bs.wi);
    float pdf = mat.pdf(si, wo, bs.wi);
    if (!(std::fabs(pdf - bs.pdf) <= 1e-4 * std::max(pdf, bs.pdf))) {
      if (n_bad_pdf++ == 0)
        first_problem += " pdf mismatch: sample " + std::to_string(bs.pdf) + " vs pdf() " + std::to_string(pdf) + ";";
    }
    bool weight_ok = pdf > 0.f;
    for (int k = 0; k < 3 && weight_ok; ++k) weight_ok = rel_diff(bs.weight[k], f[k] / pdf) <= 1e-4;
    if (!weight_ok && n_bad_weight++ == 0)
      first_problem += " weight " + std::to_string(bs.weight.x) + " vs eval/pdf " + std::to_string(f.x / pdf) + ";";
  }
  EXPECT_EQ(n_bad_dir, 0) << what << ": sampled directions not unit length or weights not finite";
  EXPECT_EQ(n_bad_pdf, 0) << what << ":" << first_problem;
  EXPECT_EQ(n_bad_weight, 0) << what << ":" << first_problem;
  EXPECT_EQ(n_bad_delta, 0) << what << ":" << first_problem;
  auto density = [&](double z, double phi) { return double(mat.pdf(si, wo, to_f(sphere_dir(frame, z, phi)))); };
  auto exp = expected_counts_cubature(g, density, double(n_samples));
  // Cells with samples but (almost) no expectation (< 0.05 samples): the density may be
  // non-zero only on a sliver along the cell edge that the interior cubature nodes miss (e.g.
  // the validity boundary of refraction, wo.h > 0 > wi.h, next to the pole; seen: cubature 0,
  // true expectation 0.11). Re-integrate those few cells with the edge-including nested
  // adaptive Simpson of chi2.h; a cell whose density really is 0 everywhere still fails the
  // chi-square test outright.
  for (int iy = 0; iy < g.ny; ++iy)
    for (int ix = 0; ix < g.nx; ++ix) {
      size_t c = size_t(iy) * g.nx + ix;
      if (obs[c] > 0.0 && exp[c] < 0.05)
        exp[c] = n_samples * integrate_2d(density, g.cx0(ix), g.cx1(ix), g.cy0(iy), g.cy1(iy), 1e-10, 20, 4);
    }
  double non_delta = sum(exp) / n_samples;
  EXPECT_LE(non_delta, 1.0 + 1e-3) << what << ": pdf integrates to more than 1";
  Chi2Result r = chi2_test(obs, exp);
  EXPECT_TRUE(r.ok) << what << ": " << r.message;
  return st;
}

/// Monte Carlo directional albedo: mean luminance of the sample weights (0 for failed
/// samples). With `undo_eta`, refraction weights are multiplied by BsdfSample::eta^2, undoing
/// the radiance scaling, so that a lossless interface gives exactly 1.
struct FurnaceMc {
  double mean = 0.0, stddev_of_mean = 0.0, max_weight = 0.0;
};
inline FurnaceMc furnace_mc(const sg::Material& mat, const sg::SurfaceInteraction& si, const sg::Vec3f& wo,
                            uint64_t seed, int n_samples, bool undo_eta) {
  sg::Pcg32 rng(seed);
  double s = 0.0, s2 = 0.0, mx = 0.0;
  for (int i = 0; i < n_samples; ++i) {
    sg::BsdfSample bs;
    float u_lobe = rng.next_float();
    sg::Vec2f u = rng.next_2d();
    if (!mat.sample(si, wo, u_lobe, u, &bs)) continue;
    double w = sg::luminance(bs.weight);
    if (undo_eta) w *= double(bs.eta) * bs.eta;
    s += w;
    s2 += w * w;
    mx = std::max(mx, w);
  }
  FurnaceMc r;
  r.mean = s / n_samples;
  r.stddev_of_mean = std::sqrt(std::max(0.0, s2 / n_samples - r.mean * r.mean) / n_samples);
  r.max_weight = mx;
  return r;
}

/// Integral over the sphere of luminance(eval(wo, wi)) by quadrature (independent of
/// sample()), by adaptive cubature on a 32 x 64 grid (absolute tolerance ~2e-5 in total);
/// with `eta_sq_transmitted`, values on the far side of the surface are multiplied by that
/// factor (eta^2 undoing the radiance scaling of refraction).
inline double furnace_quadrature(const sg::Material& mat, const sg::SurfaceInteraction& si, const sg::Vec3f& wo,
                                 double eta_sq_transmitted = 1.0) {
  DFrame frame(to_d(si.ng));
  double side = ddot(to_d(si.ng), to_d(wo)) > 0 ? 1.0 : -1.0;
  Grid2D g{32, 64, -1.0, 1.0, 0.0, 2.0 * k_pi_d};
  return sum(expected_counts_cubature(
      g,
      [&](double z, double phi) {
        double v = sg::luminance(mat.eval(si, wo, to_f(sphere_dir(frame, z, phi))));
        return z * side < 0 ? v * eta_sq_transmitted : v;
      },
      1.0, 1e-8));
}

/// Unpolarized Fresnel reflectance of a conductor with complex index n = eta + i k, in double
/// with std::complex: r_s = (cos_i - n cos_t) / (cos_i + n cos_t), r_p = (n cos_i - cos_t) /
/// (n cos_i + cos_t), cos_t = sqrt(1 - sin_i^2 / n^2) (Born & Wolf, sec. 14.2).
inline double fresnel_conductor_ref(double cos_i, double eta, double k) {
  std::complex<double> n(eta, k);
  double sin2 = 1.0 - cos_i * cos_i;
  std::complex<double> cos_t = std::sqrt(1.0 - sin2 / (n * n));
  std::complex<double> rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
  std::complex<double> rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
  return 0.5 * (std::norm(rs) + std::norm(rp));
}

}  // namespace sgtest
