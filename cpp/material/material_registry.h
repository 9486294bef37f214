// Internal: factory functions of the material plugins (one file each).
#pragma once
#include "core/error.h"
#include "material/material.h"

namespace sg {
std::shared_ptr<Material> create_diffuse_material(const ParamSet& params, const TextureLookup& textures);
std::shared_ptr<Material> create_emissive_material(const ParamSet& params, const TextureLookup& textures);
}  // namespace sg
