// Textures: colour (or scalar) fields over the surface UV parameterization.
// Created by name ("constant", "image") from a ParamSet; see texture/*.cpp.
#pragma once

#include <memory>
#include <string>

#include "core/math.h"
#include "core/params.h"

namespace sg {

class Texture {
 public:
  virtual ~Texture() = default;
  /// Linear RGB value at texture coordinate `uv`, filtered over a footprint of width
  /// `footprint` in texture space (0 = point sample).
  virtual Color eval(const Vec2f& uv, float footprint = 0.f) const = 0;
  /// Average value over the texture (used for light power estimates and albedo priors).
  virtual Color average() const = 0;
};

/// Creates a texture plugin by registry key. `base_dir` resolves relative file names.
/// Throws sg::Error naming `context` for unknown types or parameters.
std::shared_ptr<Texture> create_texture(const std::string& type, const ParamSet& params,
                                        const std::string& context);

std::shared_ptr<Texture> make_constant_texture(const Color& value);

struct ImageData;
/// Image texture from decoded pixels (already linear), repeat wrapping, times `scale`.
std::shared_ptr<Texture> make_image_texture(const ImageData& pixels, const Color& scale);

}  // namespace sg
