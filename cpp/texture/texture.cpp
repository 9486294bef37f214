#include "texture/texture.h"

#include "core/error.h"
#include "texture/texture_registry.h"

namespace sg {

std::shared_ptr<Texture> create_texture(const std::string& type, const ParamSet& params,
                                        const std::string& context, ImageCache* images,
                                        const TextureInputs& inputs) {
  std::shared_ptr<Texture> t;
  if (type == "constant") t = create_constant_texture(params);
  else if (type == "image") t = create_image_texture(params, images);
  else if (type == "noise") t = create_noise_texture(params);
  else if (type == "cellular") t = create_cellular_texture(params);
  else if (type == "blend") t = create_blend_texture(params, inputs);
  else if (type == "gradient") t = create_gradient_texture(params);
  else if (type == "projector") t = create_projector_texture(params, inputs);
  else if (type == "ao") t = create_ao_texture(params);
  else if (type == "triplanar") t = create_triplanar_texture(params, inputs);
  else {
    std::string guess = closest_match(
        type, {"ao", "blend", "cellular", "constant", "gradient", "image", "noise", "projector", "triplanar"});
    throw Error(context + ": unknown texture type '" + type + "'" +
                (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
                "; known types: ao, blend, cellular, constant, gradient, image, noise, projector, triplanar");
  }
  params.check_unused(context + " (texture '" + type + "')");
  return t;
}

}  // namespace sg
