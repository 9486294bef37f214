// Internal: factory functions of the material plugins (one file each), listed in the
// table of material.cpp.
#pragma once
#include "core/error.h"
#include "material/material.h"

namespace sg {
std::shared_ptr<Material> create_coated_material(const ParamSet& params, const MaterialContext& ctx);
std::shared_ptr<Material> create_conductor_material(const ParamSet& params, const MaterialContext& ctx);
std::shared_ptr<Material> create_dielectric_material(const ParamSet& params, const MaterialContext& ctx);
std::shared_ptr<Material> create_diffuse_material(const ParamSet& params, const MaterialContext& ctx);
std::shared_ptr<Material> create_emissive_material(const ParamSet& params, const MaterialContext& ctx);
std::shared_ptr<Material> create_mix_material(const ParamSet& params, const MaterialContext& ctx);
std::shared_ptr<Material> create_principled_material(const ParamSet& params, const MaterialContext& ctx);
// New plugins: declare `create_<key>_material` here (one line, alphabetical order).
}  // namespace sg
