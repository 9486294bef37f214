#include "core/noise.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/rng.h"

namespace sg {

namespace {

inline float fade(float t) {
  // NOTE: Perlin 2002's quintic 6t^5 - 15t^4 + 10t^3 (C2-continuous, unlike the cubic of 1985).
  return t * t * t * (t * (t * 6.f - 15.f) + 10.f);
}
inline float lerp(float t, float a, float b) { return a + t * (b - a); }

/// Gradient dot product with one of the 12 edge directions of a cube (Perlin 2002, sec. 3;
/// 16 cases, 4 repeated, as in his reference implementation).
/// The 16 gradient vectors of grad3 (Perlin's reference implementation), as a table so
/// that the dot product is branch-free.
constexpr float k_grad3[16][3] = {{1, 1, 0},  {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0}, {1, 0, 1},  {-1, 0, 1},
                                  {1, 0, -1}, {-1, 0, -1}, {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1},
                                  {1, 1, 0},  {0, -1, 1}, {-1, 1, 0}, {0, -1, -1}};
inline float grad3(int h, float x, float y, float z) {
  const float* g = k_grad3[h & 15];
  return g[0] * x + g[1] * y + g[2] * z;
}

/// 2D gradients: 8 unit directions (axes and diagonals).
inline float grad2(int h, float x, float y) {
  constexpr float d = 0.70710678f;
  switch (h & 7) {
    case 0: return x;
    case 1: return -x;
    case 2: return y;
    case 3: return -y;
    case 4: return d * (x + y);
    case 5: return d * (x - y);
    case 6: return d * (-x + y);
    default: return d * (-x - y);
  }
}

inline int fast_floor(float x) {
  int i = int(x);
  return x < float(i) ? i - 1 : i;
}

}  // namespace

NoiseBasis::NoiseBasis(uint64_t seed) {
  // A seeded permutation of 0..255 (Fisher-Yates with PCG32), duplicated to avoid wrapping.
  std::array<uint8_t, 256> p;
  for (int i = 0; i < 256; ++i) p[size_t(i)] = uint8_t(i);
  Pcg32 rng(seed, 0x9e3779b97f4a7c15ull);
  for (int i = 255; i > 0; --i) {
    int j = int(rng.next_u32() % uint32_t(i + 1));
    std::swap(p[size_t(i)], p[size_t(j)]);
  }
  for (int i = 0; i < 512; ++i) m_perm[size_t(i)] = p[size_t(i & 255)];
  m_hash_seed = uint32_t(mix64(seed ^ 0x5eed5eed5eedull) >> 32);
}

float NoiseBasis::perlin(const Vec3f& pt) const {
  int X = fast_floor(pt.x), Y = fast_floor(pt.y), Z = fast_floor(pt.z);
  float x = pt.x - float(X), y = pt.y - float(Y), z = pt.z - float(Z);
  X &= 255;
  Y &= 255;
  Z &= 255;
  float u = fade(x), v = fade(y), w = fade(z);
  const auto& P = m_perm;
  int A = P[size_t(X)] + Y, AA = P[size_t(A)] + Z, AB = P[size_t(A + 1)] + Z;
  int B = P[size_t(X + 1)] + Y, BA = P[size_t(B)] + Z, BB = P[size_t(B + 1)] + Z;
  float r = lerp(w,
                 lerp(v, lerp(u, grad3(P[size_t(AA)], x, y, z), grad3(P[size_t(BA)], x - 1, y, z)),
                      lerp(u, grad3(P[size_t(AB)], x, y - 1, z), grad3(P[size_t(BB)], x - 1, y - 1, z))),
                 lerp(v, lerp(u, grad3(P[size_t(AA + 1)], x, y, z - 1), grad3(P[size_t(BA + 1)], x - 1, y, z - 1)),
                      lerp(u, grad3(P[size_t(AB + 1)], x, y - 1, z - 1), grad3(P[size_t(BB + 1)], x - 1, y - 1, z - 1))));
  // The 12-gradient noise peaks a little above 1 in magnitude; keep the documented range.
  return std::max(-1.f, std::min(1.f, r));
}

namespace {
/// The gradient vector behind grad3(h, .): grad3(h, d) = dot(grad3_vec(h), d).
inline Vec3f grad3_vec(int h) {
  const float* g = k_grad3[h & 15];
  return Vec3f(g[0], g[1], g[2]);
}
inline float dfade(float t) { return 30.f * t * t * (t * (t - 2.f) + 1.f); }
}  // namespace

float NoiseBasis::perlin_grad(const Vec3f& pt, Vec3f* grad) const {
  // NOTE: the trilinear form of gradient noise and its derivative (Quilez, "Gradient noise
  // derivatives", 2017): n = k0 + k1 u + k2 v + k3 w + k4 uv + k5 vw + k6 wu + k7 uvw with the
  // corner values k, and dn = sum of the corner gradients blended the same way plus the
  // fade derivatives times the partial blends.
  int X = fast_floor(pt.x), Y = fast_floor(pt.y), Z = fast_floor(pt.z);
  float x = pt.x - float(X), y = pt.y - float(Y), z = pt.z - float(Z);
  X &= 255;
  Y &= 255;
  Z &= 255;
  const auto& P = m_perm;
  int A = P[size_t(X)] + Y, AA = P[size_t(A)] + Z, AB = P[size_t(A + 1)] + Z;
  int B = P[size_t(X + 1)] + Y, BA = P[size_t(B)] + Z, BB = P[size_t(B + 1)] + Z;
  Vec3f ga = grad3_vec(P[size_t(AA)]), gb = grad3_vec(P[size_t(BA)]), gc = grad3_vec(P[size_t(AB)]),
        gd = grad3_vec(P[size_t(BB)]), ge = grad3_vec(P[size_t(AA + 1)]), gf = grad3_vec(P[size_t(BA + 1)]),
        gg = grad3_vec(P[size_t(AB + 1)]), gh = grad3_vec(P[size_t(BB + 1)]);
  float va = dot(ga, Vec3f(x, y, z)), vb = dot(gb, Vec3f(x - 1, y, z)), vc = dot(gc, Vec3f(x, y - 1, z)),
        vd = dot(gd, Vec3f(x - 1, y - 1, z)), ve = dot(ge, Vec3f(x, y, z - 1)), vf = dot(gf, Vec3f(x - 1, y, z - 1)),
        vg = dot(gg, Vec3f(x, y - 1, z - 1)), vh = dot(gh, Vec3f(x - 1, y - 1, z - 1));
  float u = fade(x), v = fade(y), w = fade(z), du = dfade(x), dv = dfade(y), dw = dfade(z);
  float k0 = va, k1 = vb - va, k2 = vc - va, k3 = ve - va, k4 = va - vb - vc + vd, k5 = va - vc - ve + vg,
        k6 = va - vb - ve + vf, k7 = -va + vb + vc - vd + ve - vf - vg + vh;
  Vec3f g0 = ga, g1 = gb - ga, g2 = gc - ga, g3 = ge - ga, g4 = ga - gb - gc + gd, g5 = ga - gc - ge + gg,
        g6 = ga - gb - ge + gf, g7 = -ga + gb + gc - gd + ge - gf - gg + gh;
  *grad = g0 + g1 * u + g2 * v + g3 * w + g4 * (u * v) + g5 * (v * w) + g6 * (w * u) + g7 * (u * v * w) +
          Vec3f(du * (k1 + k4 * v + k6 * w + k7 * v * w), dv * (k2 + k5 * w + k4 * u + k7 * w * u),
                dw * (k3 + k6 * u + k5 * v + k7 * u * v));
  return k0 + k1 * u + k2 * v + k3 * w + k4 * u * v + k5 * v * w + k6 * w * u + k7 * u * v * w;
}

void NoiseBasis::perlin_range(const Vec3f& lo, const Vec3f& hi, float* mn, float* mx, int max_cells) const {
  // NOTE: inside one lattice cell, perlin() is nested lerps -- convex combinations, the fade
  // weights lying in [0, 1] -- of the eight corner functions g_c . (x - c), each linear in x. So its
  // value lies between the smallest and the largest corner function at x, and over a box between
  // the smallest minimum and the largest maximum of the corner functions over the box, which are
  // at the box's corners (a linear function's extremes; interval arithmetic, Moore 1966). The
  // clamp to [-1, 1] keeps these bounds.
  const int X0 = fast_floor(lo.x), Y0 = fast_floor(lo.y), Z0 = fast_floor(lo.z);
  const int X1 = fast_floor(hi.x), Y1 = fast_floor(hi.y), Z1 = fast_floor(hi.z);
  const int64_t cells = int64_t(X1 - X0 + 1) * int64_t(Y1 - Y0 + 1) * int64_t(Z1 - Z0 + 1);
  if (!(cells >= 1 && cells <= max_cells)) {
    *mn = -1.f;
    *mx = 1.f;
    return;
  }
  const auto& P = m_perm;
  float lo_v = k_inf, hi_v = -k_inf;
  for (int X = X0; X <= X1; ++X)
    for (int Y = Y0; Y <= Y1; ++Y)
      for (int Z = Z0; Z <= Z1; ++Z) {
        // The part of the box in this cell, in the cell's local coordinates [0, 1]^3.
        const Vec3f b0(std::max(lo.x - float(X), 0.f), std::max(lo.y - float(Y), 0.f), std::max(lo.z - float(Z), 0.f));
        const Vec3f b1(std::min(hi.x - float(X), 1.f), std::min(hi.y - float(Y), 1.f), std::min(hi.z - float(Z), 1.f));
        for (int c = 0; c < 8; ++c) {
          const int i = c & 1, j = (c >> 1) & 1, k = c >> 2;
          // The corner's gradient as perlin() finds it (the permutation table is doubled, so
          // P[a + 256] = P[a] and the wrapped indices below agree with its sums).
          const int h = P[size_t(P[size_t(P[size_t((X + i) & 255)] + ((Y + j) & 255))] + ((Z + k) & 255))];
          const Vec3f g = grad3_vec(h);
          const Vec3f corner{float(i), float(j), float(k)};
          float fmax = 0.f, fmin = 0.f;
          for (int a = 0; a < 3; ++a) {
            const float e0 = g[a] * (b0[a] - corner[a]), e1 = g[a] * (b1[a] - corner[a]);
            fmax += std::max(e0, e1);
            fmin += std::min(e0, e1);
          }
          hi_v = std::max(hi_v, fmax);
          lo_v = std::min(lo_v, fmin);
        }
      }
  *mn = std::max(-1.f, std::min(1.f, lo_v));
  *mx = std::max(-1.f, std::min(1.f, hi_v));
}

float NoiseBasis::perlin2(float px, float py) const {
  int X = fast_floor(px), Y = fast_floor(py);
  float x = px - float(X), y = py - float(Y);
  X &= 255;
  Y &= 255;
  float u = fade(x), v = fade(y);
  const auto& P = m_perm;
  int A = P[size_t(X)] + Y, B = P[size_t(X + 1)] + Y;
  float r = lerp(v, lerp(u, grad2(P[size_t(A)], x, y), grad2(P[size_t(B)], x - 1, y)),
                 lerp(u, grad2(P[size_t(A + 1)], x, y - 1), grad2(P[size_t(B + 1)], x - 1, y - 1)));
  // NOTE: the 2D maximum of this construction is sqrt(2)/2 at cell centres; scaled to [-1, 1].
  return std::max(-1.f, std::min(1.f, r * 1.41421356f));
}

float NoiseBasis::value(const Vec3f& pt) const {
  int X = fast_floor(pt.x), Y = fast_floor(pt.y), Z = fast_floor(pt.z);
  float u = fade(pt.x - float(X)), v = fade(pt.y - float(Y)), w = fade(pt.z - float(Z));
  auto val = [&](int i, int j, int k) { return float(hash(X + i, Y + j, Z + k)) * (2.f / 4294967296.f) - 1.f; };
  return lerp(w, lerp(v, lerp(u, val(0, 0, 0), val(1, 0, 0)), lerp(u, val(0, 1, 0), val(1, 1, 0))),
              lerp(v, lerp(u, val(0, 0, 1), val(1, 0, 1)), lerp(u, val(0, 1, 1), val(1, 1, 1))));
}

float octave_fade(float freq, float footprint) {
  if (!(footprint > 0.f)) return 1.f;
  // NOTE: frequency clamping (Ebert et al., "Texturing & Modeling", ch. 6): an octave of
  // frequency s sampled once per footprint w aliases beyond the Nyquist rate s w > 1/2, and
  // the pixel's box filter (the reference a renderer converges to) scales it by
  // sinc(pi s w), 0.64 at s w = 1/2 and 0 at s w = 1. Octaves are kept up to the Nyquist
  // rate and faded to their mean by the first zero of the box filter (a smoothstep, so no
  // popping as w changes).
  return 1.f - smoothstep(0.5f, 1.f, freq * footprint);
}

float mean_abs_noise(NoiseKind kind) {
  // NOTE: E|noise| measured by Monte Carlo over 10^5 points (tests/cpp/test_noise.cpp checks
  // these values within 2% on other points).
  return kind == NoiseKind::Perlin ? 0.221f : 0.330f;
}

namespace {


/// The fractal sum (fbm, or turbulence with kAbs), and with kGrad its gradient (Perlin basis).
template <bool kAbs, bool kGrad>
float fractal(const NoiseBasis& b, NoiseKind kind, const Vec3f& p, const Fractal& f, float footprint,
              Vec3f* grad = nullptr) {
  float sum = 0.f;
  Vec3f g(0.f);
  const float mean = kAbs ? mean_abs_noise(kind) : 0.f;
  const int n = f.octaves();
  for (int i = 0; i < n; ++i) {
    const float s = f.frequency(i), w = f.weight(i);
    float a = octave_fade(s, footprint);
    if (a > 0.f) {
      // Decorrelate octaves with a fixed offset per octave (integer lattices would line up).
      Vec3f q = p * s + Vec3f(17.3f, -41.7f, 29.1f) * float(i);
      if constexpr (kGrad) {
        Vec3f gn;
        float v = b.perlin_grad(q, &gn);
        if (kAbs && v < 0.f) {
          v = -v;
          gn = -gn;
        }
        sum += w * (a * v + (1.f - a) * mean);
        g += gn * (w * a * s);
      } else {
        float v = kind == NoiseKind::Perlin ? b.perlin(q) : b.value(q);
        sum += w * (a * (kAbs ? std::fabs(v) : v) + (1.f - a) * mean);
      }
    } else {
      // Frequencies grow with i: every later octave is faded out too (their mean stands in).
      for (; i < n; ++i) sum += f.weight(i) * mean;
    }
  }
  if constexpr (kGrad) *grad = g * f.norm();
  return sum * f.norm();
}

}  // namespace

Fractal::Fractal(const FractalParams& f) : m_octaves(f.octaves) {
  if (f.octaves < 1 || f.octaves > k_max_octaves)
    throw Error("fractal noise: octaves must lie in [1, " + std::to_string(k_max_octaves) + "], got " +
                std::to_string(f.octaves));
  // s_i = l^i, w_i = l^(-H i) by repeated multiplication (the seed's recurrences (4-6), (4-7)).
  float s = 1.f, w = 1.f, wsum = 0.f;
  const float wmul = f.weight_ratio();
  for (int i = 0; i < m_octaves; ++i) {
    m_freq[i] = s;
    m_weight[i] = w;
    wsum += w;
    s *= f.lacunarity;
    w *= wmul;
  }
  m_norm = (f.normalize && wsum > 0.f) ? 1.f / wsum : 1.f;
}

float fbm_grad(const NoiseBasis& b, const Vec3f& p, const Fractal& f, float footprint, Vec3f* grad) {
  return fractal<false, true>(b, NoiseKind::Perlin, p, f, footprint, grad);
}

float turbulence_grad(const NoiseBasis& b, const Vec3f& p, const Fractal& f, float footprint, Vec3f* grad) {
  return fractal<true, true>(b, NoiseKind::Perlin, p, f, footprint, grad);
}

void fbm_range(const NoiseBasis& b, const Vec3f& lo, const Vec3f& hi, const Fractal& f, float* mn, float* mx) {
  float s_lo = 0.f, s_hi = 0.f;
  for (int i = 0; i < f.octaves(); ++i) {
    const float s = f.frequency(i), w = f.weight(i);
    // The octave's lattice coordinates as fractal() computes them (rounding is monotonic, so the
    // box maps into this box).
    const Vec3f off = Vec3f(17.3f, -41.7f, 29.1f) * float(i);
    float a, c;
    b.perlin_range(lo * s + off, hi * s + off, &a, &c);
    s_lo += w * a;
    s_hi += w * c;
  }
  *mn = s_lo * f.norm();
  *mx = s_hi * f.norm();
}

float fbm(const NoiseBasis& b, NoiseKind kind, const Vec3f& p, const Fractal& f, float footprint) {
  return fractal<false, false>(b, kind, p, f, footprint);
}

float turbulence(const NoiseBasis& b, NoiseKind kind, const Vec3f& p, const Fractal& f, float footprint) {
  return fractal<true, false>(b, kind, p, f, footprint);
}

namespace {

/// Cell offsets in lanes: the 27 cells around a point's cell (own cell, faces, edges,
/// corners: nearer boxes first, so that ties resolve as a search by distance would) and
/// the 125 cells of the edge search; padded to a multiple of 8 lanes by repeating the own
/// cell (a duplicate never changes a minimum).
template <int N>
struct CellOffsets {
  int32_t x[N], y[N], z[N];
};
constexpr int k_cells_near = 32;  // 27 + 5 padding
constexpr int k_cells_edge = 128;  // 125 + 3 padding
constexpr CellOffsets<k_cells_near> make_near_offsets() {
  constexpr int8_t order[27][3] = {
      {0, 0, 0},  {-1, 0, 0},  {1, 0, 0},   {0, -1, 0},  {0, 1, 0},   {0, 0, -1},  {0, 0, 1},
      {-1, -1, 0}, {1, -1, 0},  {-1, 1, 0},  {1, 1, 0},   {-1, 0, -1}, {1, 0, -1},  {-1, 0, 1},
      {1, 0, 1},  {0, -1, -1}, {0, 1, -1},  {0, -1, 1},  {0, 1, 1},   {-1, -1, -1}, {1, -1, -1},
      {-1, 1, -1}, {1, 1, -1},  {-1, -1, 1}, {1, -1, 1},  {-1, 1, 1},  {1, 1, 1}};
  CellOffsets<k_cells_near> o{};
  for (int i = 0; i < k_cells_near; ++i) {
    int j = i < 27 ? i : 0;
    o.x[i] = order[j][0];
    o.y[i] = order[j][1];
    o.z[i] = order[j][2];
  }
  return o;
}
constexpr CellOffsets<k_cells_edge> make_edge_offsets() {
  CellOffsets<k_cells_edge> o{};
  for (int i = 0; i < k_cells_edge; ++i) {
    int j = i < 125 ? i : 62;  // 62: the centre (0, 0, 0)
    o.x[i] = j % 5 - 2;
    o.y[i] = (j / 5) % 5 - 2;
    o.z[i] = j / 25 - 2;
  }
  return o;
}
constexpr CellOffsets<k_cells_near> k_near = make_near_offsets();
constexpr CellOffsets<k_cells_edge> k_edge = make_edge_offsets();

/// The feature points of cells (X, Y, Z) + offsets, and their squared distances to p, in
/// lanes (integer hashing and float arithmetic only: the compiler vectorizes the loop).
/// One hash per cell: its 32 bits give the cell id and three 10-bit jitter offsets.
template <int N>
inline void cell_features(uint32_t seed, int X, int Y, int Z, const CellOffsets<N>& o, float jitter, const Vec3f& p,
                          float* fx, float* fy, float* fz, float* d2, uint32_t* hash) {
  for (int l = 0; l < N; ++l) {
    int i = X + o.x[l], j = Y + o.y[l], k = Z + o.z[l];
    uint32_t a = NoiseBasis::hash_cell(seed, i, j, k);
    hash[l] = a;
    float ux = (float(a & 1023u) + 0.5f) * (1.f / 1024.f), uy = (float((a >> 10) & 1023u) + 0.5f) * (1.f / 1024.f),
          uz = (float((a >> 20) & 1023u) + 0.5f) * (1.f / 1024.f);
    fx[l] = float(i) + 0.5f + jitter * (ux - 0.5f);
    fy[l] = float(j) + 0.5f + jitter * (uy - 0.5f);
    fz[l] = float(k) + 0.5f + jitter * (uz - 0.5f);
    float dx = fx[l] - p.x, dy = fy[l] - p.y, dz = fz[l] - p.z;
    d2[l] = dx * dx + dy * dy + dz * dz;
  }
}

}  // namespace

CellularResult cellular(const NoiseBasis& b, const Vec3f& p, float jitter, bool want_edge) {
  int X = fast_floor(p.x), Y = fast_floor(p.y), Z = fast_floor(p.z);
  // Pass 1: nearest and second-nearest feature points over the 27 neighbouring cells
  // (enough for jitter <= 1: a feature point never leaves its cell).
  // NOTE: all 27 cells are evaluated, 8 lanes at a time, instead of a scalar search that
  // skips cells farther than the current second-nearest point: for F2 most cells survive
  // that test, and the branch-free vector loop is several times faster (measured).
  alignas(32) float fx[k_cells_near], fy[k_cells_near], fz[k_cells_near], d2[k_cells_near];
  alignas(32) uint32_t h[k_cells_near];
  cell_features(b.hash_seed(), X, Y, Z, k_near, jitter, p, fx, fy, fz, d2, h);
  float d1 = k_inf, dd2 = k_inf;
  int nearest = 0;
  for (int l = 0; l < 27; ++l) {
    float d = d2[l];
    if (d < d1) {
      dd2 = d1;
      d1 = d;
      nearest = l;
    } else if (d < dd2) {
      dd2 = d;
    }
  }
  CellularResult r;
  r.cell_hash = h[nearest];
  r.f1 = std::sqrt(d1);
  r.f2 = std::sqrt(dd2);
  if (!want_edge) return r;
  // Pass 2: exact distance to the nearest cell boundary: the bisector planes between the
  // nearest feature point and its neighbours (Quilez, "Voronoi edges", 2012).
  // NOTE: 5^3 cells around the point's cell cover every neighbour of the nearest cell.
  const Vec3f nf(fx[nearest], fy[nearest], fz[nearest]);
  alignas(32) float ex[k_cells_edge], ey[k_cells_edge], ez[k_cells_edge], ed2[k_cells_edge];
  alignas(32) uint32_t eh[k_cells_edge];
  cell_features(b.hash_seed(), X, Y, Z, k_edge, jitter, nf, ex, ey, ez, ed2, eh);
  float edge = k_inf;
  for (int l = 0; l < k_cells_edge; ++l) {
    // The bisector plane's signed distance from p: dot(mid - p, d) / |d|, d = f - nearest.
    Vec3f d(ex[l] - nf.x, ey[l] - nf.y, ez[l] - nf.z);
    float l2 = ed2[l];
    Vec3f mid((ex[l] + nf.x) * 0.5f, (ey[l] + nf.y) * 0.5f, (ez[l] + nf.z) * 0.5f);
    float dist = l2 < 1e-12f ? k_inf : dot(mid - p, d) / std::sqrt(l2);
    edge = std::min(edge, dist);
  }
  r.edge = std::max(0.f, edge);
  return r;
}

ColorRamp::ColorRamp(std::vector<float> positions, std::vector<Color> colors)
    : m_pos(std::move(positions)), m_col(std::move(colors)) {
  if (m_pos.size() != m_col.size() || m_pos.empty())
    throw Error("colour ramp: needs as many positions as colours, at least one");
  for (size_t i = 1; i < m_pos.size(); ++i)
    if (!(m_pos[i] >= m_pos[i - 1])) throw Error("colour ramp: positions must be non-decreasing");
}

Color ColorRamp::eval(float t) const {
  if (m_pos.empty()) return Color(t);
  if (!(t > m_pos.front())) return m_col.front();
  if (t >= m_pos.back()) return m_col.back();
  size_t i = size_t(std::upper_bound(m_pos.begin(), m_pos.end(), t) - m_pos.begin());
  float a = m_pos[i - 1], b = m_pos[i];
  float u = b > a ? (t - a) / (b - a) : 1.f;
  return m_col[i - 1] * (1.f - u) + m_col[i] * u;
}

}  // namespace sg
