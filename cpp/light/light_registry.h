// Internal: factory functions of the light plugins (one file each).
#pragma once
#include "core/error.h"
#include "light/light.h"

namespace sg {
std::shared_ptr<Light> create_point_light(const ParamSet& params);
std::shared_ptr<Light> create_sun_light(const ParamSet& params);
std::shared_ptr<Light> create_environment_light(const ParamSet& params);
std::shared_ptr<Light> create_envmap_light(const ParamSet& params);
std::shared_ptr<Light> create_sky_light(const ParamSet& params);
std::shared_ptr<Light> create_spot_light(const ParamSet& params);
// New plugins: declare `create_<key>_light` here (one line, alphabetical order).
}  // namespace sg
