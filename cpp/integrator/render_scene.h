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
  const AreaLight* light = nullptr;
  int32_t light_index = -1;
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
  Distribution1D light_pick;
  std::vector<uint32_t> infinite_lights;  ///< indices into `lights`
  /// Infinite lights seen only by glossy / specular bounces (Light::reflection_only); not in
  /// `lights` (never sampled).
  std::vector<const Light*> reflection_lights;
  PinholeCamera camera;
  Bounds3 bounds;
  /// False when no ray can pick up emission by hitting something (no emissive surfaces,
  /// no infinite lights): paths then end right after their last light sample.
  bool has_hittable_emitters = false;
  /// Some instance is a catcher: render differentially (Film::differential).
  bool has_catchers = false;

  const Material* material_of(const InstanceRecord& inst, uint32_t prim) const {
    if (!inst.override_material && inst.triangle_materials) {
      const Material* m = (*inst.triangle_materials)[prim];
      if (m) return m;
    }
    return inst.material;
  }
};

}  // namespace sg
