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

namespace {

struct MaterialFactory {
  const char* key;
  std::shared_ptr<Material> (*create)(const ParamSet&, const MaterialContext&);
};

// The material plugins. One line per plugin (file material/<key>.cpp), alphabetical.
const MaterialFactory k_factories[] = {
    {"coated", create_coated_material},
    {"conductor", create_conductor_material},
    {"dielectric", create_dielectric_material},
    {"diffuse", create_diffuse_material},
    {"emissive", create_emissive_material},
    {"mix", create_mix_material},
    {"principled", create_principled_material},
};

}  // namespace

std::vector<std::string> material_types() {
  std::vector<std::string> keys;
  for (const auto& f : k_factories) keys.push_back(f.key);
  return keys;
}

std::shared_ptr<Material> create_material(const std::string& type, const ParamSet& params,
                                          const MaterialContext& ctx, const std::string& context) {
  std::shared_ptr<Material> m;
  try {
    for (const auto& f : k_factories)
      if (type == f.key) m = f.create(params, ctx);
    if (!m) {
      std::vector<std::string> keys = material_types();
      std::string guess = closest_match(type, keys);
      std::string list;
      for (size_t i = 0; i < keys.size(); ++i) list += (i ? ", " : "") + keys[i];
      throw Error("unknown material type '" + type + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
                  "; known types: " + list);
    }
    params.check_unused("material '" + type + "'");
    m->cache_traits();
  } catch (const FileError& e) {
    throw e.with_context(context);
  } catch (const Error& e) {
    throw Error(context + ": " + e.what());
  }
  return m;
}

}  // namespace sg
