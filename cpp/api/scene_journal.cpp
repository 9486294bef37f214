// The change journal (api/journal.h): recording, writing (XML in the scene file's vocabulary
// plus a binary sidecar) and replaying. The files a journal names are recorded by content
// (api/journal_resources.h).

#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>

#include "api/journal_resources.h"
#include "api/scene.h"
#include "api/xml_util.h"
#include "core/error.h"
#include "core/plugin.h"

namespace sg {

using namespace xml;  // NOLINT: the helpers of both XML formats

namespace {

using K = JournalOp::Kind;

const std::pair<K, const char*> k_names[] = {
    {K::AddMesh, "add_mesh"}, {K::UpdateMesh, "update_mesh"}, {K::RemoveMesh, "remove_mesh"},
    {K::AddShape, "add_shape"}, {K::AddTexture, "add_texture"}, {K::RemoveTexture, "remove_texture"},
    {K::AddMaterial, "add_material"}, {K::UpdateMaterial, "update_material"}, {K::RemoveMaterial, "remove_material"},
    {K::AddInstance, "add_instance"}, {K::SetInstanceTransform, "set_instance_transform"},
    {K::SetInstanceLabels, "set_instance_labels"}, {K::SetInstanceMaterial, "set_instance_material"},
    {K::SetInstanceMaterialMap, "set_instance_material_map"}, {K::SetInstanceMesh, "set_instance_mesh"},
    {K::RemoveInstance, "remove_instance"}, {K::SetInstanceVisible, "set_instance_visible"},
    {K::SetInstanceCatcher, "set_instance_catcher"}, {K::AddLight, "add_light"}, {K::UpdateLight, "update_light"},
    {K::RemoveLight, "remove_light"}, {K::SetMedium, "set_medium"}, {K::ClearMedium, "clear_medium"},
    {K::SetCamera, "set_camera"}, {K::SlotCounts, "slot_counts"}, {K::Commit, "commit"},
    {K::Extension, "extension"}, {K::Render, "render"},
};

pugi::xml_node open_journal(pugi::xml_document& doc, const std::string& path) {
  pugi::xml_parse_result res = doc.load_file(path.c_str());
  if (!res) throw FileError(path, std::string("cannot parse journal: ") + res.description() + " at byte " +
                                      std::to_string(res.offset));
  pugi::xml_node root = doc.child("synthgen_journal");
  if (!root) throw FileError(path, "not a synthgen journal (no <synthgen_journal> root)");
  if (root.attribute("version").as_int() != 1)
    throw FileError(path, "journal version " + std::string(root.attribute("version").as_string()) +
                              " (this synthgen reads version 1)");
  return root;
}

}  // namespace

const char* journal_op_name(JournalOp::Kind k) {
  for (const auto& [kind, name] : k_names)
    if (kind == k) return name;
  return "?";
}

bool journal_op_kind(const std::string& name, JournalOp::Kind* k) {
  for (const auto& [kind, n] : k_names)
    if (name == n) {
      *k = kind;
      return true;
    }
  return false;
}

// Recording -------------------------------------------------------------------------------

JournalOp* Scene::journal_op(JournalOp::Kind kind, uint32_t id) {
  if (!m_journaling || m_journal_muted > 0) return nullptr;
  m_journal.emplace_back();
  m_journal.back().kind = kind;
  m_journal.back().id = id;
  return &m_journal.back();
}

void Scene::begin_journal() {
  m_journal.clear();
  m_journaling = true;
  journal_state();
}

void Scene::end_journal() {
  m_journaling = false;
  m_journal.clear();
  m_journal.shrink_to_fit();
}

void Scene::note_extension(const std::string& source, const std::string& sha256, const std::string& text) {
  for (const auto& e : m_extensions)
    if (e.sha256 == sha256) return;
  m_extensions.push_back({source, sha256, text});
  if (JournalOp* o = journal_op(K::Extension)) {
    o->type = source;
    o->params.set("sha256", sha256);
    o->text = text;
  }
}

void Scene::journal_state() {
  // In dependency order: what an object refers to has a smaller id or comes in an earlier
  // group (textures, materials, meshes, instances), as Scene::save writes it.
  for (const auto& e : m_extensions)
    if (JournalOp* o = journal_op(K::Extension)) {
      o->type = e.source;
      o->params.set("sha256", e.sha256);
      o->text = e.text;
    }
  for (size_t i = 0; i < m_textures.size(); ++i)
    if (m_textures[i]) {
      JournalOp* o = journal_op(K::AddTexture, uint32_t(i));
      o->type = m_textures[i]->type;
      o->params = m_textures[i]->params;
      o->pixels = m_textures[i]->pixels;
      o->flag = m_textures[i]->pixels_integer;
    }
  for (size_t i = 0; i < m_materials.size(); ++i)
    if (m_materials[i]) {
      JournalOp* o = journal_op(K::AddMaterial, uint32_t(i));
      o->type = m_materials[i]->type;
      o->params = m_materials[i]->params;
    }
  for (size_t i = 0; i < m_meshes.size(); ++i)
    if (m_meshes[i]) {
      if (!m_meshes[i]->shape_type.empty()) {
        JournalOp* o = journal_op(K::AddShape, uint32_t(i));
        o->type = m_meshes[i]->shape_type;
        o->params = m_meshes[i]->shape_params;
      } else {
        journal_op(K::AddMesh, uint32_t(i))->mesh = m_meshes[i]->mesh;
      }
    }
  for (size_t i = 0; i < m_instances.size(); ++i) {
    if (!m_instances[i]) continue;
    const InstanceEntry& e = *m_instances[i];
    JournalOp* o = journal_op(K::AddInstance, uint32_t(i));
    o->a = e.mesh_id;
    o->transform = e.world_from_object;
    o->b = e.class_id;
    o->counts = {e.instance_id};
    o->material = e.material_id;
    if (!e.material_map.empty()) journal_op(K::SetInstanceMaterialMap, uint32_t(i))->pairs = e.material_map;
    if (!e.visible) journal_op(K::SetInstanceVisible, uint32_t(i))->flag = false;
    if (e.catcher) journal_op(K::SetInstanceCatcher, uint32_t(i))->flag = true;
  }
  for (size_t i = 0; i < m_lights.size(); ++i)
    if (m_lights[i]) {
      JournalOp* o = journal_op(K::AddLight, uint32_t(i));
      o->type = m_lights[i]->type;
      o->params = m_lights[i]->params;
    }
  if (m_medium) {
    JournalOp* o = journal_op(K::SetMedium);
    o->type = m_medium->type;
    o->params = m_medium->params;
  }
  if (m_camera_set) journal_op(K::SetCamera)->camera = m_camera;
  journal_op(K::SlotCounts)->counts = {m_meshes.size(), m_textures.size(), m_materials.size(), m_instances.size(),
                                       m_lights.size()};
}

// Writing ---------------------------------------------------------------------------------

void Scene::save_journal(const std::string& path) const {
  if (!m_journaling) throw Error("save_journal: the scene is not recording (begin_journal() first)");
  const std::string bin_path = path + ".bin";
  std::ofstream bin(bin_path, std::ios::binary | std::ios::trunc);
  if (!bin) throw FileError(bin_path, "cannot open for writing");
  pugi::xml_document doc;
  pugi::xml_node root = doc.append_child("synthgen_journal");
  root.append_attribute("version") = 1;
  root.append_attribute("bin") = std::filesystem::path(bin_path).filename().string().c_str();
  // Meshes and pixels shared by several operations (the state and later edits) are written once.
  std::map<const void*, uint64_t> written;
  std::map<std::string, uint64_t> embedded;  // files embedded so far: sha256 -> offset
  for (const JournalOp& o : m_journal) {
    pugi::xml_node n = root.append_child("op");
    n.append_attribute("kind") = journal_op_name(o.kind);
    switch (o.kind) {
      case K::Commit: case K::ClearMedium: break;
      case K::AddMesh: case K::UpdateMesh: {
        n.append_attribute("id") = o.id;
        auto it = written.find(o.mesh.get());
        if (it != written.end()) {
          n.append_attribute("same_as") = it->second;
        } else {
          const uint64_t key = written.size() + 1;
          written[o.mesh.get()] = key;
          n.append_attribute("key") = key;
          write_mesh(n, *o.mesh, bin);
        }
        break;
      }
      case K::AddTexture:
        n.append_attribute("id") = o.id;
        n.append_attribute("type") = o.type.c_str();
        if (o.pixels) {
          n.append_attribute("width") = o.pixels->width;
          n.append_attribute("height") = o.pixels->height;
          n.append_attribute("channels") = o.pixels->channels;
          n.append_attribute("offset") = append_blob(bin, o.pixels->pixels);
          if (o.flag) n.append_attribute("integer") = true;
        }
        write_params(n, o.params);
        write_resources(n, "texture", o.type, o.params, bin, &embedded, o.pixels ? "file" : nullptr);
        break;
      case K::AddShape: case K::AddMaterial: case K::UpdateMaterial: case K::AddLight: case K::UpdateLight:
        n.append_attribute("id") = o.id;
        n.append_attribute("type") = o.type.c_str();
        write_params(n, o.params);
        write_resources(n, o.kind == K::AddShape ? "shape" : o.kind == K::AddLight || o.kind == K::UpdateLight
                                                                 ? "light" : "material",
                        o.type, o.params, bin, &embedded);
        break;
      case K::SetMedium:
        n.append_attribute("type") = o.type.c_str();
        write_params(n, o.params);
        write_resources(n, "medium", o.type, o.params, bin, &embedded);
        break;
      case K::Render:
        write_params(n, o.params);
        break;
      case K::RemoveMesh: case K::RemoveTexture: case K::RemoveMaterial: case K::RemoveInstance: case K::RemoveLight:
        n.append_attribute("id") = o.id;
        break;
      case K::AddInstance:
        n.append_attribute("id") = o.id;
        n.append_attribute("mesh") = o.a;
        n.append_attribute("class_id") = o.b;
        n.append_attribute("instance_id") = uint64_t(o.counts.empty() ? o.id + 1 : o.counts[0]);
        n.append_attribute("material") = static_cast<long long>(o.material);
        n.append_attribute("world_from_object") = fmt_floats(o.transform.m.data(), 16).c_str();
        break;
      case K::SetInstanceTransform:
        n.append_attribute("id") = o.id;
        n.append_attribute("world_from_object") = fmt_floats(o.transform.m.data(), 16).c_str();
        break;
      case K::SetInstanceLabels:
        n.append_attribute("id") = o.id;
        n.append_attribute("class_id") = o.a;
        n.append_attribute("instance_id") = o.b;
        break;
      case K::SetInstanceMaterial:
        n.append_attribute("id") = o.id;
        n.append_attribute("material") = static_cast<long long>(o.material);
        break;
      case K::SetInstanceMaterialMap:
        n.append_attribute("id") = o.id;
        n.append_attribute("material_map") = fmt_map(o.pairs).c_str();
        break;
      case K::SetInstanceMesh:
        n.append_attribute("id") = o.id;
        n.append_attribute("mesh") = o.a;
        break;
      case K::SetInstanceVisible: case K::SetInstanceCatcher:
        n.append_attribute("id") = o.id;
        n.append_attribute("value") = o.flag;
        break;
      case K::SetCamera: write_camera(n, o.camera); break;
      case K::SlotCounts: {
        const char* names[5] = {"meshes", "textures", "materials", "instances", "lights"};
        for (size_t i = 0; i < 5 && i < o.counts.size(); ++i) n.append_attribute(names[i]) = o.counts[i];
        break;
      }
      case K::Extension:
        n.append_attribute("source") = o.type.c_str();
        n.append_attribute("sha256") = o.params.get_string("sha256", "").c_str();
        n.append_attribute("offset") = append_blob(bin, std::vector<char>(o.text.begin(), o.text.end()));
        n.append_attribute("size") = uint64_t(o.text.size());
        break;
    }
  }
  bin.close();
  if (!bin) throw FileError(bin_path, "write failed");
  if (!doc.save_file(path.c_str(), "  ")) throw FileError(path, "cannot write the journal");
}

// Reading ---------------------------------------------------------------------------------

std::vector<JournalExtension> Scene::journal_extensions(const std::string& path) {
  pugi::xml_document doc;
  pugi::xml_node root = open_journal(doc, path);
  std::vector<char> bin = read_sidecar(path, root, "journal");
  std::vector<JournalExtension> out;
  for (pugi::xml_node n : root.children("op")) {
    if (std::string(n.attribute("kind").as_string()) != "extension") continue;
    std::vector<char> text;
    read_blob(bin, n.attribute("offset").as_ullong(), size_t(n.attribute("size").as_ullong()), &text,
              "extension " + std::string(n.attribute("source").as_string()));
    out.push_back({n.attribute("source").as_string(), n.attribute("sha256").as_string(), {text.begin(), text.end()}});
  }
  return out;
}

std::unique_ptr<Scene> Scene::replay(const std::string& path, ParamSet* render_params) {
  pugi::xml_document doc;
  pugi::xml_node root = open_journal(doc, path);
  std::vector<char> bin = read_sidecar(path, root, "journal");
  auto scene = std::make_unique<Scene>();
  Scene& s = *scene;
  if (render_params) *render_params = ParamSet();
  // Slot ids are handles never reused: an add gives the next id, which must be the recorded
  // one once holes (removed objects before the journal began) are padded -- as many as the
  // journal's content allows (xml::SlotBudget: its adds of the kind, its size).
  std::error_code ec;
  const uint64_t xml_bytes = std::filesystem::file_size(path, ec);
  const SlotBudget budget{(ec ? 0 : xml_bytes) + bin.size()};
  std::map<std::string, uint64_t> adds;  // add operations of each kind
  for (pugi::xml_node n : root.children("op")) {
    std::string kind = n.attribute("kind").as_string();
    ++adds[kind == "add_shape" ? "add_mesh" : kind];
  }
  auto pad = [&](auto& vec, uint64_t id, const char* op, const char* kind) {
    budget.check(std::min(id, UINT64_MAX - 1) + 1, adds[op], kind, "id " + std::to_string(id));
    if (id < vec.size()) throw Error("id " + std::to_string(id) + " is already taken");
    vec.resize(id);
  };
  auto expect = [](uint32_t got, uint64_t id) {
    if (got != id) throw Error("replayed with id " + std::to_string(got) + ", recorded " + std::to_string(id));
  };
  std::map<uint64_t, std::shared_ptr<TriangleMesh>> meshes;  // "key" -> mesh (shared by later ops)
  size_t index = 0;
  for (pugi::xml_node n : root.children("op")) {
    std::string name = n.attribute("kind").as_string();
    uint64_t id = n.attribute("id").as_ullong();
    uint32_t id32 = uint32_t(id);
    std::string where = "operation " + std::to_string(index++) + " (" + name + " " + std::to_string(id) + ")";
    // The operation's parameters, the files it names as recorded (resolve_resources).
    auto file_params = [&] { return resolve_resources(n, read_params(n), bin); };
    try {
      K k;
      if (!journal_op_kind(name, &k)) throw Error("unknown operation '" + name + "'");
      switch (k) {
        case K::Commit: s.commit(); break;
        case K::ClearMedium: s.clear_medium(); break;
        case K::AddMesh: case K::UpdateMesh: {
          TriangleMesh m;
          if (n.attribute("same_as")) {
            auto it = meshes.find(n.attribute("same_as").as_ullong());
            if (it == meshes.end()) throw Error("same_as refers to no earlier mesh");
            m = *it->second;
          } else {
            m = read_mesh(n, bin, "mesh " + std::to_string(id));
            meshes[n.attribute("key").as_ullong()] = std::make_shared<TriangleMesh>(m);
          }
          if (k == K::UpdateMesh) {
            s.update_mesh(id32, std::move(m));
          } else {
            pad(s.m_meshes, id, "add_mesh", "meshes");
            expect(s.add_mesh(std::move(m)), id);
          }
          break;
        }
        case K::AddShape:
          pad(s.m_meshes, id, "add_mesh", "meshes");
          expect(s.add_shape(n.attribute("type").as_string(), file_params()), id);
          break;
        case K::AddTexture: {
          pad(s.m_textures, id, "add_texture", "textures");
          std::string type = n.attribute("type").as_string();
          ParamSet ps = file_params();
          std::shared_ptr<ImageData> px;
          if (n.attribute("offset")) px = read_pixels(n, bin, "texture " + std::to_string(id));
          expect(s.add_texture_entry(type, ps, px, n.attribute("integer").as_bool(false)), id);
          break;
        }
        case K::AddMaterial:
          pad(s.m_materials, id, "add_material", "materials");
          expect(s.add_material(n.attribute("type").as_string(), file_params()), id);
          break;
        case K::UpdateMaterial: s.update_material(id32, n.attribute("type").as_string(), file_params()); break;
        case K::AddLight:
          pad(s.m_lights, id, "add_light", "lights");
          expect(s.add_light(n.attribute("type").as_string(), file_params()), id);
          break;
        case K::UpdateLight: s.update_light(id32, n.attribute("type").as_string(), file_params()); break;
        case K::SetMedium: s.set_medium(n.attribute("type").as_string(), file_params()); break;
        case K::RemoveMesh: s.remove_mesh(id32); break;
        case K::RemoveTexture: s.remove_texture(id32); break;
        case K::RemoveMaterial: s.remove_material(id32); break;
        case K::RemoveInstance: s.remove_instance(id32); break;
        case K::RemoveLight: s.remove_light(id32); break;
        case K::AddInstance: {
          pad(s.m_instances, id, "add_instance", "instances");
          auto t = parse_floats(n.attribute("world_from_object").as_string(), 16, "world_from_object");
          expect(s.add_instance(n.attribute("mesh").as_uint(), Transform::from_row_major(t.data()),
                                n.attribute("class_id").as_uint(), n.attribute("instance_id").as_uint(),
                                n.attribute("material").as_llong()),
                 id);
          break;
        }
        case K::SetInstanceTransform: {
          auto t = parse_floats(n.attribute("world_from_object").as_string(), 16, "world_from_object");
          s.set_instance_transform(id32, Transform::from_row_major(t.data()));
          break;
        }
        case K::SetInstanceLabels:
          s.set_instance_labels(id32, n.attribute("class_id").as_uint(), n.attribute("instance_id").as_uint());
          break;
        case K::SetInstanceMaterial: s.set_instance_material(id32, n.attribute("material").as_llong()); break;
        case K::SetInstanceMaterialMap:
          s.set_instance_material_map(id32, parse_map(n.attribute("material_map").as_string(), "material_map"));
          break;
        case K::SetInstanceMesh: s.set_instance_mesh(id32, n.attribute("mesh").as_uint()); break;
        case K::SetInstanceVisible: s.set_instance_visible(id32, n.attribute("value").as_bool()); break;
        case K::SetInstanceCatcher: s.set_instance_catcher(id32, n.attribute("value").as_bool()); break;
        case K::SetCamera: s.set_camera(read_camera(n)); break;
        case K::SlotCounts: {
          uint64_t c[5];
          const char* names[5] = {"meshes", "textures", "materials", "instances", "lights"};
          const char* ops[5] = {"add_mesh", "add_texture", "add_material", "add_instance", "add_light"};
          for (int i = 0; i < 5; ++i) {
            c[i] = n.attribute(names[i]).as_ullong();
            budget.check(c[i], adds[ops[i]], names[i], std::string("the slot count of ") + names[i]);
          }
          s.restore_slot_counts(c[0], c[1], c[2], c[3], c[4]);
          break;
        }
        case K::Extension: {
          // Loading is the caller's (synthgen.scene.extensions, with consent): the plugins must
          // exist by now; the note is kept so that the replayed scene's journal has it too.
          std::vector<char> text;
          read_blob(bin, n.attribute("offset").as_ullong(), size_t(n.attribute("size").as_ullong()), &text, "source");
          s.m_extensions.push_back({n.attribute("source").as_string(), n.attribute("sha256").as_string(),
                                    {text.begin(), text.end()}});
          break;
        }
        case K::Render:
          if (render_params) *render_params = read_params(n);
          break;
      }
    } catch (const FileError& e) {
      throw e.with_context(path + ": " + where);
    } catch (const Error& e) {
      throw FileError(path, where + ": " + e.what());
    }
  }
  return scene;
}

}  // namespace sg
