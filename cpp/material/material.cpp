#include "material/material.h"

#include "core/error.h"

namespace sg {

std::shared_ptr<Material> create_material(const std::string& type, const ParamSet& params,
                                          const MaterialContext& ctx, const std::string& context) {
  auto m = Registry::instance().create<Material>("material", type, params, ctx, context);
  m->cache_traits();
  return m;
}

std::vector<std::string> material_types() { return Registry::instance().names("material"); }

}  // namespace sg
