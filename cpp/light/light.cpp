
#include "light/light.h"

namespace sg {

std::vector<std::string> light_types() { return Registry::instance().names("light"); }

std::shared_ptr<Light> create_light(const std::string& type, const ParamSet& params, const std::string& context) {
  return Registry::instance().create<Light>("light", type, params, PluginContext{}, context);
}

}  // namespace sg
