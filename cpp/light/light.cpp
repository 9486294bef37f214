#include "light/light.h"

#include "light/light_registry.h"

namespace sg {

namespace {

struct LightFactory {
  const char* key;
  std::shared_ptr<Light> (*create)(const ParamSet&);
};

// The light plugins. One line per plugin (file light/<key>.cpp), alphabetical.
// Area lights are not plugins: the scene makes them from emissive materials.
const LightFactory k_factories[] = {
    {"environment", create_environment_light},
    {"envmap", create_envmap_light},
    {"point", create_point_light},
    {"sky", create_sky_light},
    {"spot", create_spot_light},
    {"sun", create_sun_light},
};

}  // namespace

std::vector<std::string> light_types() {
  std::vector<std::string> keys;
  for (const auto& f : k_factories) keys.push_back(f.key);
  return keys;
}

std::shared_ptr<Light> create_light(const std::string& type, const ParamSet& params, const std::string& context) {
  std::shared_ptr<Light> l;
  try {
    for (const auto& f : k_factories)
      if (type == f.key) l = f.create(params);
    if (!l) {
      std::vector<std::string> keys = light_types();
      std::string guess = closest_match(type, keys);
      std::string list;
      for (size_t i = 0; i < keys.size(); ++i) list += (i ? ", " : "") + keys[i];
      throw Error("unknown light type '" + type + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
                  "; known types: " + list + " (area lights come from emissive materials)");
    }
    params.check_unused("light '" + type + "'");
  } catch (const FileError& e) {
    throw e.with_context(context);
  } catch (const Error& e) {
    throw Error(context + ": " + e.what());
  }
  return l;
}

}  // namespace sg
