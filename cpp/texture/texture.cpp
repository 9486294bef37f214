#include "texture/texture.h"

#include "core/error.h"
#include "texture/texture_registry.h"

namespace sg {

std::shared_ptr<Texture> create_texture(const std::string& type, const ParamSet& params,
                                        const std::string& context, ImageCache* images) {
  std::shared_ptr<Texture> t;
  if (type == "constant") t = create_constant_texture(params);
  else if (type == "image") t = create_image_texture(params, images);
  else {
    std::string guess = closest_match(type, {"constant", "image"});
    throw Error(context + ": unknown texture type '" + type + "'" +
                (guess.empty() ? "" : " (did you mean '" + guess + "'?)") + "; known types: constant, image");
  }
  params.check_unused(context + " (texture '" + type + "')");
  return t;
}

}  // namespace sg
