#include "api/scene.h"

#include <cmath>
#include <string>

#include "core/error.h"
#include "film/film.h"
#include "integrator/interaction.h"

namespace sg {

Scene::Scene() : m_accel(new Accel) {
  // Cut-out materials: hits on alpha-tested meshes are filtered inside traversal.
  m_accel->set_alpha_test(&alpha_test_hit, &m_render_scene);
  ParamSet p;
  p.set("albedo", 0.5);
  MaterialContext none{[](uint32_t) { return nullptr; }, [](uint32_t) { return nullptr; }};
  m_default_material = create_material("diffuse", p, none, "default material");
}

Scene::~Scene() = default;

static Bounds3 mesh_bounds(const TriangleMesh& m) {
  if (m.shape) return m.shape->bounds();
  Bounds3 b;
  for (const auto& p : m.positions) b.expand(p);
  return b;
}

// Meshes -------------------------------------------------------------------------------

uint32_t Scene::add_mesh(TriangleMesh mesh) {
  uint32_t id = uint32_t(m_meshes.size());
  mesh.validate(mesh.name.empty() ? "mesh " + std::to_string(id) : "mesh '" + mesh.name + "'");
  for (int32_t mid : mesh.material_ids)
    if (mid >= 0) check_material_id(mid, "mesh material_ids");
  MeshEntry e;
  e.bounds = mesh_bounds(mesh);
  e.mesh = std::make_shared<TriangleMesh>(std::move(mesh));
  if (JournalOp* o = journal_op(JournalOp::Kind::AddMesh, id)) o->mesh = e.mesh;
  m_meshes.emplace_back(std::move(e));
  return id;
}

void Scene::update_mesh(uint32_t id, TriangleMesh mesh) {
  MeshEntry& e = get_slot(m_meshes, id, "mesh");
  mesh.validate(mesh.name.empty() ? "mesh " + std::to_string(id) : "mesh '" + mesh.name + "'");
  for (int32_t mid : mesh.material_ids)
    if (mid >= 0) check_material_id(mid, "mesh material_ids");
  e.bounds = mesh_bounds(mesh);
  e.mesh = std::make_shared<TriangleMesh>(std::move(mesh));
  e.shape_type.clear();
  e.dirty = true;
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::UpdateMesh, id)) o->mesh = e.mesh;
}

void Scene::remove_mesh(uint32_t id) {
  get_slot(m_meshes, id, "mesh");
  for (size_t i = 0; i < m_instances.size(); ++i)
    if (m_instances[i] && m_instances[i]->mesh_id == id)
      throw Error("mesh " + std::to_string(id) + " is still used by instance " + std::to_string(i));
  m_accel->release_mesh(id);
  m_meshes[id].reset();
  m_structure_dirty = true;
  journal_op(JournalOp::Kind::RemoveMesh, id);
}

const TriangleMesh& Scene::mesh(uint32_t id) const { return *get_slot(m_meshes, id, "mesh").mesh; }

// Textures and materials ---------------------------------------------------------------

uint32_t Scene::add_texture(const std::string& type, const ParamSet& params) {
  uint32_t id = uint32_t(m_textures.size());
  auto inputs = [this](uint32_t tid) -> std::shared_ptr<Texture> {
    return tid < m_textures.size() && m_textures[tid] ? m_textures[tid]->object : nullptr;
  };
  auto t = create_texture(type, params, "texture " + std::to_string(id), &m_images, inputs);
  m_textures.emplace_back(TextureEntry{type, params, t, nullptr, false});
  if (JournalOp* o = journal_op(JournalOp::Kind::AddTexture, id)) {
    o->type = type;
    o->params = params;
  }
  return id;
}

uint32_t Scene::add_image_texture(std::shared_ptr<ImageData> pixels, bool integer_source, const ParamSet& params) {
  const std::string ctx = "texture " + std::to_string(m_textures.size());
  if (!pixels) throw Error(ctx + ": no pixels");
  if (params.has("filename") || params.has("file"))
    throw Error(ctx + ": an in-memory image takes no 'file' (the pixels are the image)");
  const ImageData& px = *pixels;
  if (px.width < 1 || px.height < 1 || px.channels < 1 || px.channels > 4)
    throw Error(ctx + ": image of " + std::to_string(px.width) + " x " + std::to_string(px.height) + " x " +
                std::to_string(px.channels) + " values; expected at least 1 x 1 and 1 to 4 channels");
  if (px.pixels.size() != size_t(px.width) * px.height * px.channels)
    throw Error(ctx + ": pixel buffer size does not match width x height x channels");
  for (size_t i = 0; i < px.pixels.size(); ++i)
    if (!std::isfinite(px.pixels[i]))
      throw Error(ctx + ": pixel (" + std::to_string(i / px.channels % px.width) + ", " +
                  std::to_string(i / px.channels / px.width) + ") is not finite");
  ParamSet p = params;
  p.set("file", m_images.add_memory(pixels, integer_source));
  ++m_journal_muted;  // recorded below, as one operation with its pixels
  uint32_t id;
  try {
    id = add_texture("image", p);
  } catch (...) {
    --m_journal_muted;
    throw;
  }
  --m_journal_muted;
  if (JournalOp* o = journal_op(JournalOp::Kind::AddTexture, id)) {
    o->type = "image";
    o->params = params;
    o->pixels = pixels;
    o->flag = integer_source;
  }
  m_textures[id]->pixels = std::move(pixels);
  m_textures[id]->pixels_integer = integer_source;
  return id;
}

MaterialContext Scene::material_context(std::vector<uint32_t>* depends_on) const {
  MaterialContext ctx;
  ctx.textures = [this](uint32_t tid) -> std::shared_ptr<Texture> {
    return tid < m_textures.size() && m_textures[tid] ? m_textures[tid]->object : nullptr;
  };
  ctx.materials = [this, depends_on](uint32_t mid) -> std::shared_ptr<Material> {
    if (depends_on) depends_on->push_back(mid);
    return mid < m_materials.size() && m_materials[mid] ? m_materials[mid]->object : nullptr;
  };
  return ctx;
}

void Scene::assign_ao(MaterialEntry& e) const {
  float radius = 0.f, edge_radius = 0.f;
  int samples = 0, edge_samples = 0;
  for (const auto& kv : e.params.values())
    if (auto r = std::get_if<TextureRef>(&kv.second))
      if (r->id < m_textures.size() && m_textures[r->id]) {
        const Texture& t = *m_textures[r->id]->object;
        radius = std::max(radius, t.ao_radius());
        samples = std::max(samples, t.ao_samples());
        edge_radius = std::max(edge_radius, t.edge_radius());
        edge_samples = std::max(edge_samples, t.edge_samples());
      }
  for (uint32_t d : e.depends_on)
    if (d < m_materials.size() && m_materials[d]) {
      const Material& m = *m_materials[d]->object;
      radius = std::max(radius, m.ao_radius());
      samples = std::max(samples, m.ao_samples());
      edge_radius = std::max(edge_radius, m.edge_radius());
      edge_samples = std::max(edge_samples, m.edge_samples());
    }
  if (radius > 0.f) e.object->set_ao(radius, samples);
  if (edge_radius > 0.f) e.object->set_edges(edge_radius, edge_samples);
}

uint32_t Scene::add_material(const std::string& type, const ParamSet& params) {
  uint32_t id = uint32_t(m_materials.size());
  std::vector<uint32_t> deps;
  auto m = create_material(type, params, material_context(&deps), "material " + std::to_string(id));
  m_materials.emplace_back(MaterialEntry{type, params, m, deps});
  assign_ao(*m_materials.back());
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::AddMaterial, id)) {
    o->type = type;
    o->params = params;
  }
  return id;
}

void Scene::update_material(uint32_t id, const std::string& type, const ParamSet& params) {
  MaterialEntry& e = get_slot(m_materials, id, "material");
  std::vector<uint32_t> deps;
  auto object = create_material(type, params, material_context(&deps), "material " + std::to_string(id));
  // NOTE: materials may only refer to materials created before them, so that a saved
  // scene can be replayed in id order and updates propagate in one forward pass.
  for (uint32_t d : deps)
    if (d >= id)
      throw Error("material " + std::to_string(id) + ": refers to material " + std::to_string(d) +
                  "; a material may only refer to materials with smaller ids (created before it)");
  e.object = object;
  e.type = type;
  e.params = params;
  e.depends_on = deps;
  assign_ao(e);
  // Re-create the materials built from it (e.g. a "mix" of it), transitively, in id order.
  std::vector<bool> changed(m_materials.size(), false);
  changed[id] = true;
  for (size_t j = size_t(id) + 1; j < m_materials.size(); ++j) {
    if (!m_materials[j]) continue;
    MaterialEntry& dep = *m_materials[j];
    bool stale = false;
    for (uint32_t d : dep.depends_on) stale = stale || (d < changed.size() && changed[d]);
    if (!stale) continue;
    std::vector<uint32_t> dd;
    dep.object = create_material(dep.type, dep.params, material_context(&dd), "material " + std::to_string(j));
    dep.depends_on = dd;
    assign_ao(dep);
    changed[j] = true;
  }
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::UpdateMaterial, id)) {
    o->type = type;
    o->params = params;
  }
}

void Scene::check_material_id(int64_t id, const char* context) const {
  if (id < 0) return;
  if (size_t(id) >= m_materials.size() || !m_materials[size_t(id)])
    throw Error(std::string(context) + ": material " + std::to_string(id) + " does not exist");
}

// Instances ----------------------------------------------------------------------------

uint32_t Scene::add_instance(uint32_t mesh_id, const Transform& world_from_object, uint32_t class_id,
                             std::optional<uint32_t> instance_id, int64_t material_id) {
  get_slot(m_meshes, mesh_id, "mesh");
  check_material_id(material_id, "add_instance");
  uint32_t id = uint32_t(m_instances.size());
  InstanceEntry e;
  e.mesh_id = mesh_id;
  e.world_from_object = world_from_object;
  e.class_id = class_id;
  e.instance_id = instance_id ? *instance_id : id + 1;
  e.material_id = material_id;
  m_instances.emplace_back(e);
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::AddInstance, id)) {
    o->a = mesh_id;
    o->transform = world_from_object;
    o->b = class_id;
    o->counts = {e.instance_id};
    o->material = material_id;
  }
  return id;
}

void Scene::set_instance_transform(uint32_t id, const Transform& t) {
  InstanceEntry& e = get_slot(m_instances, id, "instance");
  e.world_from_object = t;
  e.dirty = true;
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::SetInstanceTransform, id)) o->transform = t;
}

void Scene::set_instance_labels(uint32_t id, uint32_t class_id, uint32_t instance_id) {
  InstanceEntry& e = get_slot(m_instances, id, "instance");
  e.class_id = class_id;
  e.instance_id = instance_id;
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::SetInstanceLabels, id)) {
    o->a = class_id;
    o->b = instance_id;
  }
}

void Scene::set_instance_mesh(uint32_t id, uint32_t mesh_id) {
  InstanceEntry& e = get_slot(m_instances, id, "instance");
  get_slot(m_meshes, mesh_id, "mesh");
  if (e.mesh_id == mesh_id) return;
  e.mesh_id = mesh_id;
  e.dirty = true;
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::SetInstanceMesh, id)) o->a = mesh_id;
}

void Scene::set_instance_material(uint32_t id, int64_t material_id) {
  InstanceEntry& e = get_slot(m_instances, id, "instance");
  check_material_id(material_id, "set_instance_material");
  e.material_id = material_id;
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::SetInstanceMaterial, id)) o->material = material_id;
}

void Scene::set_instance_material_map(uint32_t id, const std::vector<std::pair<int32_t, int64_t>>& map) {
  InstanceEntry& e = get_slot(m_instances, id, "instance");
  for (const auto& [from, to] : map) {
    if (from < -1)
      throw Error("set_instance_material_map: mesh material id " + std::to_string(from) + " (use -1 for triangles "
                  "without a material)");
    if (to < 0) throw Error("set_instance_material_map: a triangle material maps to a material id >= 0");
    check_material_id(to, "set_instance_material_map");
  }
  e.material_map = map;
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::SetInstanceMaterialMap, id)) o->pairs = map;
}

const std::vector<std::pair<int32_t, int64_t>>& Scene::instance_material_map(uint32_t id) const {
  return get_slot(m_instances, id, "instance").material_map;
}

void Scene::remove_instance(uint32_t id) {
  get_slot(m_instances, id, "instance");
  m_instances[id].reset();
  m_removed_instances.push_back(id);
  m_structure_dirty = true;
  journal_op(JournalOp::Kind::RemoveInstance, id);
}

void Scene::set_instance_visible(uint32_t id, bool visible) {
  InstanceEntry& e = get_slot(m_instances, id, "instance");
  if (e.visible == visible) return;
  e.visible = visible;
  e.dirty = true;
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::SetInstanceVisible, id)) o->flag = visible;
}

void Scene::set_instance_catcher(uint32_t id, bool catcher) {
  InstanceEntry& e = get_slot(m_instances, id, "instance");
  if (e.catcher == catcher) return;
  e.catcher = catcher;
  e.dirty = true;
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::SetInstanceCatcher, id)) o->flag = catcher;
}

bool Scene::instance_catcher(uint32_t id) const { return get_slot(m_instances, id, "instance").catcher; }

bool Scene::instance_visible(uint32_t id) const { return get_slot(m_instances, id, "instance").visible; }

size_t Scene::texture_count() const {
  size_t n = 0;
  for (const auto& t : m_textures) n += t.has_value();
  return n;
}

size_t Scene::material_count() const {
  size_t n = 0;
  for (const auto& m : m_materials) n += m.has_value();
  return n;
}

size_t Scene::instance_count() const {
  size_t n = 0;
  for (const auto& i : m_instances) n += i.has_value();
  return n;
}

// Lights and camera --------------------------------------------------------------------

uint32_t Scene::add_light(const std::string& type, const ParamSet& params) {
  uint32_t id = uint32_t(m_lights.size());
  auto l = create_light(type, params, "light " + std::to_string(id));
  m_lights.emplace_back(LightEntry{type, params, l});
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::AddLight, id)) {
    o->type = type;
    o->params = params;
  }
  return id;
}

void Scene::update_light(uint32_t id, const std::string& type, const ParamSet& params) {
  LightEntry& e = get_slot(m_lights, id, "light");
  e.object = create_light(type, params, "light " + std::to_string(id));
  e.type = type;
  e.params = params;
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::UpdateLight, id)) {
    o->type = type;
    o->params = params;
  }
}

namespace {
bool params_refer_to_texture(const ParamSet& p, uint32_t id) {
  for (const auto& kv : p.values())
    if (auto r = std::get_if<TextureRef>(&kv.second))
      if (r->id == id) return true;
  return false;
}
}  // namespace

void Scene::remove_texture(uint32_t id) {
  get_slot(m_textures, id, "texture");
  for (size_t i = 0; i < m_textures.size(); ++i)
    if (m_textures[i] && i != id && params_refer_to_texture(m_textures[i]->params, id))
      throw Error("texture " + std::to_string(id) + " is still used by texture " + std::to_string(i));
  for (size_t i = 0; i < m_materials.size(); ++i)
    if (m_materials[i] && params_refer_to_texture(m_materials[i]->params, id))
      throw Error("texture " + std::to_string(id) + " is still used by material " + std::to_string(i));
  m_textures[id].reset();
  journal_op(JournalOp::Kind::RemoveTexture, id);
}

void Scene::remove_material(uint32_t id) {
  get_slot(m_materials, id, "material");
  for (size_t i = 0; i < m_instances.size(); ++i) {
    if (!m_instances[i]) continue;
    bool used = m_instances[i]->material_id == int64_t(id);
    for (const auto& kv : m_instances[i]->material_map) used = used || kv.second == int64_t(id);
    if (used) throw Error("material " + std::to_string(id) + " is still used by instance " + std::to_string(i));
  }
  for (size_t i = 0; i < m_materials.size(); ++i)
    if (m_materials[i] && i != id)
      for (uint32_t d : m_materials[i]->depends_on)
        if (d == id) throw Error("material " + std::to_string(id) + " is still used by material " + std::to_string(i));
  for (size_t i = 0; i < m_meshes.size(); ++i)
    if (m_meshes[i])
      for (int32_t m : m_meshes[i]->mesh->material_ids)
        if (m == int32_t(id))
          throw Error("material " + std::to_string(id) + " is still used by the triangles of mesh " + std::to_string(i));
  m_materials[id].reset();
  m_structure_dirty = true;
  journal_op(JournalOp::Kind::RemoveMaterial, id);
}

void Scene::remove_light(uint32_t id) {
  get_slot(m_lights, id, "light");
  m_lights[id].reset();
  m_structure_dirty = true;
  journal_op(JournalOp::Kind::RemoveLight, id);
}

void Scene::set_medium(const std::string& type, const ParamSet& params) {
  auto m = create_medium(type, params, "medium");
  m_medium = MediumEntry{type, params, m};
  m_structure_dirty = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::SetMedium)) {
    o->type = type;
    o->params = params;
  }
}

std::vector<float> Scene::camera_transmittance(const std::vector<float>& distance) const {
  if (!m_camera_set) throw Error("camera_transmittance: no camera has been set");
  const uint32_t w = m_camera.width, h = m_camera.height;
  if (distance.size() != size_t(w) * h)
    throw Error("camera_transmittance: distance has " + std::to_string(distance.size()) + " values, the camera " +
                std::to_string(size_t(w) * h) + " pixels");
  std::vector<float> out(distance.size(), 1.f);
  if (!m_medium) return out;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      const Ray r = m_camera.generate_ray(float(x) + 0.5f, float(y) + 0.5f);
      const float d = distance[i];
      out[i] = m_medium->object->transmittance(r.o, r.d, std::isfinite(d) && d >= 0.f ? d : k_inf);
    }
  return out;
}

void Scene::clear_medium() {
  m_medium.reset();
  m_structure_dirty = true;
  journal_op(JournalOp::Kind::ClearMedium);
}

void Scene::set_camera(const PinholeCamera& camera) {
  camera.validate();
  m_camera = camera;
  m_camera_set = true;
  if (JournalOp* o = journal_op(JournalOp::Kind::SetCamera)) o->camera = camera;
}

void Scene::restore_slot_counts(size_t meshes, size_t textures, size_t materials, size_t instances, size_t lights) {
  m_meshes.resize(std::max(m_meshes.size(), meshes));
  m_textures.resize(std::max(m_textures.size(), textures));
  m_materials.resize(std::max(m_materials.size(), materials));
  m_instances.resize(std::max(m_instances.size(), instances));
  m_lights.resize(std::max(m_lights.size(), lights));
}

// Commit -------------------------------------------------------------------------------

bool Scene::has_pending_edits() const { return m_structure_dirty || !m_removed_instances.empty(); }

void Scene::commit() {
  journal_op(JournalOp::Kind::Commit);
  uint64_t builds_before = m_accel->mesh_builds();
  bool top_dirty = !m_removed_instances.empty();
  // 0. Which meshes need the alpha test: those used by an instance whose material (override
  // or per-triangle) has alpha. A mesh whose need changed is rebuilt (Embree re-commits the
  // mesh's scene when its filter functions change), and counted as a mesh BVH build.
  std::vector<char> needs_alpha = meshes_needing_alpha_test();
  // 1. Bottom-level BVHs: only new or edited meshes (or meshes whose alpha test toggled).
  for (size_t i = 0; i < m_meshes.size(); ++i) {
    auto& e = m_meshes[i];
    if (!e) continue;
    if (!e->dirty && bool(needs_alpha[i]) == m_accel->mesh_alpha_tested(uint32_t(i))) continue;
    m_accel->build_mesh(uint32_t(i), *e->mesh, needs_alpha[i] != 0);
    e->dirty = false;
    top_dirty = true;
  }
  // 2. Top level: removed and edited instances.
  for (uint32_t id : m_removed_instances) m_accel->remove_instance(id);
  m_removed_instances.clear();
  for (size_t i = 0; i < m_instances.size(); ++i) {
    auto& e = m_instances[i];
    if (!e || !e->dirty) continue;
    if (e->visible)
      m_accel->set_instance(uint32_t(i), e->mesh_id, e->world_from_object, e->catcher);
    else
      m_accel->remove_instance(uint32_t(i));  // hidden: out of the top level, mesh BVH kept
    e->dirty = false;
    top_dirty = true;
  }
  if (top_dirty) m_accel->commit();
  // 3. Records, materials and lights (cheap; no BVH work).
  if (m_structure_dirty || top_dirty) build_render_scene();
  m_structure_dirty = false;
  m_stats.mesh_bvh_builds = m_accel->mesh_builds();
  m_stats.mesh_bvh_builds_last_commit = m_accel->mesh_builds() - builds_before;
  m_stats.top_level_builds = m_accel->top_level_builds();
  m_stats.alpha_tested_meshes = 0;
  for (size_t i = 0; i < m_meshes.size(); ++i) m_stats.alpha_tested_meshes += m_meshes[i] && m_accel->mesh_alpha_tested(uint32_t(i));
  ++m_stats.commits;
}

std::vector<char> Scene::meshes_needing_alpha_test() const {
  std::vector<char> needs(m_meshes.size(), 0), triangles_checked(m_meshes.size(), 0);
  for (const auto& e : m_instances) {
    if (!e || needs[e->mesh_id]) continue;
    if (e->material_id >= 0) {
      needs[e->mesh_id] = needs[e->mesh_id] || m_materials[size_t(e->material_id)]->object->has_alpha();
      continue;
    }
    // Mapped materials of this instance (the unmapped ones are the mesh's, checked below).
    for (const auto& kv : e->material_map)
      if (m_materials[size_t(kv.second)] && m_materials[size_t(kv.second)]->object->has_alpha()) needs[e->mesh_id] = 1;
    // Per-triangle materials (missing ones fall back to the default material: opaque),
    // scanned once per mesh however many instances share it.
    if (triangles_checked[e->mesh_id]) continue;
    triangles_checked[e->mesh_id] = 1;
    for (int32_t mid : m_meshes[e->mesh_id]->mesh->material_ids)
      if (mid >= 0 && size_t(mid) < m_materials.size() && m_materials[size_t(mid)] &&
          m_materials[size_t(mid)]->object->has_alpha()) {
        needs[e->mesh_id] = 1;
        break;
      }
  }
  return needs;
}

void Scene::render(const RenderSettings& settings, Film* film) {
  if (instance_count() == 0) throw Error("render: the scene is empty (add at least one instance)");
  if (!m_camera_set) throw Error("render: no camera has been set");
  settings.validate();
  if (has_pending_edits()) commit();
  if (m_render_scene.medium && m_render_scene.has_catchers && !settings.labels_only)
    throw Error("render: a medium (" + m_medium->type + ") with shadow catchers is not supported: a photo "
                "background has no fog of its own to match (fog on photos is applied from the photo's depth)");
  m_render_scene.camera = m_camera;
  if (m_journaling) {
    if (JournalOp* o = journal_op(JournalOp::Kind::Render)) o->params = settings.to_params();
    if (!m_journal_autosave.empty()) save_journal(m_journal_autosave);
  }
  // Labels read no colour texels: label-only renders leave the textures as they are.
  RenderStats lod_stats;
  if (!settings.labels_only) {
    if (settings.texture_lod) apply_texture_lod(settings, &lod_stats);
    else use_every_texture_level();
  }
  uint64_t alpha_calls_before = m_accel->alpha_test_calls();
  render_path_traced(m_render_scene, settings, film);
  check_extension_failures();
  if (settings.denoise && !settings.labels_only) denoise_film(film);
  film->stats.alpha_test_calls = m_accel->alpha_test_calls() - alpha_calls_before;
  film->stats.mesh_bvh_builds = m_stats.mesh_bvh_builds;
  film->stats.mesh_bvh_builds_last_commit = m_stats.mesh_bvh_builds_last_commit;
  film->stats.top_level_builds = m_stats.top_level_builds;
  film->stats.texture_lod_time_s = lod_stats.texture_lod_time_s;
  film->stats.texture_baked_bytes = lod_stats.texture_baked_bytes;
  texture_memory(&film->stats.texture_bytes_full, &film->stats.texture_bytes_resident);
}

}  // namespace sg
