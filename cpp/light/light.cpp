#include "light/light.h"

#include "light/light_registry.h"

namespace sg {

std::shared_ptr<Light> create_light(const std::string& type, const ParamSet& params, const std::string& context) {
  static const std::vector<std::string> k_types = {"point", "sun", "environment"};
  std::shared_ptr<Light> l;
  try {
    if (type == "point") l = create_point_light(params);
    else if (type == "sun") l = create_sun_light(params);
    else if (type == "environment") l = create_environment_light(params);
    else {
      std::string guess = closest_match(type, k_types);
      throw Error("unknown light type '" + type + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
                  "; known types: point, sun, environment (area lights come from emissive materials)");
    }
    params.check_unused("light '" + type + "'");
  } catch (const Error& e) {
    throw Error(context + ": " + e.what());
  }
  return l;
}

}  // namespace sg
