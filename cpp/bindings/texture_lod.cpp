// Bindings of the texture resolution estimate: its rows as Python dicts (Scene::estimate_texture_resolution).
#include <pybind11/pybind11.h>

#include "api/scene.h"
#include "bindings/convert.h"
#include "integrator/texture_estimate.h"

namespace sg::bindings {

py::dict texture_estimate_to_py(const std::vector<TextureResolution>& res, const TextureEstimate& raw) {
  py::list rows;
  for (const TextureResolution& r : res) {
    py::dict d;
    d["texture_id"] = r.texture_id;
    d["source"] = r.source;
    d["pyramid"] = r.pyramid;
    d["width"] = r.width;
    d["height"] = r.height;
    d["channels"] = r.channels;
    d["levels"] = r.levels;
    d["alpha"] = r.alpha;
    d["seen"] = r.seen;
    d["lookups"] = r.lookups;
    d["needed_level"] = r.needed_level;
    d["needed_width"] = r.needed_width;
    d["needed_height"] = r.needed_height;
    d["texture_level"] = r.texture_level;
    d["min_rho"] = r.min_rho;
    d["bytes_full"] = r.bytes_full;
    d["bytes_needed"] = r.bytes_needed;
    d["tiles"] = r.tiles;
    d["needed_tiles"] = r.needed_tiles;
    d["first_resident"] = r.first_resident;
    d["first_used"] = r.first_used;
    d["tail_level"] = r.tail_level;
    d["bytes_resident"] = r.bytes_resident;
    rows.append(d);
  }
  py::dict out;
  out["textures"] = rows;
  out["camera_rays"] = raw.camera_rays;
  out["bounce_rays"] = raw.bounce_rays;
  return out;
}

}  // namespace sg::bindings
