// CIE XYZ / xyY to the renderer's linear sRGB, shared by the sky models ("sky", "twilight").
#pragma once

#include <algorithm>

#include "core/math.h"

namespace sg {

/// CIE XYZ -> linear sRGB (Rec. 709 primaries, D65 white), negative components clamped.
/// NOTE: matrix of IEC 61966-2-1:1999 to 7 digits as tabulated by B. Lindbloom
/// ("RGB/XYZ Matrices", brucelindbloom.com); its inverse's Y row is the Rec. 709 luminance
/// (0.2126, 0.7152, 0.0722), so luminance(rgb) = Y for in-gamut colours.
inline Color xyz_to_linear_srgb(double x, double y, double z) {
  double r = 3.2404542 * x - 1.5371385 * y - 0.4985314 * z;
  double g = -0.9692660 * x + 1.8760108 * y + 0.0415560 * z;
  double b = 0.0556434 * x - 0.2040259 * y + 1.0572252 * z;
  return Color(float(std::max(r, 0.0)), float(std::max(g, 0.0)), float(std::max(b, 0.0)));
}

/// CIE xyY -> XYZ: X = x Y / y, Z = (1 - x - y) Y / y.
inline Color xyY_to_linear_srgb(double x, double y, double big_y) {
  if (!(y > 0.0) || !(big_y > 0.0)) return Color(0.f);
  return xyz_to_linear_srgb(x * big_y / y, big_y, (1.0 - x - y) * big_y / y);
}

}  // namespace sg
