#include "medium/medium.h"

#include "core/plugin.h"

namespace sg {

std::vector<std::string> medium_types() { return Registry::instance().names("medium"); }

std::shared_ptr<Medium> create_medium(const std::string& type, const ParamSet& params, const std::string& context) {
  return Registry::instance().create<Medium>("medium", type, params, PluginContext{}, context);
}

}  // namespace sg
