// The OpenVDB plugin, libsynthgen_vdb.so (see vdb_io.h): reads and writes .vdb float grids.
#include "io/vdb_io.h"

#include <cmath>
#include <mutex>

#include "core/error.h"

#ifdef SYNTHGEN_HAVE_OPENVDB
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#endif

namespace sg {

namespace {

#ifdef SYNTHGEN_HAVE_OPENVDB

constexpr bool k_supported = true;

DenseGrid read_grid(const std::string& path, const std::string& grid_name) {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
  const std::string ctx = "vdb file '" + path + "'";
  openvdb::GridBase::Ptr base;
  try {
    openvdb::io::File file(path);
    file.open(false);  // no delayed loading: the file is read once, here
    if (!file.hasGrid(grid_name)) {
      std::string names;
      for (auto it = file.beginName(); it != file.endName(); ++it) names += (names.empty() ? "'" : ", '") + *it + "'";
      file.close();
      throw Error(ctx + ": no grid named '" + grid_name + "' (the file has " + (names.empty() ? "none" : names) +
                  ")");
    }
    base = file.readGrid(grid_name);
    file.close();
  } catch (const openvdb::Exception& e) {
    throw Error(ctx + ": " + e.what());
  }
  openvdb::FloatGrid::Ptr grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
  if (!grid) throw Error(ctx + ": grid '" + grid_name + "' holds " + base->valueType() + " values, not float");
  const openvdb::math::Transform& xf = grid->transform();
  // Axis-aligned: each index axis maps onto the same world axis.
  const openvdb::Vec3d o = xf.indexToWorld(openvdb::Vec3d(0.0));
  for (int a = 0; a < 3; ++a) {
    openvdb::Vec3d e(0.0);
    e[a] = 1.0;
    const openvdb::Vec3d w = xf.indexToWorld(e) - o;
    for (int b = 0; b < 3; ++b)
      if (b != a && std::fabs(w[b]) > 1e-9 * w.length())
        throw Error(ctx + ": grid '" + grid_name + "' has a rotated or sheared transform (only scale and "
                    "translation are supported)");
    if (!(w[a] > 0.0)) throw Error(ctx + ": grid '" + grid_name + "' has a mirrored or degenerate transform");
  }
  const openvdb::CoordBBox bbox = grid->evalActiveVoxelBoundingBox();
  if (bbox.empty()) throw Error(ctx + ": grid '" + grid_name + "' has no active voxels");
  const openvdb::Coord dim = bbox.dim();
  const double count = double(dim.x()) * double(dim.y()) * double(dim.z());
  if (count > 256.0 * 1024 * 1024)
    throw Error(ctx + ": grid '" + grid_name + "' spans " + std::to_string(dim.x()) + " x " +
                std::to_string(dim.y()) + " x " + std::to_string(dim.z()) + " voxels (more than 2^28)");
  DenseGrid out;
  out.nx = dim.x();
  out.ny = dim.y();
  out.nz = dim.z();
  out.values.resize(size_t(count));
  auto acc = grid->getConstAccessor();
  size_t k = 0;
  for (int z = bbox.min().z(); z <= bbox.max().z(); ++z)
    for (int y = bbox.min().y(); y <= bbox.max().y(); ++y)
      for (int x = bbox.min().x(); x <= bbox.max().x(); ++x) out.values[k++] = acc.getValue(openvdb::Coord(x, y, z));
  // OpenVDB's voxel centres are at integer index coordinates: voxel i covers [i - 0.5, i + 0.5].
  const openvdb::Vec3d lo = xf.indexToWorld(bbox.min().asVec3d() - openvdb::Vec3d(0.5));
  const openvdb::Vec3d hi = xf.indexToWorld(bbox.max().asVec3d() + openvdb::Vec3d(0.5));
  out.lo = Vec3f(float(lo.x()), float(lo.y()), float(lo.z()));
  out.hi = Vec3f(float(hi.x()), float(hi.y()), float(hi.z()));
  return out;
}

void write_grid(const std::string& path, const std::string& grid_name, const DenseGrid& g) {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
  auto grid = openvdb::FloatGrid::create(0.f);
  grid->setName(grid_name);
  const openvdb::Vec3d voxel((g.hi.x - g.lo.x) / g.nx, (g.hi.y - g.lo.y) / g.ny, (g.hi.z - g.lo.z) / g.nz);
  // Index i's centre at lo + (i + 0.5) voxel.
  openvdb::math::Transform::Ptr xf = openvdb::math::Transform::createLinearTransform(1.0);
  xf->postScale(voxel);
  xf->postTranslate(openvdb::Vec3d(g.lo.x, g.lo.y, g.lo.z) + 0.5 * voxel);
  grid->setTransform(xf);
  auto acc = grid->getAccessor();
  size_t k = 0;
  for (int z = 0; z < g.nz; ++z)
    for (int y = 0; y < g.ny; ++y)
      for (int x = 0; x < g.nx; ++x, ++k)
        if (g.values[k] != 0.f) acc.setValueOn(openvdb::Coord(x, y, z), g.values[k]);
  try {
    openvdb::io::File(path).write({grid});
  } catch (const openvdb::Exception& e) {
    throw Error("vdb file '" + path + "': " + e.what());
  }
}

#else

constexpr bool k_supported = false;

void write_grid(const std::string& path, const std::string&, const DenseGrid&) {
  throw Error("vdb file '" + path + "': synthgen was built without OpenVDB (install libopenvdb-dev and rebuild)");
}

DenseGrid read_grid(const std::string& path, const std::string&) {
  throw Error("vdb file '" + path + "': synthgen was built without OpenVDB (install libopenvdb-dev and rebuild), "
              "so .vdb files cannot be read; a raw float32 grid can");
}

#endif

// NOTE: no exception crosses the plugin boundary (the core and this library each have their own
// copy of sg::Error's type information): errors travel as strings, the core throws them again.
bool api_read(const char* path, const char* grid_name, DenseGrid* out, std::string* error) {
  try {
    *out = read_grid(path, grid_name);
    return true;
  } catch (const std::exception& e) {
    *error = e.what();
  } catch (...) {
    *error = std::string("vdb file '") + path + "': unknown error";
  }
  return false;
}

bool api_write(const char* path, const char* grid_name, const DenseGrid* grid, std::string* error) {
  try {
    write_grid(path, grid_name, *grid);
    return true;
  } catch (const std::exception& e) {
    *error = e.what();
  } catch (...) {
    *error = std::string("vdb file '") + path + "': unknown error";
  }
  return false;
}

const VdbIoApi k_api{k_vdb_io_api_version, k_supported, api_read, api_write};

}  // namespace

}  // namespace sg

extern "C" __attribute__((visibility("default"))) const sg::VdbIoApi* synthgen_vdb_io_api() { return &sg::k_api; }
