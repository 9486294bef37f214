// CIE XYZ / xyY to the renderer's linear sRGB, shared by the sky models ("sky", "twilight").
#pragma once

#include <algorithm>

#include "core/math.h"

namespace sg {

/// CIE XYZ -> linear sRGB (Rec. 709 primaries, D65 white), negative components clamped.
/// NOTE: matrix of IEC 61966-2-1:1999 to 7 digits as tabulated by B. Lindbloom
/// ("RGB/XYZ Matrices", brucelindbloom.com); its inverse's Y row is the Rec. 709 luminance
/// (0.2126, 0.7152, 0.0722), so luminance(rgb) = Y for in-gamut colours. In double, or in
/// float for the sky's per-direction radiance (the 7-digit constants round to the same floats
/// as float literals of them).
template <class T>
inline Color xyz_to_linear_srgb(T x, T y, T z) {
  const T r = T(3.2404542) * x - T(1.5371385) * y - T(0.4985314) * z;
  const T g = T(-0.9692660) * x + T(1.8760108) * y + T(0.0415560) * z;
  const T b = T(0.0556434) * x - T(0.2040259) * y + T(1.0572252) * z;
  return Color(float(std::max(r, T(0))), float(std::max(g, T(0))), float(std::max(b, T(0))));
}

/// CIE xyY -> XYZ: X = x Y / y, Z = (1 - x - y) Y / y.
inline Color xyY_to_linear_srgb(double x, double y, double big_y) {
  if (!(y > 0.0) || !(big_y > 0.0)) return Color(0.f);
  return xyz_to_linear_srgb(x * big_y / y, big_y, (1.0 - x - y) * big_y / y);
}

/// Linear sRGB -> CIE chromaticity (x, y): the inverse of xyz_to_linear_srgb's matrix (IEC
/// 61966-2-1, D65, Lindbloom's 7 digits), then x = X / (X + Y + Z), y = Y / (X + Y + Z).
inline void linear_srgb_to_xy(const Color& c, double* x, double* y) {
  double cx = 0.4124564 * c.x + 0.3575761 * c.y + 0.1804375 * c.z;
  double cy = 0.2126729 * c.x + 0.7151522 * c.y + 0.0721750 * c.z;
  double cz = 0.0193339 * c.x + 0.1191920 * c.y + 0.9503041 * c.z;
  *x = cx / (cx + cy + cz), *y = cy / (cx + cy + cz);
}

}  // namespace sg
