// Scene::build_render_scene: the committed, read-only RenderScene the integrator renders --
// instances with their materials and labels, area lights per emitting direction, the light
// groups and their weights.
#include "api/scene.h"

#include <cmath>
#include <string>

#include "core/error.h"
#include "film/film.h"
#include "integrator/interaction.h"

namespace sg {

void Scene::build_render_scene() {
  RenderScene& rs = m_render_scene;
  rs.accel = m_accel.get();
  rs.instances.assign(m_instances.size(), InstanceRecord{});
  m_instance_triangle_materials.assign(m_instances.size(), {});
  rs.lights.clear();
  rs.reflection_lights.clear();
  rs.light_in_catcher_layer.clear();
  rs.infinite_lights.clear();
  rs.has_catchers = false;
  m_area_lights.clear();
  m_prim_lights.clear();
  rs.bounds = Bounds3{};

  // Per-triangle material pointers of each mesh.
  for (auto& e : m_meshes) {
    if (!e) continue;
    e->triangle_materials.clear();
    if (e->mesh->material_ids.empty()) continue;
    e->triangle_materials.resize(e->mesh->triangle_count(), nullptr);
    for (size_t t = 0; t < e->mesh->triangle_count(); ++t) {
      int32_t mid = e->mesh->material_ids[t];
      if (mid < 0) continue;
      check_material_id(mid, "mesh material_ids");
      e->triangle_materials[t] = m_materials[size_t(mid)]->object.get();
    }
  }

  for (size_t i = 0; i < m_instances.size(); ++i) {
    const auto& e = m_instances[i];
    if (!e || !e->visible) continue;
    const MeshEntry& me = *m_meshes[e->mesh_id];
    InstanceRecord& r = rs.instances[i];
    r.active = true;
    r.catcher = e->catcher;
    rs.has_catchers = rs.has_catchers || e->catcher;
    r.mesh = me.mesh.get();
    r.world_from_object = e->world_from_object;
    r.class_id = e->class_id;
    r.instance_id = e->instance_id;
    r.override_material = e->material_id >= 0;
    r.material = r.override_material ? m_materials[size_t(e->material_id)]->object.get() : m_default_material.get();
    r.triangle_materials = me.triangle_materials.empty() ? nullptr : &me.triangle_materials;
    if (!r.override_material && !e->material_map.empty()) {
      // This instance's own per-triangle materials: the mesh's, remapped.
      auto& tm = m_instance_triangle_materials[i];
      const TriangleMesh& mesh = *me.mesh;
      tm.assign(mesh.triangle_count(), nullptr);
      for (size_t t = 0; t < tm.size(); ++t) {
        int32_t mid = mesh.material_ids.empty() ? -1 : mesh.material_ids[t];
        const Material* m = mid >= 0 ? me.triangle_materials[t] : nullptr;
        for (const auto& [from, to] : e->material_map)
          if (from == mid) m = m_materials[size_t(to)]->object.get();
        tm[t] = m;
      }
      r.triangle_materials = &tm;
    }
    r.object_lo = me.bounds.lo;
    r.object_hi = me.bounds.hi;
    {
      const auto& M = e->world_from_object.m;
      double det = double(M[0]) * (double(M[5]) * M[10] - double(M[6]) * M[9]) -
                   double(M[1]) * (double(M[4]) * M[10] - double(M[6]) * M[8]) +
                   double(M[2]) * (double(M[4]) * M[9] - double(M[5]) * M[8]);
      r.object_per_world = std::fabs(det) > 0.0 ? float(1.0 / std::cbrt(std::fabs(det))) : 1.f;
    }
    {
      const auto& M = e->world_from_object.m;
      float row_norm = 0.f, t_max = 0.f;
      for (int row = 0; row < 3; ++row) {
        row_norm = std::max(row_norm, std::fabs(M[4 * row]) + std::fabs(M[4 * row + 1]) + std::fabs(M[4 * row + 2]));
        t_max = std::max(t_max, std::fabs(M[4 * row + 3]));
      }
      r.error_scale = gamma_n(7) * row_norm;
      r.error_offset = gamma_n(7) * t_max;
    }
    // World bounds from the eight transformed corners of the object bounds.
    for (int c = 0; c < 8; ++c) {
      Vec3f p((c & 1) ? me.bounds.hi.x : me.bounds.lo.x, (c & 2) ? me.bounds.hi.y : me.bounds.lo.y,
              (c & 4) ? me.bounds.hi.z : me.bounds.lo.z);
      rs.bounds.expand(e->world_from_object.apply_point(p));
    }
    // Area light from the emissive triangles of this instance.
    std::vector<EmissiveTriangle> tris;
    const TriangleMesh& m = *me.mesh;
    const Transform& T = e->world_from_object;
    for (size_t t = 0; t < m.triangle_count(); ++t) {
      const Material* mat = rs.material_of(r, uint32_t(t));
      if (!mat->is_emissive()) continue;
      uint32_t i0 = m.indices[3 * t], i1 = m.indices[3 * t + 1], i2 = m.indices[3 * t + 2];
      EmissiveTriangle et;
      et.p0 = T.apply_point(m.positions[i0]);
      et.p1 = T.apply_point(m.positions[i1]);
      et.p2 = T.apply_point(m.positions[i2]);
      Vec3f ng = normalize(T.apply_normal(cross(m.positions[i1] - m.positions[i0], m.positions[i2] - m.positions[i0])));
      if (!m.normals.empty()) {
        Vec3f ns = T.apply_normal(m.normals[i0] + m.normals[i1] + m.normals[i2]);
        if (dot(ns, ng) < 0.f) ng = -ng;
      }
      et.n = ng;
      if (!m.uvs.empty()) {
        et.uv0 = m.uvs[i0];
        et.uv1 = m.uvs[i1];
        et.uv2 = m.uvs[i2];
      } else {
        et.uv0 = Vec2f(0, 0);
        et.uv1 = Vec2f(1, 0);
        et.uv2 = Vec2f(0, 1);
      }
      et.p_error = emissive_triangle_error(r, m.positions[i0], m.positions[i1], m.positions[i2], et.p0, et.p1, et.p2);
      et.prim = uint32_t(t);
      et.material = mat;
      tris.push_back(et);
    }
    if (!tris.empty()) {
      // One area light per direction the emitters face (the dominant axis of one-sided
      // triangles' normals; two-sided ones apart): a car's headlamps and its tail lamps are
      // then separate lights, each weighed by where it shines (RenderScene::pick_light).
      std::vector<EmissiveTriangle> bins[7];
      for (const EmissiveTriangle& et : tris) {
        int b = 6;
        if (!et.material->two_sided_emission()) {
          Vec3f a(std::fabs(et.n.x), std::fabs(et.n.y), std::fabs(et.n.z));
          int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
          b = 2 * axis + ((axis == 0 ? et.n.x : axis == 1 ? et.n.y : et.n.z) < 0.f ? 1 : 0);
        }
        bins[b].push_back(et);
      }
      m_prim_lights.emplace_back(new std::vector<int32_t>(m.triangle_count(), -1));
      std::vector<int32_t>& prim_light = *m_prim_lights.back();
      for (int b = 0; b < 7; ++b) {
        if (bins[b].empty()) continue;
        int32_t index = int32_t(rs.lights.size());
        for (const EmissiveTriangle& et : bins[b]) prim_light[et.prim] = index;
        auto light = std::make_shared<AreaLight>(uint32_t(i), uint32_t(m.triangle_count()), std::move(bins[b]));
        rs.lights.push_back(light.get());
        rs.light_in_catcher_layer.push_back(e->catcher);
        m_area_lights.push_back(light);
      }
      r.prim_light = prim_light.data();
    }
  }
  for (auto& e : m_lights) {
    if (!e) continue;
    e->object->preprocess(rs.bounds);
    if (e->object->reflection_only()) {
      rs.reflection_lights.push_back(e->object.get());
      continue;
    }
    for (const Light* part : e->object->parts()) {
      if (part->is_infinite()) rs.infinite_lights.push_back(uint32_t(rs.lights.size()));
      rs.lights.push_back(part);
      rs.light_in_catcher_layer.push_back(1);
    }
  }
  rs.medium = m_medium ? m_medium->object.get() : nullptr;
  rs.has_hittable_emitters = !m_area_lights.empty() || !rs.infinite_lights.empty() || !rs.reflection_lights.empty();
  rs.light_group.clear();
  std::vector<float> power[RenderScene::k_light_groups];
  for (int g = 0; g < RenderScene::k_light_groups; ++g) rs.group_lights[g].clear();
  for (size_t i = 0; i < rs.lights.size(); ++i) {
    const int g = rs.lights[i]->is_dome() ? 1 : 0;
    rs.light_group.push_back(uint8_t(g));
    rs.group_lights[g].push_back(uint32_t(i));
    power[g].push_back(std::max(rs.lights[i]->power(), 0.f));
  }
  for (int g = 0; g < RenderScene::k_light_groups; ++g) rs.group_pick[g] = Distribution1D(power[g]);
  rs.light_weights.clear();
  const float scene_r = std::max(rs.bounds.radius(), 1e-3f);
  for (const Light* l : rs.lights) {
    RenderScene::LightWeight lw;
    float r = 0.f;
    lw.local = !l->is_infinite() && l->bounding_sphere(&lw.centre, &r);
    // A point light's sphere: 1 mm (its weight stays finite at the light).
    r = std::max(r, 1e-3f);
    lw.radius2 = r * r;
    lw.power = lw.local ? std::max(l->power(), 0.f) : std::max(l->power(), 0.f) / (k_pi * scene_r * scene_r);
    lw.oriented = lw.local && l->normal_cone(&lw.axis, &lw.cone_angle);
    if (lw.local && l->has_selection_intensity()) lw.directional = l;
    rs.light_weights.push_back(lw);
  }
}

}  // namespace sg
