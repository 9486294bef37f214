// OpenVDB files (.vdb): a float grid read into a dense array, for the 'grid' medium. OpenVDB's API
// is used in vdb_io.cpp alone, built as the plugin libsynthgen_vdb.so (see CMakeLists.txt for why)
// that vdb_io_loader.cpp opens on first use (`import synthgen` took 0.164 s with OpenVDB's
// libraries loaded, 0.126 s without: medians of 15 runs); without OpenVDB at build time (CMake
// found no libopenvdb-dev) these are errors saying so.
#pragma once

#include <string>
#include <vector>

#include "core/math.h"

namespace sg {

/// A dense grid of voxel values: nx * ny * nz values, x fastest, then y, then z; voxel (i, j, k)
/// covers the world box lo + (i, j, k) * voxel size .. + voxel size (voxel size = (hi - lo) / n).
struct DenseGrid {
  int nx = 0, ny = 0, nz = 0;
  Vec3f lo{0.f}, hi{0.f};
  std::vector<float> values;
};

/// True when this build can read .vdb files (opens the plugin).
bool vdb_supported();
/// Reads the float grid `grid_name` of the .vdb file `path`: its active voxels' bounding box as a
/// dense grid (inactive voxels there take the background value), placed in the world by the
/// grid's transform (axis-aligned scale and translation only). Throws sg::Error naming the file:
/// missing or unreadable, no grid of that name (listing the grids), not a float grid, a rotated
/// transform, an empty or too large grid.
DenseGrid read_vdb_grid(const std::string& path, const std::string& grid_name);

/// Writes `grid` as the float grid `grid_name` (active voxels: the non-zero ones) of a new .vdb file:
/// voxel (i, j, k) at index (i, j, k), the transform placing it over [lo, hi] (axis-aligned voxels
/// of size (hi - lo) / n). For tests and tools. Throws sg::Error naming the file.
void write_vdb_grid(const std::string& path, const std::string& grid_name, const DenseGrid& grid);

/// The plugin's entry points (synthgen_vdb_io_api()): false and a message on failure.
struct VdbIoApi {
  int version;
  bool supported;
  bool (*read)(const char* path, const char* grid_name, DenseGrid* out, std::string* error);
  bool (*write)(const char* path, const char* grid_name, const DenseGrid* grid, std::string* error);
};
constexpr int k_vdb_io_api_version = 1;

}  // namespace sg

extern "C" const sg::VdbIoApi* synthgen_vdb_io_api();
