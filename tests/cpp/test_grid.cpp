// Medium "grid" (medium/grid.cpp): voxel values at voxel centres and trilinear between them; a
// constant grid is Beer-Lambert over the box; raw float32 files and .vdb files (written here with
// OpenVDB) give the same medium as inline data; bad input names the file or key: a missing file, a
// raw file of the wrong size, a .vdb file without the grid (listing the grids it has), non-finite
// or negative densities, data of the wrong size. Tracking and bounds: test_tracking.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "io/vdb_io.h"
#include "tracked_media.h"


using namespace sg;
using namespace sgtest;

namespace {

// The OpenVDB plugin is built next to the Python module, not next to this test: point the loader
// (io/vdb_io_loader.cpp) at it before any test runs, unless the caller already did.
const bool g_vdb_plugin_env = [] { return setenv("SYNTHGEN_VDB_PLUGIN", SYNTHGEN_VDB_PLUGIN_PATH, 0) == 0; }();

std::string temp_path(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("sg_test_grid_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

std::vector<double> ramp(int nx, int ny, int nz) {
  std::vector<double> v(size_t(nx) * ny * nz);
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) v[(size_t(z) * ny + y) * nx + x] = 0.1 * x + 0.01 * y + 0.3 * (z % 2);
  return v;
}

ParamSet grid_params(const std::vector<double>& v, int nx, int ny, int nz) {
  ParamSet p;
  p.set("data", v);
  p.set("resolution", std::vector<double>{double(nx), double(ny), double(nz)});
  p.set("bounds_min", std::vector<double>{0, 0, 0});
  p.set("bounds_max", std::vector<double>{double(nx), double(ny), double(nz)});  // 1 m voxels
  p.set("extinction", 0.5);
  return p;
}

std::string error_of(const ParamSet& p) {
  try {
    create_medium("grid", p, "medium");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(grid, voxel_centres_trilinear_and_constant_beer_lambert) {
  const auto v = ramp(6, 5, 4);
  auto m = create_medium("grid", grid_params(v, 6, 5, 4), "medium");
  const TrackedMedium& g = tracked(*m);
  EXPECT_NEAR(g.density({2.5f, 1.5f, 0.5f}), v[(0 * 5 + 1) * 6 + 2], 1e-6);
  EXPECT_NEAR(g.density({3.0f, 1.5f, 0.5f}), 0.5 * (v[(0 * 5 + 1) * 6 + 2] + v[(0 * 5 + 1) * 6 + 3]), 1e-6);
  // z between centres 0.5 and 1.5 at 1.0: half of each.
  EXPECT_NEAR(g.density({2.5f, 1.5f, 1.0f}), 0.5 * (v[(0 * 5 + 1) * 6 + 2] + v[(1 * 5 + 1) * 6 + 2]), 1e-6);
  // A constant grid: exp(-sigma rho L) for the length inside the box, exactly.
  auto c = create_medium("grid", grid_params(std::vector<double>(6 * 5 * 4, 0.8), 6, 5, 4), "medium");
  EXPECT_NEAR(c->transmittance({-1.f, 2.f, 2.f}, {1.f, 0.f, 0.f}, k_inf), std::exp(-0.5 * 0.8 * 6.0), 1e-5);
  Pcg32 rng(4201);
  MediumRng st = stream(rng);
  // Constant cells: residual ratio tracking is exact.
  EXPECT_NEAR(c->transmittance_estimate({-1.f, 2.f, 2.f}, {1.f, 0.f, 0.f}, k_inf, st), std::exp(-0.5 * 0.8 * 6.0),
              1e-5);
}

TEST(grid, raw_and_vdb_files_match_inline_data) {
  const int nx = 7, ny = 5, nz = 6;
  const auto v = ramp(nx, ny, nz);
  auto inline_m = create_medium("grid", grid_params(v, nx, ny, nz), "medium");
  const std::string raw = temp_path("ramp.raw");
  {
    std::ofstream f(raw, std::ios::binary);
    for (double x : v) {
      const float y = float(x);
      f.write(reinterpret_cast<const char*>(&y), 4);
    }
  }
  ParamSet p = grid_params(v, nx, ny, nz);
  ParamSet from_raw;
  for (const auto& [k, val] : p.values())
    if (k != "data") from_raw.set(k, val);
  from_raw.set("file", raw);
  auto raw_m = create_medium("grid", from_raw, "medium");
  const Vec3f o(-1.f, 2.2f, 3.1f), d = normalize(Vec3f(1.f, 0.1f, 0.05f));
  EXPECT_EQ(raw_m->transmittance(o, d, k_inf), inline_m->transmittance(o, d, k_inf));
  // A raw file of the wrong size names the file and both sizes.
  from_raw.set("resolution", std::vector<double>{7, 5, 5});
  const std::string e = error_of(from_raw);
  EXPECT_NE(e.find(raw), std::string::npos) << e;
  EXPECT_NE(e.find("840 bytes"), std::string::npos) << e;
  from_raw.set("file", temp_path("missing.raw"));
  EXPECT_NE(error_of(from_raw).find("missing.raw"), std::string::npos) << error_of(from_raw);
  if (!vdb_supported()) {
    ParamSet q;
    q.set("file", temp_path("any.vdb"));
    q.set("extinction", 0.5);
    EXPECT_NE(error_of(q).find("without OpenVDB"), std::string::npos);
    GTEST_SKIP() << "built without OpenVDB";
  }
  // The same values (all positive: all voxels active) through a .vdb file.
  DenseGrid dense;
  dense.nx = nx;
  dense.ny = ny;
  dense.nz = nz;
  dense.lo = Vec3f(0.f);
  dense.hi = Vec3f(float(nx), float(ny), float(nz));
  for (double x : v) dense.values.push_back(float(x) + 0.05f);
  const std::string vdb = temp_path("ramp.vdb");
  write_vdb_grid(vdb, "density", dense);
  ParamSet shifted = grid_params(std::vector<double>(dense.values.begin(), dense.values.end()), nx, ny, nz);
  inline_m = create_medium("grid", shifted, "medium");
  ParamSet q;
  q.set("file", vdb);
  q.set("extinction", 0.5);
  auto vdb_m = create_medium("grid", q, "medium");
  const Box3& b = tracked(*vdb_m).majorants().box();
  EXPECT_NEAR(b.lo.x, 0.f, 1e-5);
  EXPECT_NEAR(b.hi.z, float(nz), 1e-5);
  EXPECT_NEAR(vdb_m->transmittance(o, d, k_inf), inline_m->transmittance(o, d, k_inf), 1e-6);
  std::printf("grid: T inline %.6f, vdb %.6f\n", inline_m->transmittance(o, d, k_inf),
              vdb_m->transmittance(o, d, k_inf));
  // No grid of that name: the error names the file and the grids it has.
  q.set("grid_name", "smoke");
  std::string ev = error_of(q);
  EXPECT_NE(ev.find("ramp.vdb"), std::string::npos) << ev;
  EXPECT_NE(ev.find("'density'"), std::string::npos) << ev;
  q.set("file", temp_path("missing.vdb"));
  ev = error_of(q);
  EXPECT_NE(ev.find("missing.vdb"), std::string::npos) << ev;
}

TEST(grid, bad_densities_and_sizes_are_errors) {
  auto v = ramp(4, 4, 4);
  v[(2 * 4 + 1) * 4 + 3] = -0.5;
  std::string e = error_of(grid_params(v, 4, 4, 4));
  EXPECT_NE(e.find("voxel (3, 1, 2)"), std::string::npos) << e;
  EXPECT_NE(e.find("data"), std::string::npos) << e;
  v[(2 * 4 + 1) * 4 + 3] = std::nan("");
  e = error_of(grid_params(v, 4, 4, 4));
  EXPECT_NE(e.find("finite"), std::string::npos) << e;
  e = error_of(grid_params(ramp(4, 4, 4), 4, 4, 5));
  EXPECT_NE(e.find("64 values"), std::string::npos) << e;
  ParamSet p = grid_params(ramp(4, 4, 4), 4, 4, 4);
  p.set("bounds_max", std::vector<double>{4, -1, 4});
  e = error_of(p);
  EXPECT_NE(e.find("bounds_max"), std::string::npos) << e;
  ParamSet q;
  q.set("data", ramp(2, 2, 2));
  q.set("extinction", 1.0);
  e = error_of(q);
  EXPECT_NE(e.find("resolution"), std::string::npos) << e;
}
