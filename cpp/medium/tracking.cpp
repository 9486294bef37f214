#include "medium/tracking.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/plugin.h"

namespace sg {

namespace {

constexpr float k_koschmieder = 3.912f;  // -ln(0.02)

/// An exponential step of rate `rate` (per unit of t) from a uniform u in [0, 1).
inline float exp_step(float u, float rate) { return -std::log1p(-std::min(u, 0x1.fffffep-1f)) / rate; }

/// The ray parameters [*t0, *t1] of o + t d inside `box`, within [0, t_max); false when empty.
bool clip(const Box3& box, const Vec3f& o, const Vec3f& d, float t_max, float* t0, float* t1) {
  float lo = 0.f, hi = t_max;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.f) {
      if (o[a] < box.lo[a] || o[a] > box.hi[a]) return false;
      continue;
    }
    const float inv = 1.f / d[a];
    float ta = (box.lo[a] - o[a]) * inv, tb = (box.hi[a] - o[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    lo = std::max(lo, ta);
    hi = std::min(hi, tb);
  }
  *t0 = lo;
  *t1 = hi;
  return lo < hi;
}

}  // namespace

void MajorantGrid::build(const Box3& box, int nx, int ny, int nz,
                         const std::function<DensityBounds(const Vec3f& lo, const Vec3f& hi)>& cell_bounds) {
  m_box = box;
  m_res[0] = std::max(1, nx);
  m_res[1] = std::max(1, ny);
  m_res[2] = std::max(1, nz);
  m_cell_size = Vec3f((box.hi.x - box.lo.x) / float(m_res[0]), (box.hi.y - box.lo.y) / float(m_res[1]),
                      (box.hi.z - box.lo.z) / float(m_res[2]));
  m_cells.assign(size_t(m_res[0]) * size_t(m_res[1]) * size_t(m_res[2]), DensityBounds{});
  tbb::parallel_for(0, m_res[2], [&](int z) {
    for (int y = 0; y < m_res[1]; ++y)
      for (int x = 0; x < m_res[0]; ++x) {
        const Box3 c = cell_box(x, y, z);
        DensityBounds b = cell_bounds(c.lo, c.hi);
        b.mn = std::max(0.f, std::min(b.mn, b.mx));
        b.mx = std::max(0.f, b.mx);
        m_cells[(size_t(z) * size_t(m_res[1]) + size_t(y)) * size_t(m_res[0]) + size_t(x)] = b;
      }
  });
  m_max = 0.f;
  for (const DensityBounds& b : m_cells) m_max = std::max(m_max, b.mx);
}

void MajorantGrid::cell_of(const Vec3f& p, int* x, int* y, int* z) const {
  int c[3];
  for (int a = 0; a < 3; ++a)
    c[a] = std::clamp(int(std::floor((p[a] - m_box.lo[a]) / m_cell_size[a])), 0, m_res[a] - 1);
  *x = c[0];
  *y = c[1];
  *z = c[2];
}

Box3 MajorantGrid::cell_box(int x, int y, int z) const {
  // The last cell ends exactly at the box (no rounding gap at the far faces).
  const int c[3] = {x, y, z};
  Box3 b;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = m_box.lo[a] + m_cell_size[a] * float(c[a]);
    b.hi[a] = c[a] + 1 == m_res[a] ? m_box.hi[a] : m_box.lo[a] + m_cell_size[a] * float(c[a] + 1);
  }
  return b;
}

MajorantDda::MajorantDda(const MajorantGrid& grid, const Vec3f& o, const Vec3f& d, float t_max) : m_grid(&grid) {
  float t0, t1;
  if (!clip(grid.box(), o, d, t_max, &t0, &t1)) return;  // m_t_end < m_t: no segment
  m_t = t0;
  m_t_end = t1;
  const Box3& box = grid.box();
  const Vec3f p = o + d * t0;
  for (int a = 0; a < 3; ++a) {
    const float size = (box.hi[a] - box.lo[a]) / float(grid.res(a));
    m_cell[a] = std::clamp(int(std::floor((p[a] - box.lo[a]) / size)), 0, grid.res(a) - 1);
    if (d[a] == 0.f) {
      m_next_t[a] = k_inf;
      m_delta_t[a] = k_inf;
      m_step[a] = 0;
      m_limit[a] = -2;
      continue;
    }
    // NOTE: the crossings are computed from the ray's own origin (not from the entry point), so a
    // segment's ends are the cell planes' ray parameters up to rounding (pbrt-v4 sec. 11.4.3).
    const bool pos = d[a] > 0.f;
    const float plane = box.lo[a] + size * float(m_cell[a] + (pos ? 1 : 0));
    m_next_t[a] = (plane - o[a]) / d[a];
    m_delta_t[a] = size / std::fabs(d[a]);
    m_step[a] = pos ? 1 : -1;
    m_limit[a] = pos ? grid.res(a) : -1;
  }
}

bool MajorantDda::next(MajorantSegment* seg) {
  if (!(m_t < m_t_end)) return false;
  // The axis whose cell plane the ray crosses first.
  int a = 0;
  if (m_next_t[1] < m_next_t[a]) a = 1;
  if (m_next_t[2] < m_next_t[a]) a = 2;
  const float t_exit = std::min(m_next_t[a], m_t_end);
  seg->t0 = m_t;
  seg->t1 = std::max(t_exit, m_t);
  seg->b = m_grid->cell(m_cell[0], m_cell[1], m_cell[2]);
  m_t = seg->t1;
  if (m_t >= m_t_end) {
    m_t_end = -1.f;
  } else {
    m_cell[a] += m_step[a];
    m_next_t[a] += m_delta_t[a];
    if (m_cell[a] == m_limit[a]) m_t_end = -1.f;
  }
  return true;
}

float TrackedMedium::transmittance(const Vec3f& o, const Vec3f& d, float t_max) const {
  // A midpoint quadrature of the optical depth, exact in cells of constant density (minorant =
  // majorant) and skipping empty ones: deterministic, for labels and tests.
  if (!(m_sigma > 0.f)) return 1.f;
  const float len = length(d);
  MajorantDda dda(m_grid, o, d, t_max);
  MajorantSegment s;
  double tau = 0.0;
  while (dda.next(&s)) {
    if (!(s.b.mx > 0.f) || !(s.t1 > s.t0)) continue;
    const float dt = s.t1 - s.t0;
    if (s.b.mn == s.b.mx) {
      tau += double(m_sigma) * s.b.mx * dt * len;
      continue;
    }
    const int n = std::clamp(int(std::ceil(dt * len / m_step)), 1, 4096);
    const float h = dt / float(n);
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum += density(o + d * (s.t0 + (float(i) + 0.5f) * h));
    tau += double(m_sigma) * sum * h * len;
  }
  return float(std::exp(-tau));
}

float TrackedMedium::transmittance_estimate(const Vec3f& o, const Vec3f& d, float t_max, MediumRng& rng) const {
  // NOTE: residual ratio tracking (Novak, Selle, Jarosz 2014, eq. (8)-(10)) with the cell's
  // minorant as the control: T = exp(-sigma mn L) exactly times ratio tracking of the residual
  // density - mn against the residual majorant mx - mn (each tentative collision multiplies by
  // the residual's null fraction 1 - (density - mn) / (mx - mn), in [0, 1] since the bounds are
  // conservative). A cell of constant density costs no lookup, an empty one nothing.
  if (!(m_sigma > 0.f)) return 1.f;
  const float len = length(d);
  MajorantDda dda(m_grid, o, d, t_max);
  MajorantSegment s;
  float T = 1.f;
  while (dda.next(&s)) {
    if (!(s.b.mx > 0.f)) continue;
    const float dt = s.t1 - s.t0;
    if (s.b.mn > 0.f) T *= std::exp(-m_sigma * s.b.mn * dt * len);
    const float range = s.b.mx - s.b.mn;
    if (range > 0.f) {
      const float rate = m_sigma * range * len;
      for (float t = s.t0;;) {
        t += exp_step(rng.next(), rate);
        if (!(t < s.t1)) break;
        T *= 1.f - (density(o + d * t) - s.b.mn) / range;
      }
    }
    // NOTE: Russian roulette on a small running estimate (pbrt-v4 sec. 14.2.2,
    // "Ratio-tracking transmittance"): stopped with probability 1/2 below 0.05, doubled
    // otherwise -- unbiased, and a thick cloud stops costing lookups once it has nearly
    // blocked the ray.
    if (T < 0.05f) {
      if (!(T > 0.f) || rng.next() < 0.5f) return 0.f;
      T *= 2.f;
    }
  }
  return T;
}

bool TrackedMedium::sample_distance(const Vec3f& o, const Vec3f& d, float t_max, MediumRng& rng, float* t_out) const {
  // NOTE: decomposition tracking (Kutz et al. 2017, sec. 4) per majorant cell: sigma_t = the
  // control sigma mn (collisions all real, sampled exactly: tc) + the residual (delta tracking,
  // Woodcock et al. 1965, against mx - mn: a tentative collision at x is real with probability
  // (density(x) - mn) / (mx - mn)); the flight ends at the first real collision of either. The
  // exponential distribution is memoryless, so each cell starts afresh at its entry. The weight is
  // the albedo at the event and 1 when the flight passes (Medium::sample_distance), since the
  // albedo is the same everywhere.
  if (!(m_sigma > 0.f)) return false;
  const float len = length(d);
  MajorantDda dda(m_grid, o, d, t_max);
  MajorantSegment s;
  while (dda.next(&s)) {
    if (!(s.b.mx > 0.f)) continue;
    const float tc = s.b.mn > 0.f ? s.t0 + exp_step(rng.next(), m_sigma * s.b.mn * len) : k_inf;
    const float end = std::min(s.t1, tc);
    const float range = s.b.mx - s.b.mn;
    if (range > 0.f) {
      const float rate = m_sigma * range * len;
      for (float t = s.t0;;) {
        t += exp_step(rng.next(), rate);
        if (!(t < end)) break;
        if (rng.next() * range < density(o + d * t) - s.b.mn) {
          *t_out = t;
          return true;
        }
      }
    }
    if (tc < s.t1) {
      *t_out = tc;
      return true;
    }
  }
  return false;
}

bool TrackedMedium::sample_in_segment(const Vec3f& o, const Vec3f& d, float t_max, MediumRng& rng, float* t_out,
                                      float* weight) const {
  // NOTE: delta tracking conditioned on the segment. Delta tracking's tentative collisions are a
  // Poisson process of the majorant's rate, each real with probability density / mx (Woodcock et
  // al. 1965); its first real one has the density sigma_t T. Here every tentative collision is
  // drawn from the majorant's free flight conditioned on the rest of the segment, and the weight
  // takes the probability of that condition, 1 - T_maj(rest) (exact: the majorant is piecewise
  // constant), so a flight never leaves the segment unused: E[weight f(t)] = integral sigma_t T f
  // by the same recursion as delta tracking's (each step's expectation: integral over the rest of
  // sigma_maj T_maj (density / mx f + (1 - density / mx) (the rest's estimate)) = integral sigma_t
  // T f). Weights lie in [0, 1]; where the majorant is tight the first point is real and this is the
  // homogeneous medium's estimator exactly (weight 1 - T). Rejected points continue forwards, so one
  // DDA pass serves the whole search; Russian roulette ends flights whose weight has become small.
  if (!(m_sigma > 0.f)) return false;
  const float len = length(d);
  double tau_rem = 0.0;
  {
    MajorantDda dda(m_grid, o, d, t_max);
    MajorantSegment s;
    while (dda.next(&s)) tau_rem += double(m_sigma) * s.b.mx * double(s.t1 - s.t0) * len;
  }
  if (!(tau_rem > 0.0)) return false;
  MajorantDda dda(m_grid, o, d, t_max);
  MajorantSegment s{0.f, 0.f, DensityBounds{}};
  float t = 0.f;
  double w = 1.0;
  bool have = false;
  for (int step = 0; step < 1024; ++step) {
    const double p = -std::expm1(-tau_rem);
    if (!(p > 0.0)) return false;
    w *= p;
    // The majorant's optical depth to the next tentative collision, truncated to the rest.
    double dtau = std::min(-std::log1p(-double(std::min(rng.next(), 0x1.fffffep-1f)) * p), tau_rem);
    tau_rem -= dtau;
    // Walk forwards by dtau of majorant optical depth.
    for (;;) {
      if (!have) {
        if (!dda.next(&s)) return false;  // rounding ran past the last cell
        have = true;
        t = s.t0;
      }
      const double rate = double(m_sigma) * s.b.mx * len;
      const double avail = rate * double(s.t1 - t);
      if (rate > 0.0 && dtau < avail) {
        t = std::min(s.t1, float(double(t) + dtau / rate));
        break;
      }
      dtau -= avail;
      have = false;
    }
    const float dens = density(o + d * t);
    if (rng.next() * s.b.mx < dens) {
      *t_out = t;
      *weight = float(w);
      return true;
    }
    // NOTE: Russian roulette below weight 0.05: continue with probability w / 0.05 at weight 0.05
    // (unbiased; Arvo, Kirk 1990, "Particle transport and image synthesis").
    if (w < 0.05) {
      if (rng.next() * 0.05 >= w) return false;
      w = 0.05;
    }
  }
  return false;
}

float extinction_from(const Params& params) {
  return params.has("visibility") ? k_koschmieder / params.get_float("visibility") : params.get_float("extinction");
}

void whole_numbers(const Params& params, const std::string& key, const std::string& medium, int out[3]) {
  const Vec3f v = params.get_vec3(key);
  for (int a = 0; a < 3; ++a) {
    if (v[a] != std::floor(v[a]))
      throw Error("medium '" + medium + "': " + key + " must be whole numbers, got " + std::to_string(v[a]));
    out[a] = int(v[a]);
  }
}

std::vector<ParamDecl> tracked_medium_params(const std::string& density_one, double albedo, double g) {
  return {param::real("visibility", "meteorological visibility in metres at " + density_one +
                                        " (where a black object's contrast falls to 2%): extinction = 3.912 / "
                                        "visibility there, proportional to the density elsewhere")
              .above(0),
          param::real("extinction", "extinction coefficient sigma_t in 1/m at " + density_one + " (instead of "
                                    "visibility)")
              .at_least(0),
          param::color("albedo", Color(float(albedo)), "single-scattering albedo sigma_s / sigma_t per channel (water "
                                               "droplets about 1)")
              .in(0, 1),
          param::real("g", g, "Henyey-Greenstein asymmetry: 0 isotropic, > 0 forward (fog and cloud droplets "
                                 "0.75-0.85)")
              .above(-1)
              .below(1)};
}

}  // namespace sg
