// Internal: factory functions of the texture plugins.
#pragma once
#include <memory>

#include "core/params.h"
#include "texture/texture.h"

namespace sg {
std::shared_ptr<Texture> create_constant_texture(const ParamSet& params);
class ImageCache;
std::shared_ptr<Texture> create_image_texture(const ParamSet& params, ImageCache* images);
std::shared_ptr<Texture> create_noise_texture(const ParamSet& params);
std::shared_ptr<Texture> create_cellular_texture(const ParamSet& params);
std::shared_ptr<Texture> create_blend_texture(const ParamSet& params, const TextureInputs& inputs);
std::shared_ptr<Texture> create_gradient_texture(const ParamSet& params);
std::shared_ptr<Texture> create_ao_texture(const ParamSet& params);
std::shared_ptr<Texture> create_triplanar_texture(const ParamSet& params, const TextureInputs& inputs);
std::shared_ptr<Texture> create_projector_texture(const ParamSet& params, const TextureInputs& inputs);
}  // namespace sg
