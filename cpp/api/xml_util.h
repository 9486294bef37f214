// Helpers of the XML formats of the integration API (api/scene_xml.cpp: Scene::save / load;
// api/scene_journal.cpp: the change journal): numbers as text, plugin parameters as <param>
// children, arrays in a binary sidecar. Included by those two files only (pugixml's API).
#pragma once

#include <pugixml.hpp>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/params.h"

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

inline ParamSet read_params(pugi::xml_node node) {
  ParamSet ps;
  for (pugi::xml_node p : node.children("param")) {
    std::string name = p.attribute("name").as_string();
    std::string type = p.attribute("type").as_string();
    const char* v = p.attribute("value").as_string();
    if (type == "bool") ps.set(name, std::string(v) == "true");
    else if (type == "int") ps.set(name, int64_t(std::stoll(v)));
    else if (type == "float") ps.set(name, std::strtod(v, nullptr));
    else if (type == "string") ps.set(name, std::string(v));
    else if (type == "texture") ps.set(name, TextureRef{uint32_t(std::stoul(v))});
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

}  // namespace sg::xml
