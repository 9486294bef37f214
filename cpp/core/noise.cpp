#include "core/noise.h"

#include <algorithm>
#include <cmath>

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
}

uint32_t NoiseBasis::hash(int x, int y, int z) const {
  uint64_t h = (uint64_t(uint32_t(x)) * 0x9e3779b97f4a7c15ull) ^ (uint64_t(uint32_t(y)) * 0xc2b2ae3d27d4eb4full) ^
               (uint64_t(uint32_t(z)) * 0x165667b19e3779f9ull) ^ (uint64_t(m_perm[0]) << 56 | uint64_t(m_perm[1]) << 48 |
                                                                  uint64_t(m_perm[2]) << 40 | uint64_t(m_perm[3]) << 32);
  return uint32_t(mix64(h) >> 32);
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

inline float basis_noise(const NoiseBasis& b, NoiseKind kind, const Vec3f& p) {
  return kind == NoiseKind::Perlin ? b.perlin(p) : b.value(p);
}

/// The fractal sum (fbm, or turbulence with kAbs), and with kGrad its gradient (Perlin basis).
template <bool kAbs, bool kGrad>
float fractal(const NoiseBasis& b, NoiseKind kind, const Vec3f& p, const FractalParams& f, float footprint,
              Vec3f* grad = nullptr) {
  float s = 1.f, w = 1.f, sum = 0.f, wsum = 0.f;
  Vec3f g(0.f);
  const float wmul = f.weight_ratio();
  const float mean = kAbs ? mean_abs_noise(kind) : 0.f;
  for (int i = 0; i < f.octaves; ++i) {
    float a = octave_fade(s, footprint);
    if (a > 0.f) {
      // Decorrelate octaves with a fixed offset per octave (integer lattices would line up).
      Vec3f q = p * s + Vec3f(17.3f, -41.7f, 29.1f) * float(i);
      if constexpr (kGrad) {
        Vec3f gn;
        float n = b.perlin_grad(q, &gn);
        if (kAbs && n < 0.f) {
          n = -n;
          gn = -gn;
        }
        sum += w * (a * n + (1.f - a) * mean);
        g += gn * (w * a * s);
      } else {
        float n = basis_noise(b, kind, q);
        sum += w * (a * (kAbs ? std::fabs(n) : n) + (1.f - a) * mean);
      }
    } else {
      sum += w * mean;
    }
    wsum += w;
    s *= f.lacunarity;
    w *= wmul;
  }
  if constexpr (kGrad) {
    float norm = (f.normalize && wsum > 0.f) ? 1.f / wsum : 1.f;
    *grad = g * norm;
    return sum * norm;
  }
  return (f.normalize && wsum > 0.f) ? sum / wsum : sum;
}

}  // namespace

float fbm_grad(const NoiseBasis& b, const Vec3f& p, const FractalParams& f, float footprint, Vec3f* grad) {
  return fractal<false, true>(b, NoiseKind::Perlin, p, f, footprint, grad);
}

float turbulence_grad(const NoiseBasis& b, const Vec3f& p, const FractalParams& f, float footprint, Vec3f* grad) {
  return fractal<true, true>(b, NoiseKind::Perlin, p, f, footprint, grad);
}

float fbm(const NoiseBasis& b, NoiseKind kind, const Vec3f& p, const FractalParams& f, float footprint) {
  return fractal<false, false>(b, kind, p, f, footprint);
}

float turbulence(const NoiseBasis& b, NoiseKind kind, const Vec3f& p, const FractalParams& f, float footprint) {
  return fractal<true, false>(b, kind, p, f, footprint);
}

CellularResult cellular(const NoiseBasis& b, const Vec3f& p, float jitter, bool want_edge) {
  int X = fast_floor(p.x), Y = fast_floor(p.y), Z = fast_floor(p.z);
  // One hash per cell: its 32 bits give the cell id and three 10-bit jitter offsets.
  auto feature = [&](int i, int j, int k, uint32_t* h) {
    uint32_t a = b.hash(i, j, k);
    *h = a;
    auto unit = [](uint32_t v) { return (float(v & 1023u) + 0.5f) * (1.f / 1024.f); };
    return Vec3f(float(i) + 0.5f + jitter * (unit(a) - 0.5f), float(j) + 0.5f + jitter * (unit(a >> 10) - 0.5f),
                 float(k) + 0.5f + jitter * (unit(a >> 20) - 0.5f));
  };
  // Pass 1: nearest and second-nearest feature points over the 27 neighbouring cells
  // (enough for jitter <= 1: a feature point never leaves its cell). Cells are visited by
  // increasing distance of their box to p (own cell, faces, edges, corners) and skipped
  // when that box is farther than the current second-nearest point.
  static const int8_t k_order[27][3] = {
      {0, 0, 0},  {-1, 0, 0},  {1, 0, 0},   {0, -1, 0},  {0, 1, 0},   {0, 0, -1},  {0, 0, 1},
      {-1, -1, 0}, {1, -1, 0},  {-1, 1, 0},  {1, 1, 0},   {-1, 0, -1}, {1, 0, -1},  {-1, 0, 1},
      {1, 0, 1},  {0, -1, -1}, {0, 1, -1},  {0, -1, 1},  {0, 1, 1},   {-1, -1, -1}, {1, -1, -1},
      {-1, 1, -1}, {1, 1, -1},  {-1, -1, 1}, {1, -1, 1},  {-1, 1, 1},  {1, 1, 1}};
  const Vec3f f(p.x - float(X), p.y - float(Y), p.z - float(Z));  // position inside the own cell
  auto axis_gap = [](int o, float t) { return o < 0 ? t : (o > 0 ? 1.f - t : 0.f); };
  CellularResult r;
  float d1 = k_inf, d2 = k_inf;
  Vec3f nearest;
  for (const auto& o : k_order) {
    float gx = axis_gap(o[0], f.x), gy = axis_gap(o[1], f.y), gz = axis_gap(o[2], f.z);
    if (gx * gx + gy * gy + gz * gz >= d2) continue;
    uint32_t h;
    Vec3f fp = feature(X + o[0], Y + o[1], Z + o[2], &h);
    float d = length_squared(fp - p);
    if (d < d1) {
      d2 = d1;
      d1 = d;
      nearest = fp;
      r.cell_hash = h;
    } else if (d < d2) {
      d2 = d;
    }
  }
  r.f1 = std::sqrt(d1);
  r.f2 = std::sqrt(d2);
  if (!want_edge) return r;
  // Pass 2: exact distance to the nearest cell boundary: the bisector planes between the
  // nearest feature point and its neighbours (Quilez, "Voronoi edges", 2012).
  // NOTE: 5^3 cells around the point's cell cover every neighbour of the nearest cell.
  float edge = k_inf;
  for (int k = -2; k <= 2; ++k)
    for (int j = -2; j <= 2; ++j)
      for (int i = -2; i <= 2; ++i) {
        uint32_t h;
        Vec3f f = feature(X + i, Y + j, Z + k, &h);
        Vec3f d = f - nearest;
        float l2 = length_squared(d);
        if (l2 < 1e-12f) continue;
        Vec3f mid = (f + nearest) * 0.5f;
        float dist = dot(mid - p, d) / std::sqrt(l2);
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
