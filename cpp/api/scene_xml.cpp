// Scene::save / Scene::load: the scene state as XML (pugixml, the only file using
// its API) plus a binary sidecar "<file>.bin" with mesh data and the pixels of images
// that live in memory (GLB-embedded images, Scene::add_image_texture). Ids are preserved
// exactly, so a replayed scene renders bit-identically. It lives next to the API it
// serialises (api/scene.h), so no lower layer depends on the Scene.
#include <pugixml.hpp>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "api/scene.h"
#include "api/xml_util.h"
#include "core/error.h"

namespace sg {

using namespace xml;  // NOLINT: the helpers of both XML formats

uint32_t Scene::add_texture_entry(const std::string& type, const ParamSet& params, std::shared_ptr<ImageData> pixels,
                                  bool integer_source) {
  if (pixels && type == "embedded_image")
    return add_embedded_texture(pixels, params.get_color("scale", Color(1.f)), params.get_string("source", ""));
  if (pixels && type == "image") {
    ParamSet rest;  // the pixels replace the in-memory key under "file"
    for (const auto& [k, v] : params.values())
      if (k != "file" && k != "filename") rest.set(k, v);
    return add_image_texture(pixels, integer_source, rest);
  }
  return add_texture(type, params);
}

void Scene::save(const std::string& path) const {
  std::string bin_path = path + ".bin";
  std::ofstream bin(bin_path, std::ios::binary);
  if (!bin) throw FileError(bin_path, "cannot open for writing");
  pugi::xml_document doc;
  pugi::xml_node root = doc.append_child("synthgen_scene");
  root.append_attribute("version") = 1;
  root.append_attribute("bin") = std::filesystem::path(bin_path).filename().string().c_str();
  pugi::xml_node counts = root.append_child("slots");
  counts.append_attribute("meshes") = uint64_t(m_meshes.size());
  counts.append_attribute("textures") = uint64_t(m_textures.size());
  counts.append_attribute("materials") = uint64_t(m_materials.size());
  counts.append_attribute("instances") = uint64_t(m_instances.size());
  counts.append_attribute("lights") = uint64_t(m_lights.size());

  for (size_t i = 0; i < m_textures.size(); ++i) {
    if (!m_textures[i]) continue;
    const auto& e = *m_textures[i];
    pugi::xml_node n = root.append_child("texture");
    n.append_attribute("id") = uint64_t(i);
    n.append_attribute("type") = e.type.c_str();
    if (e.pixels) {
      n.append_attribute("width") = e.pixels->width;
      n.append_attribute("height") = e.pixels->height;
      n.append_attribute("channels") = e.pixels->channels;
      n.append_attribute("offset") = append_blob(bin, e.pixels->pixels);
      if (e.pixels_integer) n.append_attribute("integer") = true;
    }
    write_params(n, e.params);
  }
  for (size_t i = 0; i < m_materials.size(); ++i) {
    if (!m_materials[i]) continue;
    pugi::xml_node n = root.append_child("material");
    n.append_attribute("id") = uint64_t(i);
    n.append_attribute("type") = m_materials[i]->type.c_str();
    write_params(n, m_materials[i]->params);
  }
  for (size_t i = 0; i < m_meshes.size(); ++i) {
    if (!m_meshes[i]) continue;
    pugi::xml_node n = root.append_child("mesh");
    n.append_attribute("id") = uint64_t(i);
    write_mesh(n, *m_meshes[i]->mesh, bin);
  }
  for (size_t i = 0; i < m_instances.size(); ++i) {
    if (!m_instances[i]) continue;
    const auto& e = *m_instances[i];
    pugi::xml_node n = root.append_child("instance");
    n.append_attribute("id") = uint64_t(i);
    n.append_attribute("mesh") = e.mesh_id;
    n.append_attribute("class_id") = e.class_id;
    n.append_attribute("instance_id") = e.instance_id;
    n.append_attribute("material") = static_cast<long long>(e.material_id);
    n.append_attribute("world_from_object") = fmt_floats(e.world_from_object.m.data(), 16).c_str();
    if (!e.visible) n.append_attribute("visible") = false;
    if (e.catcher) n.append_attribute("catcher") = true;
    if (!e.material_map.empty()) n.append_attribute("material_map") = fmt_map(e.material_map).c_str();
  }
  for (size_t i = 0; i < m_lights.size(); ++i) {
    if (!m_lights[i]) continue;
    pugi::xml_node n = root.append_child("light");
    n.append_attribute("id") = uint64_t(i);
    n.append_attribute("type") = m_lights[i]->type.c_str();
    write_params(n, m_lights[i]->params);
  }
  if (m_medium) {
    pugi::xml_node n = root.append_child("medium");
    n.append_attribute("type") = m_medium->type.c_str();
    write_params(n, m_medium->params);
  }
  if (m_camera_set) write_camera(root.append_child("camera"), m_camera);
  bin.close();
  if (!bin) throw FileError(bin_path, "write failed");
  if (!doc.save_file(path.c_str(), "  ")) throw FileError(path, "cannot write scene file");
}

std::unique_ptr<Scene> Scene::load(const std::string& path) {
  pugi::xml_document doc;
  pugi::xml_parse_result res = doc.load_file(path.c_str());
  if (!res) throw FileError(path, std::string("cannot parse scene file: ") + res.description() + " at byte " +
                                      std::to_string(res.offset));
  pugi::xml_node root = doc.child("synthgen_scene");
  if (!root) throw FileError(path, "not a synthgen scene file (no <synthgen_scene> root)");
  std::vector<char> bin = read_sidecar(path, root, "scene file");

  auto scene = std::make_unique<Scene>();
  Scene& s = *scene;
  // Slot ids are stable handles (never reused), so a file may have holes, but only as many as
  // its content allows (xml::SlotBudget): a hostile id must not make the loader allocate
  // without bound. Ids must be below the file's slot counts (<slots>).
  std::error_code ec;
  const uint64_t xml_bytes = std::filesystem::file_size(path, ec);
  SlotBudget budget{(ec ? 0 : xml_bytes) + bin.size()};
  pugi::xml_node counts = root.child("slots");
  std::map<std::string, uint64_t> n_entries;  // entries of each kind in the file
  for (pugi::xml_node n : root.children()) ++n_entries[n.name()];
  auto entries = [&](const char* tag) { return n_entries[tag]; };
  auto pad = [&](auto& vec, uint64_t id, const char* tag, const char* kind) {
    const std::string what = std::string(tag) + " id " + std::to_string(id);
    budget.check(std::min(id, UINT64_MAX - 1) + 1, entries(tag), kind, what);
    if (counts && id >= counts.attribute(kind).as_ullong())
      throw Error(what + " is not below the file's slot count of " + kind + " (" +
                  std::to_string(counts.attribute(kind).as_ullong()) + "): its ids and <slots> disagree");
    if (id < vec.size()) throw Error("duplicate id " + std::to_string(id));
    vec.resize(id);
  };
  try {
    for (pugi::xml_node n : root.children("texture")) {
      uint64_t id = n.attribute("id").as_ullong();
      pad(s.m_textures, id, "texture", "textures");
      std::string type = n.attribute("type").as_string();
      ParamSet ps = read_params(n);
      std::shared_ptr<ImageData> px;
      if (n.attribute("offset")) px = read_pixels(n, bin, "texture " + std::to_string(id));
      s.add_texture_entry(type, ps, px, n.attribute("integer").as_bool(false));
    }
    for (pugi::xml_node n : root.children("material")) {
      pad(s.m_materials, n.attribute("id").as_ullong(), "material", "materials");
      s.add_material(n.attribute("type").as_string(), read_params(n));
    }
    for (pugi::xml_node n : root.children("mesh")) {
      uint64_t id = n.attribute("id").as_ullong();
      pad(s.m_meshes, id, "mesh", "meshes");
      s.add_mesh(read_mesh(n, bin, "mesh " + std::to_string(id)));
    }
    for (pugi::xml_node n : root.children("instance")) {
      uint64_t id = n.attribute("id").as_ullong();
      pad(s.m_instances, id, "instance", "instances");
      auto t = parse_floats(n.attribute("world_from_object").as_string(), 16, "instance " + std::to_string(id));
      s.add_instance(n.attribute("mesh").as_uint(), Transform::from_row_major(t.data()),
                     n.attribute("class_id").as_uint(), n.attribute("instance_id").as_uint(),
                     n.attribute("material").as_llong());
      if (!n.attribute("visible").as_bool(true)) s.set_instance_visible(uint32_t(id), false);
      if (n.attribute("catcher").as_bool(false)) s.set_instance_catcher(uint32_t(id), true);
      if (n.attribute("material_map"))
        s.set_instance_material_map(uint32_t(id), parse_map(n.attribute("material_map").as_string(),
                                                            "instance " + std::to_string(id)));
    }
    for (pugi::xml_node n : root.children("light")) {
      pad(s.m_lights, n.attribute("id").as_ullong(), "light", "lights");
      s.add_light(n.attribute("type").as_string(), read_params(n));
    }
    if (pugi::xml_node n = root.child("medium")) s.set_medium(n.attribute("type").as_string(), read_params(n));
    if (pugi::xml_node n = root.child("camera")) s.set_camera(read_camera(n));
    const std::pair<const char*, const char*> kinds[] = {
        {"mesh", "meshes"}, {"texture", "textures"}, {"material", "materials"}, {"instance", "instances"},
        {"light", "lights"}};
    for (const auto& [tag, kind] : kinds)
      budget.check(counts.attribute(kind).as_ullong(), entries(tag), kind, std::string("the slot count of ") + kind);
    s.restore_slot_counts(counts.attribute("meshes").as_ullong(), counts.attribute("textures").as_ullong(),
                          counts.attribute("materials").as_ullong(), counts.attribute("instances").as_ullong(),
                          counts.attribute("lights").as_ullong());
  } catch (const FileError&) {
    throw;
  } catch (const Error& e) {
    throw FileError(path, e.what());
  }
  return scene;
}

}  // namespace sg
