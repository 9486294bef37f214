#include "core/plugin.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

namespace sg {

std::string format_number(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  for (int prec = 6; prec <= 17; ++prec) {
    std::snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

const char* param_type_name(ParamType t) {
  switch (t) {
    case ParamType::Bool: return "bool";
    case ParamType::Int: return "int";
    case ParamType::Float: return "float";
    case ParamType::String: return "string";
    case ParamType::Path: return "path";
    case ParamType::Color: return "color";
    case ParamType::Vec2: return "vec2";
    case ParamType::Vec3: return "vec3";
    case ParamType::Floats: return "floats";
    case ParamType::Matrix4: return "matrix4";
    case ParamType::Texture: return "texture";
    case ParamType::ColorTexture: return "color_texture";
    case ParamType::FloatTexture: return "float_texture";
    case ParamType::Material: return "material";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------
// Declarations

bool ParamDecl::has_range() const { return std::isfinite(lo) || std::isfinite(hi); }

std::string ParamDecl::range_text() const {
  bool l = std::isfinite(lo), h = std::isfinite(hi);
  if (l && h)
    return std::string(lo_open ? "(" : "[") + format_number(lo) + ", " + format_number(hi) + (hi_open ? ")" : "]");
  if (l) return std::string(lo_open ? "> " : ">= ") + format_number(lo);
  if (h) return std::string(hi_open ? "< " : "<= ") + format_number(hi);
  return "";
}

bool ParamDecl::in_range(double v) const {
  if (lo_open ? !(v > lo) : !(v >= lo)) return false;
  if (hi_open ? !(v < hi) : !(v <= hi)) return false;
  return true;
}

namespace param {
namespace {
ParamDecl make(const std::string& name, ParamType type, const std::string& doc) {
  ParamDecl d;
  d.name = name;
  d.type = type;
  d.doc = doc;
  return d;
}
template <class V>
ParamDecl with_default(ParamDecl d, V v) {
  d.has_default = true;
  d.default_value = std::move(v);
  return d;
}
std::vector<double> rgb(const Color& c) { return {double(c.x), double(c.y), double(c.z)}; }
}  // namespace

ParamDecl boolean(const std::string& n, bool def, const std::string& doc) {
  return with_default(make(n, ParamType::Bool, doc), def);
}
ParamDecl integer(const std::string& n, int64_t def, const std::string& doc) {
  return with_default(make(n, ParamType::Int, doc), def);
}
ParamDecl real(const std::string& n, double def, const std::string& doc) {
  return with_default(make(n, ParamType::Float, doc), def);
}
ParamDecl real(const std::string& n, const std::string& doc) { return make(n, ParamType::Float, doc); }
ParamDecl string(const std::string& n, const std::string& def, const std::string& doc) {
  return with_default(make(n, ParamType::String, doc), def);
}
ParamDecl choice(const std::string& n, const std::string& def, std::vector<std::string> choices,
                 const std::string& doc) {
  ParamDecl d = with_default(make(n, ParamType::String, doc), def);
  d.choices = std::move(choices);
  return d;
}
ParamDecl path(const std::string& n, const std::string& doc) {
  ParamDecl d = make(n, ParamType::Path, doc);
  d.required = true;
  return d;
}
ParamDecl color(const std::string& n, Color def, const std::string& doc) {
  return with_default(make(n, ParamType::Color, doc), rgb(def));
}
ParamDecl color(const std::string& n, const std::string& doc) { return make(n, ParamType::Color, doc); }
ParamDecl vec2(const std::string& n, Vec2f def, const std::string& doc) {
  return with_default(make(n, ParamType::Vec2, doc), std::vector<double>{def.x, def.y});
}
ParamDecl vec3(const std::string& n, Vec3f def, const std::string& doc) {
  return with_default(make(n, ParamType::Vec3, doc), rgb(def));
}
ParamDecl vec3(const std::string& n, const std::string& doc) { return make(n, ParamType::Vec3, doc); }
ParamDecl floats(const std::string& n, const std::string& doc) { return make(n, ParamType::Floats, doc); }
ParamDecl matrix4(const std::string& n, const std::string& doc) {
  ParamDecl d = make(n, ParamType::Matrix4, doc);
  d.size = 16;
  return d;
}
ParamDecl texture(const std::string& n, const std::string& doc) { return make(n, ParamType::Texture, doc); }
ParamDecl color_texture(const std::string& n, Color def, const std::string& doc) {
  return with_default(make(n, ParamType::ColorTexture, doc), rgb(def));
}
ParamDecl float_texture(const std::string& n, double def, const std::string& doc) {
  return with_default(make(n, ParamType::FloatTexture, doc), def);
}
ParamDecl material(const std::string& n, const std::string& doc) {
  ParamDecl d = make(n, ParamType::Material, doc);
  d.required = true;
  return d;
}
}  // namespace param

const ParamDecl* PluginInfo::find(const std::string& n) const {
  for (const auto& p : params)
    if (p.name == n) return &p;
  for (const auto& p : params)
    if (std::find(p.aliases.begin(), p.aliases.end(), n) != p.aliases.end()) return &p;
  return nullptr;
}

// ---------------------------------------------------------------------------------------
// Checking given values against a declaration

namespace {

std::string quoted_list(const std::vector<std::string>& keys, const char* sep) {
  std::string out;
  for (size_t i = 0; i < keys.size(); ++i) out += (i ? sep : "") + ("'" + keys[i] + "'");
  return out;
}

const char* expected_text(const ParamDecl& d) {
  switch (d.type) {
    case ParamType::Bool: return "true or false";
    case ParamType::Int: return "an integer";
    case ParamType::Float: return "a number";
    case ParamType::String: return "a string";
    case ParamType::Path: return "a file path (a string)";
    case ParamType::Color: return "a number or a list of 3 numbers";
    case ParamType::Vec2: return "a number or a list of 2 numbers";
    case ParamType::Vec3: return "a number or a list of 3 numbers";
    case ParamType::Floats: return "a list of numbers";
    case ParamType::Matrix4: return "a list of 16 numbers (a row-major 4x4 matrix)";
    case ParamType::Texture: return "a texture reference";
    case ParamType::ColorTexture: return "a colour (a number or a list of 3 numbers) or a texture reference";
    case ParamType::FloatTexture: return "a number or a texture reference";
    case ParamType::Material: return "a material id (an integer)";
  }
  return "a value";
}

[[noreturn]] void bad_type(const ParamDecl& d) {
  throw Error("parameter '" + d.name + "': expected " + expected_text(d));
}

void check_number(const ParamDecl& d, double v, bool component) {
  if (!std::isfinite(v)) throw Error("parameter '" + d.name + "': value is not finite");
  if (!d.in_range(v)) {
    std::string r = d.range_text();
    bool interval = r[0] == '[' || r[0] == '(';
    throw Error("parameter '" + d.name + "': " + (component ? "components " : "") +
                (interval ? "must lie in " : "must be ") + r + ", got " + format_number(v));
  }
}

void check_numbers(const ParamDecl& d, const ParamSet::Value& v, size_t size, bool allow_scalar) {
  if (auto x = std::get_if<double>(&v)) {
    if (!allow_scalar) bad_type(d);
    check_number(d, *x, size > 1);
  } else if (auto i = std::get_if<int64_t>(&v)) {
    if (!allow_scalar) bad_type(d);
    check_number(d, double(*i), size > 1);
  } else if (auto l = std::get_if<std::vector<double>>(&v)) {
    if (size > 0 && l->size() != size) bad_type(d);
    for (double c : *l) check_number(d, c, true);
  } else {
    bad_type(d);
  }
}

void check_value(const ParamDecl& d, const ParamSet::Value& v) {
  switch (d.type) {
    case ParamType::Bool:
      if (!std::holds_alternative<bool>(v)) bad_type(d);
      return;
    case ParamType::Int:
      if (auto i = std::get_if<int64_t>(&v)) check_number(d, double(*i), false);
      else bad_type(d);
      return;
    case ParamType::Float:
      check_numbers(d, v, 1, true);
      if (std::holds_alternative<std::vector<double>>(v)) bad_type(d);
      return;
    case ParamType::String:
    case ParamType::Path: {
      auto s = std::get_if<std::string>(&v);
      if (!s) bad_type(d);
      if (!d.choices.empty() && std::find(d.choices.begin(), d.choices.end(), *s) == d.choices.end()) {
        std::string guess = closest_match(*s, d.choices), list;
        for (size_t i = 0; i < d.choices.size(); ++i) list += (i ? ", " : "") + d.choices[i];
        throw Error("parameter '" + d.name + "': unknown value '" + *s + "'" +
                    (guess.empty() ? "" : " (did you mean '" + guess + "'?)") + "; allowed: " + list);
      }
      if (d.type == ParamType::Path && s->empty()) throw Error("parameter '" + d.name + "': empty file path");
      return;
    }
    case ParamType::Color:
    case ParamType::Vec3: check_numbers(d, v, 3, true); return;
    case ParamType::Vec2: check_numbers(d, v, 2, true); return;
    case ParamType::Floats: check_numbers(d, v, d.size, true); return;
    case ParamType::Matrix4: check_numbers(d, v, 16, false); return;
    case ParamType::Texture:
      if (!std::holds_alternative<TextureRef>(v)) bad_type(d);
      return;
    case ParamType::ColorTexture:
      if (!std::holds_alternative<TextureRef>(v)) check_numbers(d, v, 3, true);
      return;
    case ParamType::FloatTexture:
      if (!std::holds_alternative<TextureRef>(v)) {
        check_numbers(d, v, 1, true);
        if (std::holds_alternative<std::vector<double>>(v)) bad_type(d);
      }
      return;
    case ParamType::Material:
      // (the plugin reports ids that do not exist, negative ones included)
      if (!std::holds_alternative<int64_t>(v)) bad_type(d);
      return;
  }
}

}  // namespace

void check_param_value(const ParamDecl& decl, const ParamSet::Value& value) { check_value(decl, value); }

Params::Params(const PluginInfo& info, const ParamSet& given) : m_info(&info) {
  std::vector<std::string> names;
  for (const auto& p : info.params) names.push_back(p.name);
  for (const auto& [key, v] : given.values()) {
    const ParamDecl* d = info.find(key);
    if (!d) {
      std::string msg = info.label() + ": unknown parameter '" + key + "'";
      std::vector<std::string> candidates = names;
      for (const auto& p : info.params) candidates.insert(candidates.end(), p.aliases.begin(), p.aliases.end());
      std::string guess = closest_match(key, candidates);
      if (!guess.empty()) msg += " (did you mean '" + guess + "'?)";
      msg += "; accepted parameters: ";
      for (size_t i = 0; i < names.size(); ++i) msg += (i ? ", " : "") + names[i];
      if (names.empty()) msg += "none";
      throw Error(msg);
    }
    if (m_set.has(d->name))
      throw Error("parameter '" + d->name + "' is given twice (as '" + key + "' and as an alias)");
    check_value(*d, v);
    m_set.set(d->name, v);
  }
  for (const auto& p : info.params)
    if (p.required && !m_set.has(p.name))
      throw Error("parameter '" + p.name + "' is required (" + p.doc + ")");
  auto first_given = [&](const std::vector<std::string>& keys) -> std::string {
    for (const auto& k : keys)
      if (m_set.has(k)) return k;
    return "";
  };
  for (const auto& [a, b] : info.exclusive) {
    std::string ka = first_given(a), kb = first_given(b);
    if (!ka.empty() && !kb.empty())
      throw Error("parameters '" + ka + "' and '" + kb + "' cannot be combined: give " + quoted_list(a, "/") +
                  " or " + quoted_list(b, "/"));
  }
  for (const auto& [k, others] : info.requires)
    if (m_set.has(k))
      for (const auto& o : others)
        if (!m_set.has(o)) throw Error("parameter '" + k + "' requires '" + o + "' to be given as well");
  for (const auto& group : info.one_of) {
    std::vector<std::string> present;
    for (const auto& k : group)
      if (m_set.has(k)) present.push_back(k);
    if (present.empty()) throw Error("missing parameter: give exactly one of " + quoted_list(group, " or "));
    if (present.size() > 1)
      throw Error("parameters '" + present[0] + "' and '" + present[1] + "' cannot be combined: give exactly one of " +
                  quoted_list(group, " or "));
  }
}

bool Params::has(const std::string& name) const {
  decl(name, {});
  return m_set.has(name);
}

const ParamDecl& Params::decl(const std::string& name, std::initializer_list<ParamType> types) const {
  const ParamDecl* d = nullptr;
  for (const auto& p : m_info->params)
    if (p.name == name) d = &p;
  if (!d) throw Error(m_info->label() + ": reads undeclared parameter '" + name + "' (a bug of the plugin)");
  if (types.size() && std::find(types.begin(), types.end(), d->type) == types.end())
    throw Error(m_info->label() + ": reads parameter '" + name + "' as another type than declared (a bug)");
  return *d;
}

void Params::need_value(const ParamDecl& d) const {
  if (!d.has_default && !m_set.has(d.name))
    throw Error("parameter '" + d.name + "' is required" + (d.default_doc.empty() ? "" : " (" + d.default_doc + ")"));
}

namespace {
double default_double(const ParamDecl& d) {
  if (auto x = std::get_if<double>(&d.default_value)) return *x;
  if (auto i = std::get_if<int64_t>(&d.default_value)) return double(*i);
  return 0.0;
}
Vec3f default_vec3(const ParamDecl& d) {
  if (auto l = std::get_if<std::vector<double>>(&d.default_value); l && l->size() == 3)
    return Vec3f(float((*l)[0]), float((*l)[1]), float((*l)[2]));
  return Vec3f(float(default_double(d)));
}
}  // namespace

float Params::get_float(const std::string& name) const {
  const ParamDecl& d = decl(name, {ParamType::Float, ParamType::FloatTexture});
  need_value(d);
  return m_set.get_float(name, float(default_double(d)));
}

float Params::get_float_or(const std::string& name, float def) const {
  decl(name, {ParamType::Float, ParamType::FloatTexture});
  return m_set.get_float(name, def);
}

int64_t Params::get_int(const std::string& name) const {
  const ParamDecl& d = decl(name, {ParamType::Int, ParamType::Material});
  need_value(d);
  int64_t def = 0;
  if (auto i = std::get_if<int64_t>(&d.default_value)) def = *i;
  return m_set.get_int(name, def);
}

bool Params::get_bool(const std::string& name) const {
  const ParamDecl& d = decl(name, {ParamType::Bool});
  need_value(d);
  bool def = false;
  if (auto b = std::get_if<bool>(&d.default_value)) def = *b;
  return m_set.get_bool(name, def);
}

std::string Params::get_string(const std::string& name) const {
  const ParamDecl& d = decl(name, {ParamType::String, ParamType::Path});
  need_value(d);
  std::string def;
  if (auto s = std::get_if<std::string>(&d.default_value)) def = *s;
  return m_set.get_string(name, def);
}

Color Params::get_color(const std::string& name) const {
  const ParamDecl& d = decl(name, {ParamType::Color, ParamType::ColorTexture});
  need_value(d);
  return m_set.get_color(name, default_vec3(d));
}

Vec3f Params::get_vec3(const std::string& name) const {
  const ParamDecl& d = decl(name, {ParamType::Vec3});
  need_value(d);
  return m_set.get_vec3(name, default_vec3(d));
}

Vec2f Params::get_vec2(const std::string& name) const {
  const ParamDecl& d = decl(name, {ParamType::Vec2});
  need_value(d);
  Vec2f def(0.f, 0.f);
  if (auto l = std::get_if<std::vector<double>>(&d.default_value); l && l->size() == 2)
    def = Vec2f(float((*l)[0]), float((*l)[1]));
  return m_set.get_vec2(name, def);
}

std::vector<float> Params::get_floats(const std::string& name) const {
  const ParamDecl& d = decl(name, {ParamType::Floats, ParamType::Matrix4});
  need_value(d);
  if (!m_set.has(name)) {
    std::vector<float> out;
    if (auto l = std::get_if<std::vector<double>>(&d.default_value))
      for (double x : *l) out.push_back(float(x));
    return out;
  }
  return m_set.get_floats(name);
}

bool Params::get_texture(const std::string& name, TextureRef* out) const {
  decl(name, {ParamType::Texture, ParamType::ColorTexture, ParamType::FloatTexture});
  return m_set.get_texture(name, out);
}

void Params::check_all_read() const {
  for (const auto& kv : m_set.values())
    if (!m_set.queried(kv.first))
      throw Error(m_info->label() + ": parameter '" + kv.first + "' is accepted but was not read (a bug of the plugin)");
}

// ---------------------------------------------------------------------------------------
// Registry

Registry& Registry::instance() {
  static Registry r;
  return r;
}

bool Registry::add_entry(PluginInfo info, void (*factory)(), const char* file) {
  std::string f = file ? file : "";
  // Keep the path from the source root's "cpp/" on (the build's absolute path is noise).
  size_t pos = f.rfind("cpp/");
  info.file = pos == std::string::npos ? f : f.substr(pos);
  auto key = std::make_pair(info.kind, info.name);
  if (m_entries.count(key)) {
    std::fprintf(stderr, "synthgen: plugin %s registered twice\n", info.label().c_str());
    std::abort();
  }
  for (const auto& p : info.params) {
    if (p.type == ParamType::String && p.has_default && !p.choices.empty()) {
      const auto& def = std::get<std::string>(p.default_value);
      if (std::find(p.choices.begin(), p.choices.end(), def) == p.choices.end()) {
        std::fprintf(stderr, "synthgen: %s: default of '%s' is not one of its choices\n", info.label().c_str(),
                     p.name.c_str());
        std::abort();
      }
    }
  }
  std::lock_guard<std::mutex> lock(m_mutex);
  m_entries.emplace(key, Entry{std::move(info), factory});
  return true;
}

void Registry::add_runtime_entry(PluginInfo info, void (*factory)()) {
  std::lock_guard<std::mutex> lock(m_mutex);
  auto key = std::make_pair(info.kind, info.name);
  auto it = m_entries.find(key);
  if (it != m_entries.end()) {
    if (!it->second.runtime)
      throw Error(info.file + ": " + info.label() + " has the name of a built-in " + info.kind + " (" +
                  it->second.info.file + "); rename it");
    m_replaced.push_back(m_entries.extract(it));
  }
  m_entries.emplace(key, Entry{std::move(info), factory, true});
}

bool Registry::is_runtime(const std::string& kind, const std::string& name) const {
  const Entry* e = find_entry(kind, name);
  return e && e->runtime;
}

const Registry::Entry* Registry::find_entry(const std::string& kind, const std::string& name) const {
  std::lock_guard<std::mutex> lock(m_mutex);
  auto it = m_entries.find({kind, name});
  return it == m_entries.end() ? nullptr : &it->second;
}

const PluginInfo* Registry::find(const std::string& kind, const std::string& name) const {
  const Entry* e = find_entry(kind, name);
  return e ? &e->info : nullptr;
}

std::vector<std::string> Registry::names(const std::string& kind) const {
  std::lock_guard<std::mutex> lock(m_mutex);
  std::vector<std::string> out;
  for (const auto& kv : m_entries)
    if (kv.first.first == kind) out.push_back(kv.first.second);
  return out;
}

std::vector<std::string> Registry::kinds() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  std::set<std::string> k;
  for (const auto& kv : m_entries) k.insert(kv.first.first);
  return {k.begin(), k.end()};
}

const PluginInfo& Registry::info(const std::string& kind, const std::string& name) const {
  if (const PluginInfo* i = find(kind, name)) return *i;
  std::vector<std::string> keys = names(kind);
  if (keys.empty()) throw Error("unknown plugin kind '" + kind + "'");
  std::string guess = closest_match(name, keys), list;
  for (size_t i = 0; i < keys.size(); ++i) list += (i ? ", " : "") + keys[i];
  throw Error("unknown " + kind + " type '" + name + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
              "; known types: " + list + (kind == "light" ? " (area lights come from emissive materials)" : ""));
}

void Registry::run(const std::string& kind, const std::string& name, const ParamSet& params,
                   const std::string& context, const std::function<void(const Entry&, const Params&)>& call) const {
  try {
    const PluginInfo& i = info(kind, name);
    const Entry* e = find_entry(kind, name);
    Params p(i, params);
    call(*e, p);
    p.check_all_read();
  } catch (const FileError& e) {
    throw e.with_context(context);
  } catch (const Error& e) {
    throw Error(context + ": " + e.what());
  }
}

Params check_params(const std::string& kind, const std::string& name, const ParamSet& params,
                    const std::string& context) {
  try {
    return Params(Registry::instance().info(kind, name), params);
  } catch (const Error& e) {
    throw Error(context + ": " + e.what());
  }
}

}  // namespace sg
