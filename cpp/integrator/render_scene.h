// The committed, read-only view of a scene that the integrator renders.
// Built by sg::Scene::commit(); contains no owning pointers and is never modified
// while rendering.
#pragma once

#include <cstdint>
#include <vector>

#include "camera/camera.h"
#include "core/sampling.h"
#include "geometry/accel.h"
#include "geometry/mesh.h"
#include "light/light.h"
#include "material/material.h"
#include "medium/medium.h"

namespace sg {

struct InstanceRecord {
  bool active = false;
  bool catcher = false;  ///< a stand-in of the photo's world (Scene::set_instance_catcher)
  const TriangleMesh* mesh = nullptr;
  Transform world_from_object;
  uint32_t class_id = 0, instance_id = 0;
  const Material* material = nullptr;  ///< instance material (override or default)
  bool override_material = false;      ///< ignore per-triangle material ids
  const std::vector<const Material*>* triangle_materials = nullptr;  ///< per triangle, may be null
  /// Per triangle, the index (into RenderScene::lights) of the area light holding it, -1 for
  /// triangles that do not emit; null when the instance emits nothing.
  const int32_t* prim_light = nullptr;
  /// Hit-point error bound = error_scale * max|object vertex coordinate| + error_offset
  /// (see make_interaction); precomputed from world_from_object at commit.
  float error_scale = 0.f, error_offset = 0.f;
  /// Object-space bounds of the mesh and the instance's object-per-world length scale
  /// (1 / cbrt|det M|), for procedural textures (relative-local mapping, footprints).
  Vec3f object_lo, object_hi;
  float object_per_world = 1.f;
};

struct RenderScene {
  const Accel* accel = nullptr;
  std::vector<InstanceRecord> instances;  ///< indexed by instance slot (= Embree instance id)
  std::vector<const Light*> lights;
  /// Per light: 1 when it exists without the inserted objects (lights of the scene, area lights
  /// of catchers), 0 for the emitters of inserted objects (their headlamps).
  std::vector<char> light_in_catcher_layer;
  /// Next-event estimation samples one light of each group at every vertex: group 1 holds
  /// the domes (Light::is_dome: lights over the whole sky), group 0 all other lights (a sun,
  /// lamps, emitters). A sunlit point then always gets a sun sample and a sky sample, each
  /// by its own strategy, rather than one or the other by chance.
  static constexpr int k_light_groups = 2;
  std::vector<uint8_t> light_group;                   ///< per light: 0 or 1
  std::vector<uint32_t> group_lights[k_light_groups];  ///< indices into `lights`
  /// Per group, its lights by power over the whole scene: the choice when there are too many
  /// lights to weigh at each shading point (pick_light).
  Distribution1D group_pick[k_light_groups];
  /// Per light, what pick_light weighs: flux density at distance d of a light with a place
  /// (power / (4 pi max(d^2, radius^2)), the sphere holding it), or at any point (power /
  /// (pi R^2), R the scene's radius: infinite lights, and lights without a place).
  struct LightWeight {
    Vec3f centre{0.f};
    float radius2 = 0.f;
    float power = 0.f;
    bool local = false;
    /// One-sided emitters whose normals lie in a cone: its axis and half-angle (the light
    /// sends nothing to points behind the cone widened by the sphere's angular radius).
    bool oriented = false;
    Vec3f axis{0.f};
    float cone_angle = k_pi;
    /// A delta light whose intensity varies with direction (Light::has_selection_intensity):
    /// weighed by its intensity towards p / d^2.
    const Light* directional = nullptr;
  };
  std::vector<LightWeight> light_weights;
  /// Up to this many lights of a group are weighed at each shading point; more fall back to
  /// group_pick. A night street holds a few dozen (street lights and their lenses, headlamp
  /// beams, each vehicle's lit lamps): weighing 64 costs a few hundred flops per vertex, less
  /// than one shadow ray.
  static constexpr size_t k_max_weighed_lights = 64;
  std::vector<uint32_t> infinite_lights;  ///< indices into `lights`
  /// Infinite lights seen only by glossy / specular bounces (Light::reflection_only); not in
  /// `lights` (never sampled).
  std::vector<const Light*> reflection_lights;
  PinholeCamera camera;
  Bounds3 bounds;
  /// The global participating medium (fog, haze), or null: every ray segment and shadow ray
  /// travels through it (path_tracer.cpp); labels do not.
  const Medium* medium = nullptr;
  /// False when no ray can pick up emission by hitting something (no emissive surfaces,
  /// no infinite lights): paths then end right after their last light sample.
  bool has_hittable_emitters = false;
  /// Some instance is a catcher: render differentially (Film::differential).
  bool has_catchers = false;

  /// Chooses a light of group g for next-event estimation at p (u in [0, 1)), returning its
  /// index into `lights` and its probability within the group in *pmf.
  /// NOTE: lights are weighed by the flux density each brings to p, isotropic and unoccluded
  /// (a one-level version of the light trees of Conty Estevez & Kulla 2018, "Importance
  /// Sampling of Many Lights with Adaptive Tree Splitting", and pbrt-v4's BVHLightSampler):
  /// by power alone, a car's small, bright lamps next to a sky whose power is counted over
  /// the whole scene are never chosen, and their light arrives only through BSDF-sampled hits,
  /// as fireflies.
  /// `total` (when given) receives the group's weights' sum at p, from which
  /// light_pmf(p, li, total) gives any of its lights' probability at p without weighing them
  /// all again.
  size_t pick_light(int g, const Vec3f& p, float u, float* pmf, float* total = nullptr) const {
    const std::vector<uint32_t>& ls = group_lights[g];
    const size_t n = ls.size();
    if (total) *total = 0.f;
    if (n == 1) {
      *pmf = 1.f;
      return ls[0];
    }
    if (n > k_max_weighed_lights) return ls[group_pick[g].sample(u, pmf)];
    float w[k_max_weighed_lights];
    float sum = weigh_lights(g, p, w);
    if (!(sum > 0.f)) return ls[group_pick[g].sample(u, pmf)];
    if (total) *total = sum;
    float target = u * sum, acc = 0.f;
    size_t i = 0;
    for (; i + 1 < n; ++i) {
      acc += w[i];
      if (target < acc && w[i] > 0.f) break;
    }
    while (w[i] <= 0.f && i > 0) --i;  // rounding at the top end: the last light with weight
    *pmf = w[i] / sum;
    return ls[i];
  }
  /// The probability that pick_light(group of li, p, ...) chooses light li.
  float light_pmf(const Vec3f& p, uint32_t li) const {
    const int g = light_group[li];
    const size_t n = group_lights[g].size();
    if (n == 1) return 1.f;
    if (n > k_max_weighed_lights) return group_pmf(li);
    float w[k_max_weighed_lights];
    return light_pmf(p, li, weigh_lights(g, p, w));
  }
  /// light_pmf with the weights' sum at p of li's group that pick_light(...) returned (0: the
  /// power distribution was used there).
  float light_pmf(const Vec3f& p, uint32_t li, float total) const {
    if (group_lights[light_group[li]].size() == 1) return 1.f;
    if (!(total > 0.f)) return group_pmf(li);
    return light_weight(li, p) / total;
  }
  /// Light li's probability in its group's power distribution.
  float group_pmf(uint32_t li) const {
    const std::vector<uint32_t>& ls = group_lights[light_group[li]];
    for (size_t k = 0; k < ls.size(); ++k)
      if (ls[k] == li) return group_pick[light_group[li]].pmf(k);
    return 0.f;
  }
  float weigh_lights(int g, const Vec3f& p, float* w) const {
    float total = 0.f;
    const std::vector<uint32_t>& ls = group_lights[g];
    for (size_t i = 0; i < ls.size(); ++i) total += (w[i] = light_weight(ls[i], p));
    return total;
  }
  /// What pick_light weighs light i by at p.
  float light_weight(size_t i, const Vec3f& p) const {
    const LightWeight& lw = light_weights[i];
    if (!lw.local) return lw.power;
    Vec3f d = p - lw.centre;
    float d2 = dot(d, d);
    // NOTE: for a delta light the flux density at p is exactly I(towards p) / d^2 (unoccluded):
    // a spot's or headlamp's beam weighs by what it sends to p (zero outside it), not by its
    // flux spread over the sphere, which under-weighs a headlamp in its beam 75-fold.
    if (lw.directional) return lw.directional->selection_intensity(p) / std::max(d2, lw.radius2);
    float w = lw.power / (4.f * k_pi * std::max(d2, lw.radius2));
    if (lw.oriented && d2 > lw.radius2) {
      // NOTE: pbrt-v4's LightBounds::Importance (Pharr et al., "Physically Based Rendering",
      // 4th ed., sec. 12.6.3): the angle between the cone's axis and the direction to p,
      // less the cone's half-angle and the sphere's angular radius, bounds the emission
      // angle from below; its cosine (0 past 90 degrees) weighs the light.
      float d_len = std::sqrt(d2);
      float cos_t = std::min(1.f, std::max(-1.f, dot(lw.axis, d) / d_len));
      float theta = std::acos(cos_t) - lw.cone_angle - std::asin(std::min(1.f, std::sqrt(lw.radius2) / d_len));
      w *= theta <= 0.f ? 1.f : (theta >= 0.5f * k_pi ? 0.f : std::cos(theta));
    }
    return w;
  }

  const Material* material_of(const InstanceRecord& inst, uint32_t prim) const {
    if (!inst.override_material && inst.triangle_materials) {
      const Material* m = (*inst.triangle_materials)[prim];
      if (m) return m;
    }
    return inst.material;
  }
};

}  // namespace sg
