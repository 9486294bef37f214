// Loads the OpenVDB plugin (libsynthgen_vdb.so) on first use; see vdb_io.h.
#include <mutex>

#include "core/error.h"
#include "io/plugin_loader.h"
#include "io/vdb_io.h"

namespace sg {

namespace {

const VdbIoApi* g_api = nullptr;
std::string g_load_error;

const VdbIoApi* api() {
  static std::once_flag once;
  std::call_once(once, [] {
    std::string errors;
    g_api = load_plugin_api<VdbIoApi>("libsynthgen_vdb.so", "SYNTHGEN_VDB_PLUGIN", "synthgen_vdb_io_api",
                                      k_vdb_io_api_version, "OpenVDB", &errors);
    if (!g_api) g_load_error = "cannot load the OpenVDB plugin libsynthgen_vdb.so:" + errors;
  });
  return g_api;
}

}  // namespace

bool vdb_supported() { return api() && api()->supported; }

DenseGrid read_vdb_grid(const std::string& path, const std::string& grid_name) {
  if (!api()) throw Error("vdb file '" + path + "': " + g_load_error);
  DenseGrid grid;
  std::string err;
  if (!api()->read(path.c_str(), grid_name.c_str(), &grid, &err)) throw Error(err);
  return grid;
}

void write_vdb_grid(const std::string& path, const std::string& grid_name, const DenseGrid& grid) {
  if (!api()) throw Error("vdb file '" + path + "': " + g_load_error);
  std::string err;
  if (!api()->write(path.c_str(), grid_name.c_str(), &grid, &err)) throw Error(err);
}

}  // namespace sg
