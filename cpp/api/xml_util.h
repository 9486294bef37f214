// Helpers of the XML formats of the integration API (api/scene_xml.cpp: Scene::save / load;
// api/scene_journal.cpp: the change journal): numbers as text, plugin parameters as <param>
// children, arrays in a binary sidecar. Included by those two files only (pugixml's API).
#pragma once

#include <pugixml.hpp>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "camera/camera.h"
#include "core/error.h"
#include "core/params.h"
#include "geometry/mesh.h"
#include "io/image_io.h"

namespace sg::xml {

inline std::string fmt_floats(const float* v, size_t n) {
  std::string s;
  char buf[32];
  for (size_t i = 0; i < n; ++i) {
    std::snprintf(buf, sizeof(buf), "%.9g", double(v[i]));
    if (i) s += ' ';
    s += buf;
  }
  return s;
}

inline std::vector<float> parse_floats(const char* s, size_t expected, const std::string& ctx) {
  std::vector<float> out;
  std::istringstream is(s);
  float f;
  while (is >> f) out.push_back(f);
  if (out.size() != expected) throw Error(ctx + ": expected " + std::to_string(expected) + " numbers");
  return out;
}

inline void write_params(pugi::xml_node node, const ParamSet& ps) {
  char buf[40];
  for (const auto& [name, value] : ps.values()) {
    pugi::xml_node p = node.append_child("param");
    p.append_attribute("name") = name.c_str();
    if (auto b = std::get_if<bool>(&value)) {
      p.append_attribute("type") = "bool";
      p.append_attribute("value") = *b ? "true" : "false";
    } else if (auto i = std::get_if<int64_t>(&value)) {
      p.append_attribute("type") = "int";
      p.append_attribute("value") = std::to_string(*i).c_str();
    } else if (auto d = std::get_if<double>(&value)) {
      p.append_attribute("type") = "float";
      std::snprintf(buf, sizeof(buf), "%.17g", *d);
      p.append_attribute("value") = buf;
    } else if (auto s = std::get_if<std::string>(&value)) {
      p.append_attribute("type") = "string";
      p.append_attribute("value") = s->c_str();
    } else if (auto v = std::get_if<std::vector<double>>(&value)) {
      p.append_attribute("type") = "floats";
      std::string out;
      for (size_t k = 0; k < v->size(); ++k) {
        std::snprintf(buf, sizeof(buf), "%.17g", (*v)[k]);
        if (k) out += ' ';
        out += buf;
      }
      p.append_attribute("value") = out.c_str();
    } else if (auto t = std::get_if<TextureRef>(&value)) {
      p.append_attribute("type") = "texture";
      p.append_attribute("value") = std::to_string(t->id).c_str();
    }
  }
}

/// The integer `text` (all of it, in [lo, hi]); throws sg::Error naming `what` otherwise.
/// NOTE: strtoll with an end pointer and errno, not std::stoll, whose std::invalid_argument and
/// std::out_of_range are not sg::Error (a hostile file must get a clear error, never a crash).
inline int64_t parse_integer(const char* text, int64_t lo, int64_t hi, const std::string& what) {
  errno = 0;
  char* end = nullptr;
  long long v = std::strtoll(text, &end, 10);
  if (end == text || *end != '\0' || errno == ERANGE || v < lo || v > hi)
    throw Error(what + ": '" + std::string(text).substr(0, 32) + "' is not an integer in [" + std::to_string(lo) +
                ", " + std::to_string(hi) + "]");
  return int64_t(v);
}

inline ParamSet read_params(pugi::xml_node node) {
  ParamSet ps;
  for (pugi::xml_node p : node.children("param")) {
    std::string name = p.attribute("name").as_string();
    std::string type = p.attribute("type").as_string();
    const char* v = p.attribute("value").as_string();
    const std::string what = "parameter '" + name + "'";
    if (type == "bool") ps.set(name, std::string(v) == "true");
    else if (type == "int") ps.set(name, parse_integer(v, INT64_MIN, INT64_MAX, what));
    else if (type == "float") {
      char* end = nullptr;
      double d = std::strtod(v, &end);
      if (end == v || *end != '\0') throw Error(what + ": '" + std::string(v).substr(0, 32) + "' is not a number");
      ps.set(name, d);
    } else if (type == "string") ps.set(name, std::string(v));
    else if (type == "texture") ps.set(name, TextureRef{uint32_t(parse_integer(v, 0, UINT32_MAX, what))});
    else if (type == "floats") {
      std::vector<double> d;
      std::istringstream is(v);
      double x;
      while (is >> x) d.push_back(x);
      ps.set(name, d);
    } else {
      throw Error("scene file: parameter '" + name + "' has unknown type '" + type + "'");
    }
  }
  return ps;
}

template <class T>
uint64_t append_blob(std::ofstream& bin, const std::vector<T>& v) {
  uint64_t off = uint64_t(bin.tellp());
  if (!v.empty()) bin.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
  return off;
}

template <class T>
void read_blob(const std::vector<char>& bin, uint64_t off, size_t count, std::vector<T>* out, const std::string& ctx) {
  // Written so that no hostile offset or count can overflow the bound.
  if (off > bin.size() || count > (bin.size() - off) / sizeof(T)) throw Error(ctx + ": binary data is truncated");
  out->resize(count);
  if (count) std::memcpy(out->data(), bin.data() + off, count * sizeof(T));
}

/// The binary sidecar that `root`'s "bin" attribute names (next to `path`), read whole;
/// `what` names the document in errors ("scene file", "journal").
inline std::vector<char> read_sidecar(const std::string& path, pugi::xml_node root, const std::string& what) {
  std::filesystem::path bin_path = std::filesystem::path(path).parent_path() / root.attribute("bin").as_string();
  std::error_code ec;
  if (!root.attribute("bin") || !std::filesystem::is_regular_file(bin_path, ec))
    throw FileError(bin_path.string(), "the binary sidecar named by the " + what + "'s 'bin' attribute is not a file");
  uint64_t size = std::filesystem::file_size(bin_path, ec);
  std::ifstream in(bin_path, std::ios::binary);
  if (ec || !in) throw FileError(bin_path.string(), "cannot open the binary sidecar");
  std::vector<char> bin;
  try {
    bin.resize(size_t(size));
  } catch (const std::exception&) {
    throw FileError(bin_path.string(), "binary sidecar of " + std::to_string(size) + " bytes does not fit in memory");
  }
  if (size && !in.read(bin.data(), std::streamsize(size))) throw FileError(bin_path.string(), "cannot read the binary sidecar");
  return bin;
}

/// Slot ids are stable handles, never reused, so a file may leave empty slots (the ids of objects
/// removed before it was written) below its highest id, and its loader allocates them all. How
/// many slots of one kind a file may make its loader allocate: its `entries` of that kind plus
/// k_free_holes empty ones, or one more per byte of the file (`file_bytes`: XML and sidecar)
/// beyond that, at most k_max_slots. A hostile id (2^24 - 1 in a file of one entry) fails before
/// anything is allocated instead of making the loader allocate 2^24 slots.
struct SlotBudget {
  static constexpr uint64_t k_max_slots = uint64_t(1) << 24;
  static constexpr uint64_t k_free_holes = uint64_t(1) << 16;
  uint64_t file_bytes = 0;

  uint64_t limit(uint64_t entries) const {
    return std::min(k_max_slots, entries + std::max(k_free_holes, file_bytes));
  }
  /// Throws unless `slots` slots of `kind` ("instances") fit, naming `what` ("instance id 7",
  /// "slot count of instances") and the file's content.
  void check(uint64_t slots, uint64_t entries, const char* kind, const std::string& what) const {
    if (slots <= limit(entries)) return;
    throw Error(what + " is out of range: the file has " + std::to_string(entries) + " " + kind + " and " +
                std::to_string(file_bytes) + " bytes, which allow at most " + std::to_string(limit(entries)) +
                " slots of " + kind + " (its entries, plus " + std::to_string(k_free_holes) +
                " empty ones or one per byte of the file)");
  }
};

/// A mesh's arrays into the sidecar, their offsets and sizes as attributes of `n`.
inline void write_mesh(pugi::xml_node n, const TriangleMesh& m, std::ofstream& bin) {
  n.append_attribute("name") = m.name.c_str();
  n.append_attribute("vertices") = uint64_t(m.positions.size());
  n.append_attribute("triangles") = uint64_t(m.triangle_count());
  n.append_attribute("positions") = append_blob(bin, m.positions);
  n.append_attribute("indices") = append_blob(bin, m.indices);
  if (!m.normals.empty()) n.append_attribute("normals") = append_blob(bin, m.normals);
  if (!m.uvs.empty()) n.append_attribute("uvs") = append_blob(bin, m.uvs);
  if (!m.material_ids.empty()) n.append_attribute("material_ids") = append_blob(bin, m.material_ids);
}

/// The mesh write_mesh wrote (bounds checked: a hostile count or offset throws).
inline TriangleMesh read_mesh(pugi::xml_node n, const std::vector<char>& bin, const std::string& ctx) {
  TriangleMesh m;
  m.name = n.attribute("name").as_string();
  size_t nv = n.attribute("vertices").as_ullong(), nt = n.attribute("triangles").as_ullong();
  if (nt > bin.size() || nv > bin.size()) throw Error(ctx + ": binary data is truncated");
  read_blob(bin, n.attribute("positions").as_ullong(), nv, &m.positions, ctx);
  read_blob(bin, n.attribute("indices").as_ullong(), 3 * nt, &m.indices, ctx);
  if (n.attribute("normals")) read_blob(bin, n.attribute("normals").as_ullong(), nv, &m.normals, ctx);
  if (n.attribute("uvs")) read_blob(bin, n.attribute("uvs").as_ullong(), nv, &m.uvs, ctx);
  if (n.attribute("material_ids")) read_blob(bin, n.attribute("material_ids").as_ullong(), nt, &m.material_ids, ctx);
  return m;
}

/// A material map as "from:to from:to".
inline std::string fmt_map(const std::vector<std::pair<int32_t, int64_t>>& map) {
  std::string s;
  for (const auto& [from, to] : map) s += (s.empty() ? "" : " ") + std::to_string(from) + ":" + std::to_string(to);
  return s;
}

inline std::vector<std::pair<int32_t, int64_t>> parse_map(const char* text, const std::string& ctx) {
  std::vector<std::pair<int32_t, int64_t>> map;
  std::istringstream is(text);
  std::string item;
  while (is >> item) {
    size_t colon = item.find(':');
    try {
      if (colon == std::string::npos) throw std::invalid_argument("no colon");
      map.emplace_back(int32_t(parse_integer(item.substr(0, colon).c_str(), INT32_MIN, INT32_MAX, ctx)),
                       parse_integer(item.substr(colon + 1).c_str(), INT64_MIN, INT64_MAX, ctx));
    } catch (const std::exception&) {
      throw Error(ctx + ": bad material_map entry '" + item + "'");
    }
  }
  return map;
}

/// An in-memory image written as width / height / channels / offset attributes of `n`.
inline std::shared_ptr<ImageData> read_pixels(pugi::xml_node n, const std::vector<char>& bin, const std::string& ctx) {
  auto px = std::make_shared<ImageData>();
  px->width = n.attribute("width").as_int();
  px->height = n.attribute("height").as_int();
  px->channels = n.attribute("channels").as_int();
  if (px->width < 1 || px->height < 1 || px->channels < 1 || px->channels > 4 || px->width > 65536 ||
      px->height > 65536)
    throw Error(ctx + ": bad image size");
  read_blob(bin, n.attribute("offset").as_ullong(), size_t(px->width) * px->height * px->channels, &px->pixels, ctx);
  return px;
}

/// A camera as attributes of `n`: intrinsics (fx fy cx cy), width, height, world_from_camera.
inline void write_camera(pugi::xml_node n, const PinholeCamera& cam) {
  float k[4] = {cam.fx, cam.fy, cam.cx, cam.cy};
  n.append_attribute("intrinsics") = fmt_floats(k, 4).c_str();
  n.append_attribute("width") = cam.width;
  n.append_attribute("height") = cam.height;
  n.append_attribute("world_from_camera") = fmt_floats(cam.world_from_camera.m.data(), 16).c_str();
}

inline PinholeCamera read_camera(pugi::xml_node n) {
  auto k = parse_floats(n.attribute("intrinsics").as_string(), 4, "camera intrinsics");
  auto t = parse_floats(n.attribute("world_from_camera").as_string(), 16, "camera world_from_camera");
  PinholeCamera c;
  c.fx = k[0];
  c.fy = k[1];
  c.cx = k[2];
  c.cy = k[3];
  c.width = n.attribute("width").as_uint();
  c.height = n.attribute("height").as_uint();
  c.world_from_camera = Transform::from_row_major(t.data());
  return c;
}

}  // namespace sg::xml
