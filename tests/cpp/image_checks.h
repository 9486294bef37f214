// Test images shared by the image and mip-map tests.
#pragma once

#include <cstdint>
#include <random>

#include "io/image_io.h"

namespace sg {

/// A w x h image of uniform random values in [0, 1) (`channels` per texel), from `seed`.
inline ImageData random_image(int w, int h, int channels, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  ImageData img;
  img.width = w;
  img.height = h;
  img.channels = channels;
  img.pixels.resize(size_t(w) * h * channels);
  for (float& v : img.pixels) v = u(rng);
  return img;
}

}  // namespace sg
