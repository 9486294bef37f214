// Footprints of texture lookups, recorded for the texture resolution estimate
// (integrator/texture_estimate.h). While a FootprintRecorder is active on a thread, every
// image-texture lookup made on that thread reports its pyramid, its texture (the pyramid
// under one uv transform) and its footprint in image units; renders never activate one, so
// a lookup then costs one thread-local read.
//
// A footprint is given by two vectors in image units (s, t in [0, 1]): the image of one
// pixel step along the screen's x and y axes (the columns of the pixel's Jacobian, from ray
// differentials). In the texels of level L (W_L x H_L) a vector (a_s, a_t) is
// (a_s W_L, a_t H_L) long, and the pixel holds "at least one texel in at least one axis" at
// level L when the longer of the two is at least one texel:
//   rho_L = max(|(a_s W_L, a_t H_L)|, |(b_s W_L, b_t H_L)|) >= 1.
// NOTE: that is the isotropic level-of-detail rule of OpenGL (the scale factor rho of the
// OpenGL 4.6 core specification, sec. 8.14.1, eq. (8.7)-(8.9): rho = max of the two
// derivative lengths, lambda = log2 rho): the level a GPU's isotropic lookup reads at that
// pixel is the coarsest with rho_L >= 1. Recorded is the smallest rho_L of any lookup for
// every level, so that the coarsest level keeping every lookup at rho_L >= 1 is read off
// exactly, also for non-square and non-power-of-two pyramids whose levels do not halve
// both sides alike.
#pragma once

#include <atomic>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "core/math.h"

namespace sg {

class MipMap;
class Texture;
enum class WrapMode;

class FootprintRecorder {
 public:
  /// What the lookups of one pyramid (or one texture) needed.
  struct Use {
    std::vector<float> min_rho;  ///< per level: the smallest rho_L of any lookup
    uint64_t lookups = 0;
    /// Where the lookups fell (pyramids only): per level k, a flag per tile of level k
    /// (MipMap::tiles_x(k) x tiles_y(k), row-major; empty: no lookup), set for every tile
    /// within the footprint plus two texels of a lookup that reads level k (k = floor(lambda
    /// - 1/2): half a level finer than the estimate's footprint, as the render's cones differ
    /// a little), wrapped as the texture wraps.
    std::vector<std::vector<uint8_t>> cells;
    /// The tiles of `level` of `mip` the lookups of that level and finer ones fall in
    /// (MipMap::use_tiles' flags): coarser lookups read coarser levels only.
    std::vector<uint8_t> tiles(const MipMap& mip, int level) const;
    /// The coarsest level whose min_rho is >= 1 (0 when even level 0 is magnified).
    int needed_level() const;
  };

  /// A lookup of `texture` (null: a pyramid looked up directly) in `mip` at image coordinates
  /// `st` (s right, t down, before wrapping by `wrap`) with footprint vectors `a`, `b` in image
  /// units. All-zero vectors (a point lookup: alpha cut-outs, or a lookup made without a
  /// footprint) stand for the hit's own footprint: `hit_a`, `hit_b` mapped by the texture's
  /// uv transform `m` (row-major 2 x 2, image units per uv unit).
  void record(const Texture* texture, const MipMap& mip, Vec2f a, Vec2f b, const float m[4], Vec2f st,
              WrapMode wrap);

  /// What the lookups of a texture baked on demand (texture/baked.h) needed, in uv units.
  struct UvUse {
    float min_footprint = k_inf;  ///< smallest footprint of a lookup
    Vec2f lo{k_inf, k_inf}, hi{-k_inf, -k_inf};  ///< uv rectangle of the lookups' footprints
    uint64_t lookups = 0;
  };
  /// A lookup of a bakeable texture at `uv` with footprint `footprint` (uv units).
  void record_uv(const Texture* texture, const Vec2f& uv, float footprint);
  std::unordered_map<const Texture*, UvUse> by_uv;

  /// Adds another recorder's lookups (per-thread recorders are merged once at the end:
  /// minima, so the order does not matter).
  void merge(const FootprintRecorder& other);

  /// The footprint of the hit being shaded, in uv units (set by the estimate per hit).
  Vec2f hit_a, hit_b;

  std::unordered_map<const MipMap*, Use> by_mip;
  std::unordered_map<const Texture*, Use> by_texture;
};

/// Recorders in scope on any thread: renders, which never record, then skip the thread-local
/// lookup (a call into the TLS machinery of a shared library) on every texture lookup.
extern std::atomic<int> g_footprint_recorders;
FootprintRecorder* thread_footprint_recorder();

/// The recorder active on this thread (null while rendering).
inline FootprintRecorder* active_footprint_recorder() {
  return g_footprint_recorders.load(std::memory_order_relaxed) ? thread_footprint_recorder() : nullptr;
}

/// Makes `recorder` the thread's active recorder for the scope.
class ScopedFootprintRecorder {
 public:
  explicit ScopedFootprintRecorder(FootprintRecorder* recorder);
  ~ScopedFootprintRecorder();
  ScopedFootprintRecorder(const ScopedFootprintRecorder&) = delete;
  ScopedFootprintRecorder& operator=(const ScopedFootprintRecorder&) = delete;

 private:
  FootprintRecorder* m_previous;
};

}  // namespace sg
