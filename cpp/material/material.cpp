#include "material/material.h"

#include "core/error.h"
#include "material/material_registry.h"

namespace sg {

std::shared_ptr<Texture> get_color_texture(const ParamSet& params, const std::string& name, const Color& def,
                                           const TextureLookup& textures) {
  TextureRef ref;
  if (params.get_texture(name, &ref)) {
    auto t = textures(ref.id);
    if (!t) throw Error("parameter '" + name + "': texture " + std::to_string(ref.id) + " does not exist");
    return t;
  }
  return make_constant_texture(params.get_color(name, def));
}

std::shared_ptr<Material> create_material(const std::string& type, const ParamSet& params,
                                          const TextureLookup& textures, const std::string& context) {
  static const std::vector<std::string> k_types = {"diffuse", "emissive"};
  std::shared_ptr<Material> m;
  try {
    if (type == "diffuse") m = create_diffuse_material(params, textures);
    else if (type == "emissive") m = create_emissive_material(params, textures);
    else {
      std::string guess = closest_match(type, k_types);
      throw Error("unknown material type '" + type + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
                  "; known types: diffuse, emissive");
    }
    params.check_unused("material '" + type + "'");
  } catch (const Error& e) {
    throw Error(context + ": " + e.what());
  }
  return m;
}

}  // namespace sg
