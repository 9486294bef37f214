// Heterogeneous media: a density field sigma_t(x) = sigma * density(x) tracked against a majorant
// grid. The base of the plugins ground_fog, clouds and grid (one file each in this folder).
//
// A coarse grid over the medium's bounds holds per cell a conservative upper bound (majorant) and
// lower bound (minorant) of the density. A ray walks the cells it crosses with a 3D DDA; in each it
// tracks against that cell's bounds only, so empty cells (majorant 0) cost one DDA step and no
// density lookup, and the majorant is tight locally:
// * free flights (sample_distance): decomposition tracking -- the minorant's collisions are real
//   and sampled exactly, the residual (density - minorant) by delta tracking;
// * transmittance (shadow rays): residual ratio tracking -- exp(-minorant's optical depth) times the
//   ratio-tracking estimate of the residual's transmittance;
// * decoupled next-event estimation (sample_in_segment): delta tracking whose tentative collisions
//   are each conditioned on the rest of the segment, weighted by those conditions' probabilities;
// * labels and tests (transmittance): a deterministic midpoint quadrature through the same cells.
// NOTE: delta tracking: Woodcock, Murphy, Hemmings, Paterson 1965, "Techniques used in the GEM
// code for Monte Carlo neutronics calculations"; ratio and residual ratio tracking: Novak, Selle,
// Jarosz 2014, "Residual Ratio Tracking for Estimating Attenuation in Participating Media" (SIGGRAPH
// Asia); decomposition tracking: Kutz, Habel, Li, Novak 2017, "Spectral and Decomposition Tracking
// for Rendering Heterogeneous Volumes" (SIGGRAPH), sec. 4; majorant grids walked by a DDA: Pharr,
// Jakob, Humphreys, "Physically Based Rendering" 4th ed., sec. 11.4.3 (DDAMajorantIterator) and
// ch. 14.
#pragma once

#include <functional>
#include <vector>

#include "core/plugin.h"
#include "medium/medium.h"

namespace sg {

/// An axis-aligned box.
struct Box3 {
  Vec3f lo{0.f}, hi{0.f};
};

/// Density bounds of a cell: mn <= density(x) <= mx for every x in the cell.
struct DensityBounds {
  float mn = 0.f, mx = 0.f;
};

/// The coarse grid of per-cell density bounds over a medium's box.
class MajorantGrid {
 public:
  /// Fills an nx x ny x nz grid over `box`; `cell_bounds(lo, hi)` must return conservative bounds
  /// of the density over the cell [lo, hi] (an under-estimated majorant is a bias). Cells are
  /// computed in parallel (each a pure function of its box: deterministic).
  void build(const Box3& box, int nx, int ny, int nz,
             const std::function<DensityBounds(const Vec3f& lo, const Vec3f& hi)>& cell_bounds);
  const Box3& box() const { return m_box; }
  int res(int axis) const { return m_res[axis]; }
  const DensityBounds& cell(int x, int y, int z) const {
    return m_cells[(size_t(z) * size_t(m_res[1]) + size_t(y)) * size_t(m_res[0]) + size_t(x)];
  }
  /// The cell containing p (clamped into the grid).
  void cell_of(const Vec3f& p, int* x, int* y, int* z) const;
  /// The box of cell (x, y, z).
  Box3 cell_box(int x, int y, int z) const;
  /// The largest majorant of the grid.
  float max_density() const { return m_max; }

 private:
  Box3 m_box;
  int m_res[3] = {0, 0, 0};
  Vec3f m_cell_size{1.f};
  float m_max = 0.f;
  std::vector<DensityBounds> m_cells;
};

/// A piece of a ray inside one majorant cell: ray parameters [t0, t1) and the cell's bounds.
struct MajorantSegment {
  float t0, t1;
  DensityBounds b;
};

/// Walks the cells of a MajorantGrid that the ray o + t d, t in [0, t_max), crosses, in order
/// (a 3D DDA: Amanatides, Woo 1987, "A Fast Voxel Traversal Algorithm for Ray Tracing").
/// Allocation-free; a few dozen bytes on the stack.
class MajorantDda {
 public:
  MajorantDda(const MajorantGrid& grid, const Vec3f& o, const Vec3f& d, float t_max);
  /// The next segment; false when the ray has left the grid or reached t_max.
  bool next(MajorantSegment* seg);

 private:
  const MajorantGrid* m_grid;
  float m_t = 0.f, m_t_end = -1.f;
  float m_next_t[3] = {0.f, 0.f, 0.f}, m_delta_t[3] = {0.f, 0.f, 0.f};
  int m_cell[3] = {0, 0, 0}, m_step[3] = {0, 0, 0}, m_limit[3] = {0, 0, 0};
};

/// A medium of extinction sigma_t(x) = sigma * density(x) tracked against a majorant grid (see the
/// file's comment). Plugins implement density() and build the grid with conservative bounds.
class TrackedMedium : public Medium {
 public:
  /// The density at p (>= 0; inside the majorant grid's box -- it is never asked outside).
  virtual float density(const Vec3f& p) const = 0;
  /// Extinction per unit density (1/m): sigma_t = sigma() * density.
  float sigma() const { return m_sigma; }
  const MajorantGrid& majorants() const { return m_grid; }
  /// The quadrature's step (m) of transmittance().
  float quadrature_step() const { return m_step; }

  float transmittance(const Vec3f& o, const Vec3f& d, float t_max) const override;
  float transmittance_estimate(const Vec3f& o, const Vec3f& d, float t_max, MediumRng& rng) const override;
  bool sample_distance(const Vec3f& o, const Vec3f& d, float t_max, MediumRng& rng, float* t) const override;
  bool sample_in_segment(const Vec3f& o, const Vec3f& d, float t_max, MediumRng& rng, float* t,
                         float* weight) const override;
  Color albedo() const override { return m_albedo; }
  HenyeyGreenstein phase() const override { return HenyeyGreenstein{m_g}; }

 protected:
  /// `sigma`: extinction at density 1 (1/m); `quadrature_step`: the deterministic quadrature's
  /// largest step in metres (a fraction of the field's smallest feature).
  TrackedMedium(float sigma, const Color& albedo, float g, float quadrature_step)
      : m_sigma(sigma), m_albedo(albedo), m_g(g), m_step(quadrature_step) {}
  MajorantGrid m_grid;

 private:
  float m_sigma;
  Color m_albedo;
  float m_g, m_step;
};

/// Extinction (1/m) from a plugin's `visibility` (3.912 / V, Koschmieder) or `extinction` key.
float extinction_from(const Params& params);
/// The parameters every heterogeneous medium shares (visibility / extinction at density 1, albedo,
/// g with these defaults) for PluginInfo::add.
std::vector<ParamDecl> tracked_medium_params(const std::string& density_one, double albedo, double g);
/// The vec3 parameter `key` as three whole numbers (cell or voxel counts); an error naming
/// `medium` and the key otherwise.
void whole_numbers(const Params& params, const std::string& key, const std::string& medium, int out[3]);

}  // namespace sg
