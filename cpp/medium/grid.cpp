// Medium "grid": density from a voxel grid -- an OpenVDB file (.vdb: a float grid, "density" by
// default, placed by its transform; read by io/vdb_io.cpp), a raw float32 file (x fastest, then y,
// then z; any other extension) or values given inline -- over a world box, trilinearly interpolated
// between voxel centres and 0 outside the box. Extinction at density 1 from the visibility there.
//
// Tracked against a majorant grid (medium/tracking.h): each cell's bounds are the extreme values of
// the voxels whose interpolation reaches into it -- exact bounds, since trilinear interpolation is a
// convex combination of voxel values.
#include <algorithm>
#include <cmath>
#include <fstream>

#include "core/error.h"
#include "core/plugin.h"
#include "io/vdb_io.h"
#include "medium/tracking.h"

namespace sg {

namespace {

class VoxelGrid final : public TrackedMedium {
 public:
  VoxelGrid(float sigma, const Color& albedo, float g, DenseGrid grid, const int cells[3])
      : TrackedMedium(sigma, albedo, g, 0.125f * min_voxel(grid)), m_v(std::move(grid)) {
    m_n[0] = m_v.nx;
    m_n[1] = m_v.ny;
    m_n[2] = m_v.nz;
    for (int a = 0; a < 3; ++a) m_inv_voxel[a] = float(m_n[a]) / (m_v.hi[a] - m_v.lo[a]);
    m_grid.build(Box3{m_v.lo, m_v.hi}, cells[0], cells[1], cells[2],
                 [this](const Vec3f& lo, const Vec3f& hi) { return bounds(lo, hi); });
  }

  float density(const Vec3f& p) const override {
    // Voxel centres at integer + 0.5 in voxel units; clamped to the outermost centres at the box's
    // faces (the box itself bounds the medium).
    int i0[3], i1[3];
    float f[3];
    for (int a = 0; a < 3; ++a) {
      const float u = (p[a] - m_v.lo[a]) * m_inv_voxel[a] - 0.5f;
      const float fl = std::floor(u);
      f[a] = u - fl;
      const int i = int(fl);
      i0[a] = std::clamp(i, 0, m_n[a] - 1);
      i1[a] = std::clamp(i + 1, 0, m_n[a] - 1);
    }
    auto v = [&](int x, int y, int z) {
      return m_v.values[(size_t(z) * size_t(m_n[1]) + size_t(y)) * size_t(m_n[0]) + size_t(x)];
    };
    auto lerp = [](float t, float a, float b) { return a + t * (b - a); };
    const float c00 = lerp(f[0], v(i0[0], i0[1], i0[2]), v(i1[0], i0[1], i0[2]));
    const float c10 = lerp(f[0], v(i0[0], i1[1], i0[2]), v(i1[0], i1[1], i0[2]));
    const float c01 = lerp(f[0], v(i0[0], i0[1], i1[2]), v(i1[0], i0[1], i1[2]));
    const float c11 = lerp(f[0], v(i0[0], i1[1], i1[2]), v(i1[0], i1[1], i1[2]));
    return std::max(0.f, lerp(f[2], lerp(f[1], c00, c10), lerp(f[1], c01, c11)));
  }

 private:
  static float min_voxel(const DenseGrid& g) {
    return std::min(
        {(g.hi.x - g.lo.x) / float(g.nx), (g.hi.y - g.lo.y) / float(g.ny), (g.hi.z - g.lo.z) / float(g.nz)});
  }
  DensityBounds bounds(const Vec3f& lo, const Vec3f& hi) const {
    // The voxels whose centres' interpolation reaches the cell: one more on each side (a margin
    // for rounding at the cell's faces).
    int a0[3], a1[3];
    for (int a = 0; a < 3; ++a) {
      a0[a] = std::clamp(int(std::floor((lo[a] - m_v.lo[a]) * m_inv_voxel[a] - 0.5f)) - 1, 0, m_n[a] - 1);
      a1[a] = std::clamp(int(std::floor((hi[a] - m_v.lo[a]) * m_inv_voxel[a] - 0.5f)) + 2, 0, m_n[a] - 1);
    }
    DensityBounds b{k_inf, 0.f};
    for (int z = a0[2]; z <= a1[2]; ++z)
      for (int y = a0[1]; y <= a1[1]; ++y)
        for (int x = a0[0]; x <= a1[0]; ++x) {
          const float v = m_v.values[(size_t(z) * size_t(m_n[1]) + size_t(y)) * size_t(m_n[0]) + size_t(x)];
          b.mn = std::min(b.mn, v);
          b.mx = std::max(b.mx, v);
        }
    // NOTE: a lerp of values <= M may round an ulp above M; a relative margin covers it.
    b.mx *= 1.f + 1e-5f;
    b.mn *= 1.f - 1e-5f;
    return b;
  }

  DenseGrid m_v;
  int m_n[3];
  Vec3f m_inv_voxel{1.f};
};

/// Reads a raw float32 grid (little-endian, x fastest) of n[0] x n[1] x n[2] values.
std::vector<float> read_raw(const std::string& path, const int n[3]) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) throw Error("medium 'grid': raw grid file '" + path + "' cannot be opened");
  const auto bytes = uint64_t(f.tellg());
  const uint64_t count = uint64_t(n[0]) * uint64_t(n[1]) * uint64_t(n[2]);
  if (bytes != count * 4u)
    throw Error("medium 'grid': raw grid file '" + path + "' has " + std::to_string(bytes) + " bytes; resolution " +
                std::to_string(n[0]) + " x " + std::to_string(n[1]) + " x " + std::to_string(n[2]) + " needs " +
                std::to_string(count * 4u) + " (float32, x fastest)");
  std::vector<float> v(count);
  f.seekg(0);
  f.read(reinterpret_cast<char*>(v.data()), std::streamsize(count * 4u));
  if (!f) throw Error("medium 'grid': raw grid file '" + path + "' could not be read");
  return v;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         std::equal(suffix.rbegin(), suffix.rend(), s.rbegin(), [](char a, char b) { return std::tolower(a) == b; });
}

PluginInfo info() {
  return PluginInfo("medium", "grid",
                    "Density from a voxel grid: an OpenVDB file (.vdb, a float grid named grid_name, placed by its "
                    "transform), a raw float32 file (x fastest, then y, z; with resolution and bounds) or inline "
                    "data; trilinear between voxel centres, 0 outside the box. Extinction at density 1 from the "
                    "visibility. Tracked against a majorant grid (delta / ratio tracking): unbiased.")
      .add(tracked_medium_params("density 1", 0.95, 0.75))
      .exactly_one_of({"visibility", "extinction"})
      .add([] {
        ParamDecl file = param::path("file", "a .vdb file (OpenVDB) or a raw float32 grid (any other extension)");
        file.required = false;  // or data
        return file;
      }())
      .add(param::floats("data", "the voxel values inline (x fastest, then y, then z), instead of file"))
      .exactly_one_of({"file", "data"})
      .add(param::string("grid_name", "density", "the .vdb file's float grid to read"))
      .add(param::vec3("resolution", "voxels along x, y, z of a raw file or data (whole numbers)").in(1, 4096))
      .add(param::vec3("bounds_min", "world position in metres of the grid's lowest corner (required for raw "
                                     "files and data; overrides a .vdb file's placement)"))
      .add(param::vec3("bounds_max", "world position in metres of the grid's highest corner"))
      .requires_all("bounds_min", {"bounds_max"})
      .requires_all("bounds_max", {"bounds_min"})
      .add(param::vec3("majorant_cells", "cells of the majorant grid along x, y, z (whole numbers)")
               .in(1, 512)
               .default_is("one per 4 voxels along each axis, at most 64"));
}

std::shared_ptr<Medium> create(const Params& params, const PluginContext&) {
  DenseGrid grid;
  std::string source;
  const bool vdb = params.has("file") && ends_with(params.get_string("file"), ".vdb");
  auto whole3 = [&](const char* key, int out[3]) { whole_numbers(params, key, "grid", out); };
  if (vdb) {
    source = "vdb file '" + params.get_string("file") + "'";
    if (params.has("resolution"))
      throw Error("medium 'grid': resolution is given by the .vdb file '" + params.get_string("file") + "'");
    grid = read_vdb_grid(params.get_string("file"), params.get_string("grid_name"));
  } else {
    if (params.has("grid_name"))
      throw Error("medium 'grid': grid_name applies to .vdb files only");
    if (!params.has("resolution") || !params.has("bounds_min"))
      throw Error(std::string("medium 'grid': ") + (params.has("file") ? "a raw grid file" : "data") +
                  " needs resolution, bounds_min and bounds_max");
    int n[3];
    whole3("resolution", n);
    grid.nx = n[0];
    grid.ny = n[1];
    grid.nz = n[2];
    if (params.has("file")) {
      source = "raw grid file '" + params.get_string("file") + "'";
      grid.values = read_raw(params.get_string("file"), n);
    } else {
      source = "data";
      grid.values = params.get_floats("data");
      const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
      if (grid.values.size() != count)
        throw Error("medium 'grid': data has " + std::to_string(grid.values.size()) + " values; resolution " +
                    std::to_string(n[0]) + " x " + std::to_string(n[1]) + " x " + std::to_string(n[2]) +
                    " needs " + std::to_string(count));
    }
  }
  if (params.has("bounds_min")) {
    grid.lo = params.get_vec3("bounds_min");
    grid.hi = params.get_vec3("bounds_max");
  }
  for (int a = 0; a < 3; ++a)
    if (!(grid.hi[a] > grid.lo[a]) || !std::isfinite(grid.hi[a] - grid.lo[a]))
      throw Error("medium 'grid': " + source + ": the box's bounds_max must exceed bounds_min on every axis");
  for (size_t k = 0; k < grid.values.size(); ++k) {
    const float v = grid.values[k];
    if (!std::isfinite(v) || v < 0.f) {
      const size_t x = k % size_t(grid.nx), y = (k / size_t(grid.nx)) % size_t(grid.ny),
                   z = k / (size_t(grid.nx) * size_t(grid.ny));
      throw Error("medium 'grid': " + source + ": voxel (" + std::to_string(x) + ", " + std::to_string(y) + ", " +
                  std::to_string(z) + ") is " + std::to_string(v) + " (densities must be finite and >= 0)");
    }
  }
  int cells[3] = {std::min(64, (grid.nx + 3) / 4), std::min(64, (grid.ny + 3) / 4), std::min(64, (grid.nz + 3) / 4)};
  if (params.has("majorant_cells")) whole3("majorant_cells", cells);
  return std::make_shared<VoxelGrid>(extinction_from(params), params.get_color("albedo"), params.get_float("g"),
                                     std::move(grid), cells);
}

}  // namespace

SG_REGISTER_PLUGIN(Medium, info(), create)

}  // namespace sg
