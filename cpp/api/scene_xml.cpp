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
#include <sstream>

#include "api/scene.h"
#include "api/xml_util.h"
#include "core/error.h"

namespace sg {

using namespace xml;  // NOLINT: the helpers of both XML formats

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
    const TriangleMesh& m = *m_meshes[i]->mesh;
    pugi::xml_node n = root.append_child("mesh");
    n.append_attribute("id") = uint64_t(i);
    n.append_attribute("name") = m.name.c_str();
    n.append_attribute("vertices") = uint64_t(m.positions.size());
    n.append_attribute("triangles") = uint64_t(m.triangle_count());
    n.append_attribute("positions") = append_blob(bin, m.positions);
    n.append_attribute("indices") = append_blob(bin, m.indices);
    if (!m.normals.empty()) n.append_attribute("normals") = append_blob(bin, m.normals);
    if (!m.uvs.empty()) n.append_attribute("uvs") = append_blob(bin, m.uvs);
    if (!m.material_ids.empty()) n.append_attribute("material_ids") = append_blob(bin, m.material_ids);
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
    if (!e.material_map.empty()) {
      std::string map;
      for (const auto& [from, to] : e.material_map)
        map += (map.empty() ? "" : " ") + std::to_string(from) + ":" + std::to_string(to);
      n.append_attribute("material_map") = map.c_str();
    }
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
  if (m_camera_set) {
    pugi::xml_node n = root.append_child("camera");
    float k[4] = {m_camera.fx, m_camera.fy, m_camera.cx, m_camera.cy};
    n.append_attribute("intrinsics") = fmt_floats(k, 4).c_str();
    n.append_attribute("width") = m_camera.width;
    n.append_attribute("height") = m_camera.height;
    n.append_attribute("world_from_camera") = fmt_floats(m_camera.world_from_camera.m.data(), 16).c_str();
  }
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
  std::filesystem::path bin_path = std::filesystem::path(path).parent_path() / root.attribute("bin").as_string();
  std::error_code ec;
  if (!root.attribute("bin") || !std::filesystem::is_regular_file(bin_path, ec))
    throw FileError(bin_path.string(), "the binary sidecar named by the scene file's 'bin' attribute is not a file");
  uint64_t bin_size = std::filesystem::file_size(bin_path, ec);
  std::ifstream bin_in(bin_path, std::ios::binary);
  if (ec || !bin_in) throw FileError(bin_path.string(), "cannot open binary sidecar");
  std::vector<char> bin;
  try {
    bin.resize(size_t(bin_size));
  } catch (const std::exception&) {
    throw FileError(bin_path.string(), "binary sidecar of " + std::to_string(bin_size) + " bytes does not fit in memory");
  }
  if (bin_size && !bin_in.read(bin.data(), std::streamsize(bin_size)))
    throw FileError(bin_path.string(), "cannot read binary sidecar");

  auto scene = std::make_unique<Scene>();
  Scene& s = *scene;
  // Slot ids are stable handles (never reused), so a file may have holes, but not more than
  // k_max_slots of a kind: a hostile id must not make the loader allocate without bound.
  constexpr uint64_t k_max_slots = uint64_t(1) << 24;
  auto check_slots = [&](uint64_t n, const char* what) {
    if (n > k_max_slots)
      throw Error(std::string(what) + " " + std::to_string(n) + " is out of range (at most " +
                  std::to_string(k_max_slots) + " slots of a kind)");
  };
  auto pad = [&](auto& vec, uint64_t id) {
    check_slots(id, "id");
    if (id < vec.size()) throw Error("duplicate id " + std::to_string(id));
    vec.resize(id);
  };
  try {
    for (pugi::xml_node n : root.children("texture")) {
      uint64_t id = n.attribute("id").as_ullong();
      pad(s.m_textures, id);
      std::string type = n.attribute("type").as_string();
      ParamSet ps = read_params(n);
      std::shared_ptr<ImageData> px;
      if (n.attribute("offset")) {
        px = std::make_shared<ImageData>();
        px->width = n.attribute("width").as_int();
        px->height = n.attribute("height").as_int();
        px->channels = n.attribute("channels").as_int();
        if (px->width < 1 || px->height < 1 || px->channels < 1 || px->channels > 4 || px->width > 65536 ||
            px->height > 65536)
          throw Error("texture " + std::to_string(id) + ": bad image size");
        read_blob(bin, n.attribute("offset").as_ullong(), size_t(px->width) * px->height * px->channels, &px->pixels,
                  "texture " + std::to_string(id));
      }
      if (type == "embedded_image" && px) {
        Color scale = ps.get_color("scale", Color(1.f));
        s.add_embedded_texture(px, scale, ps.get_string("source", ""));
      } else if (type == "image" && px) {
        ParamSet rest;  // the pixels replace the in-memory key under "file"
        for (const auto& [k, v] : ps.values())
          if (k != "file" && k != "filename") rest.set(k, v);
        s.add_image_texture(px, n.attribute("integer").as_bool(false), rest);
      } else {
        s.add_texture(type, ps);
      }
    }
    for (pugi::xml_node n : root.children("material")) {
      pad(s.m_materials, n.attribute("id").as_ullong());
      s.add_material(n.attribute("type").as_string(), read_params(n));
    }
    for (pugi::xml_node n : root.children("mesh")) {
      uint64_t id = n.attribute("id").as_ullong();
      pad(s.m_meshes, id);
      TriangleMesh m;
      m.name = n.attribute("name").as_string();
      size_t nv = n.attribute("vertices").as_ullong(), nt = n.attribute("triangles").as_ullong();
      std::string ctx = "mesh " + std::to_string(id);
      if (nt > bin.size()) throw Error(ctx + ": binary data is truncated");  // before 3 * nt can wrap
      read_blob(bin, n.attribute("positions").as_ullong(), nv, &m.positions, ctx);
      read_blob(bin, n.attribute("indices").as_ullong(), 3 * nt, &m.indices, ctx);
      if (n.attribute("normals")) read_blob(bin, n.attribute("normals").as_ullong(), nv, &m.normals, ctx);
      if (n.attribute("uvs")) read_blob(bin, n.attribute("uvs").as_ullong(), nv, &m.uvs, ctx);
      if (n.attribute("material_ids")) read_blob(bin, n.attribute("material_ids").as_ullong(), nt, &m.material_ids, ctx);
      s.add_mesh(std::move(m));
    }
    for (pugi::xml_node n : root.children("instance")) {
      uint64_t id = n.attribute("id").as_ullong();
      pad(s.m_instances, id);
      auto t = parse_floats(n.attribute("world_from_object").as_string(), 16, "instance " + std::to_string(id));
      s.add_instance(n.attribute("mesh").as_uint(), Transform::from_row_major(t.data()),
                     n.attribute("class_id").as_uint(), n.attribute("instance_id").as_uint(),
                     n.attribute("material").as_llong());
      if (!n.attribute("visible").as_bool(true)) s.set_instance_visible(uint32_t(id), false);
      if (n.attribute("catcher").as_bool(false)) s.set_instance_catcher(uint32_t(id), true);
      if (n.attribute("material_map")) {
        std::vector<std::pair<int32_t, int64_t>> map;
        std::istringstream is(n.attribute("material_map").as_string());
        std::string item;
        while (is >> item) {
          size_t colon = item.find(':');
          if (colon == std::string::npos) throw Error("instance " + std::to_string(id) + ": bad material_map entry '" + item + "'");
          try {
            map.emplace_back(int32_t(std::stol(item.substr(0, colon))), int64_t(std::stoll(item.substr(colon + 1))));
          } catch (const std::exception&) {
            throw Error("instance " + std::to_string(id) + ": bad material_map entry '" + item + "'");
          }
        }
        s.set_instance_material_map(uint32_t(id), map);
      }
    }
    for (pugi::xml_node n : root.children("light")) {
      pad(s.m_lights, n.attribute("id").as_ullong());
      s.add_light(n.attribute("type").as_string(), read_params(n));
    }
    if (pugi::xml_node n = root.child("medium")) s.set_medium(n.attribute("type").as_string(), read_params(n));
    if (pugi::xml_node n = root.child("camera")) {
      auto k = parse_floats(n.attribute("intrinsics").as_string(), 4, "camera");
      auto t = parse_floats(n.attribute("world_from_camera").as_string(), 16, "camera");
      PinholeCamera c;
      c.fx = k[0];
      c.fy = k[1];
      c.cx = k[2];
      c.cy = k[3];
      c.width = n.attribute("width").as_uint();
      c.height = n.attribute("height").as_uint();
      c.world_from_camera = Transform::from_row_major(t.data());
      s.set_camera(c);
    }
    pugi::xml_node counts = root.child("slots");
    for (const char* kind : {"meshes", "textures", "materials", "instances", "lights"})
      check_slots(counts.attribute(kind).as_ullong(), "slot count");
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
