// Plugins created by name from typed parameters declared once.
//
// Every plugin (material, texture, light, camera, render settings) declares its
// parameters in its own file: name, type, default, range and a one-line doc (a
// PluginInfo), and registers it with a factory (SG_REGISTER_PLUGIN). The registry then
//   - creates plugins by (kind, name), after checking the given parameters against the
//     declaration: unknown keys (with "did you mean"), types, ranges, allowed values,
//     required keys and the declared combinations (exclusive, requires, one_of);
//   - hands the factory a Params view whose getters return the given value or the
//     declared default, so no default is written twice;
//   - exposes the declarations (plugin_info, through the bindings) from which the YAML
//     schemas of scene files and scenarios and the reference docs are generated.
// A factory only checks what the declaration cannot express (relations between values).
#pragma once

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/params.h"

namespace sg {

class Texture;
class Material;
class ImageCache;

using TextureLookup = std::function<std::shared_ptr<Texture>(uint32_t id)>;
using MaterialLookup = std::function<std::shared_ptr<Material>(uint32_t id)>;

/// What a plugin may look up while it is created: textures and materials by id (for
/// textures and materials built from others) and the scene's image cache.
struct PluginContext {
  TextureLookup textures;
  MaterialLookup materials;
  ImageCache* images = nullptr;  ///< null: image textures decode a private copy
};

enum class ParamType {
  Bool,          ///< true / false
  Int,           ///< integer
  Float,         ///< number
  String,        ///< string (with `choices`: one of them)
  Path,          ///< file path (a string; resolved by the caller)
  Color,         ///< a number (grey) or 3 numbers
  Vec2,          ///< a number (both) or 2 numbers
  Vec3,          ///< a number (all three) or 3 numbers
  Floats,        ///< a list of numbers (`size` > 0: exactly that many)
  Matrix4,       ///< 16 numbers, a row-major 4x4 affine matrix
  Texture,       ///< a texture reference
  ColorTexture,  ///< a colour or a texture reference
  FloatTexture,  ///< a number or a texture reference (its first channel)
  Material,      ///< a material id
};

/// Name of a parameter type as used in plugin_info() ("color_texture", ...).
const char* param_type_name(ParamType t);

/// One declared parameter.
struct ParamDecl {
  std::string name;
  ParamType type = ParamType::Float;
  bool has_default = false;     ///< the value used when the key is absent
  ParamSet::Value default_value;
  bool required = false;        ///< the key must be given
  std::string default_doc;      ///< a default that depends on other values, in words
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
  std::vector<std::string> choices;  ///< allowed strings (empty: any)
  std::vector<std::string> aliases;  ///< other accepted spellings of the key
  size_t size = 0;                   ///< Floats: exact element count (0: any)
  std::string doc;

  /// Range of the number, of each component, or of each element (inclusive).
  ParamDecl& in(double lo_, double hi_) { lo = lo_; hi = hi_; return *this; }
  ParamDecl& at_least(double lo_) { lo = lo_; return *this; }
  ParamDecl& above(double lo_) { lo = lo_; lo_open = true; return *this; }
  ParamDecl& below(double hi_) { hi = hi_; hi_open = true; return *this; }
  ParamDecl& at_most(double hi_) { hi = hi_; return *this; }
  ParamDecl& open_low() { lo_open = true; return *this; }
  ParamDecl& open_high() { hi_open = true; return *this; }
  ParamDecl& alias(const std::string& a) { aliases.push_back(a); return *this; }
  ParamDecl& require() { required = true; return *this; }
  ParamDecl& exact_size(size_t n) { size = n; return *this; }
  /// No fixed default: `text` says what is used when the key is absent.
  ParamDecl& default_is(const std::string& text) { default_doc = text; return *this; }
  bool has_range() const;
  /// The range as text: "[0, 1]", "(0, 1e4]", ">= 0", "> 0", "<= 90", or "".
  std::string range_text() const;
  bool in_range(double v) const;
};

/// Declaration builders: name, default (where the type has one) and doc.
namespace param {
ParamDecl boolean(const std::string& name, bool def, const std::string& doc);
ParamDecl integer(const std::string& name, int64_t def, const std::string& doc);
ParamDecl real(const std::string& name, double def, const std::string& doc);
/// A number without a default (optional: the plugin reads it only when given).
ParamDecl real(const std::string& name, const std::string& doc);
ParamDecl string(const std::string& name, const std::string& def, const std::string& doc);
ParamDecl choice(const std::string& name, const std::string& def, std::vector<std::string> choices,
                 const std::string& doc);
ParamDecl path(const std::string& name, const std::string& doc);
ParamDecl color(const std::string& name, Color def, const std::string& doc);
/// A colour without a default (optional).
ParamDecl color(const std::string& name, const std::string& doc);
ParamDecl vec2(const std::string& name, Vec2f def, const std::string& doc);
ParamDecl vec3(const std::string& name, Vec3f def, const std::string& doc);
ParamDecl vec3(const std::string& name, const std::string& doc);
ParamDecl floats(const std::string& name, const std::string& doc);
ParamDecl matrix4(const std::string& name, const std::string& doc);
ParamDecl texture(const std::string& name, const std::string& doc);
ParamDecl color_texture(const std::string& name, Color def, const std::string& doc);
ParamDecl float_texture(const std::string& name, double def, const std::string& doc);
ParamDecl material(const std::string& name, const std::string& doc);
}  // namespace param

/// A plugin's declaration.
struct PluginInfo {
  std::string kind;  ///< "material", "texture", "light", "camera", "render"
  std::string name;  ///< registry key = file name
  std::string doc;   ///< one paragraph
  std::string file;  ///< source file (set by SG_REGISTER_PLUGIN)
  std::vector<ParamDecl> params;
  /// Keys of `first` cannot be combined with keys of `second`.
  std::vector<std::pair<std::vector<std::string>, std::vector<std::string>>> exclusive;
  /// When `first` is given, every key of `second` must be given too.
  std::vector<std::pair<std::string, std::vector<std::string>>> requires;
  /// Exactly one key of each group must be given.
  std::vector<std::vector<std::string>> one_of;

  PluginInfo() = default;
  PluginInfo(std::string kind_, std::string name_, std::string doc_)
      : kind(std::move(kind_)), name(std::move(name_)), doc(std::move(doc_)) {}
  PluginInfo& add(ParamDecl p) { params.push_back(std::move(p)); return *this; }
  PluginInfo& add(const std::vector<ParamDecl>& ps) {
    params.insert(params.end(), ps.begin(), ps.end());
    return *this;
  }
  PluginInfo& exclusive_of(std::vector<std::string> a, std::vector<std::string> b) {
    exclusive.emplace_back(std::move(a), std::move(b));
    return *this;
  }
  PluginInfo& requires_all(std::string key, std::vector<std::string> others) {
    requires.emplace_back(std::move(key), std::move(others));
    return *this;
  }
  PluginInfo& exactly_one_of(std::vector<std::string> keys) {
    one_of.push_back(std::move(keys));
    return *this;
  }
  /// The declaration of `name` (or of the parameter it is an alias of); null when none.
  const ParamDecl* find(const std::string& name) const;
  /// "material 'diffuse'"
  std::string label() const { return kind + " '" + name + "'"; }
};

/// The parameters a factory reads: given values checked against the declaration, with
/// the declared defaults for absent keys. Aliases are resolved to the declared name.
class Params {
 public:
  /// Checks `given` against `info` (throws sg::Error naming the problem).
  Params(const PluginInfo& info, const ParamSet& given);

  const PluginInfo& info() const { return *m_info; }
  /// True when the key was given (not defaulted).
  bool has(const std::string& name) const;

  // Typed values: the given value or the declared default. Reading a parameter that is
  // neither given nor has a default throws (use has(), or the *_or variants for defaults
  // that depend on other values).
  float get_float(const std::string& name) const;
  float get_float_or(const std::string& name, float def) const;
  int64_t get_int(const std::string& name) const;
  bool get_bool(const std::string& name) const;
  std::string get_string(const std::string& name) const;
  Color get_color(const std::string& name) const;
  Vec2f get_vec2(const std::string& name) const;
  Vec3f get_vec3(const std::string& name) const;
  std::vector<float> get_floats(const std::string& name) const;
  /// True and sets `out` when the parameter was given as a texture reference.
  bool get_texture(const std::string& name, TextureRef* out) const;

  /// Throws naming the first given key the factory did not read (the declaration allows
  /// it but the plugin ignored it: a bug of the plugin, never silently accepted).
  void check_all_read() const;
  /// The given values under their declared names.
  const ParamSet& given() const { return m_set; }

 private:
  /// The declaration of `name`; throws (a bug of the plugin) when it is not declared or
  /// read as another type.
  const ParamDecl& decl(const std::string& name, std::initializer_list<ParamType> types) const;
  /// Throws when `name` is neither given nor has a declared default.
  void need_value(const ParamDecl& d) const;

  const PluginInfo* m_info;
  ParamSet m_set;  ///< given values under their declared names
};

/// Creates a plugin object from checked parameters.
template <class T>
using PluginFactory = std::shared_ptr<T> (*)(const Params& params, const PluginContext& ctx);

/// All plugins, by kind and name.
class Registry {
 public:
  static Registry& instance();

  /// Registers a plugin (at static initialisation, through SG_REGISTER_PLUGIN).
  template <class T>
  bool add(PluginInfo info, PluginFactory<T> factory, const char* file) {
    return add_entry(std::move(info), reinterpret_cast<void (*)()>(factory), file);
  }
  /// Registers a plugin at run time (user extensions, ext/extension.h): `info.file` names its
  /// source. Replaces an earlier run-time plugin of the same kind and name (a recompiled
  /// extension); throws sg::Error when a built-in plugin has the name. Thread-safe; a replaced
  /// declaration stays valid (plugins created from it keep pointing at it).
  template <class T>
  void add_runtime(PluginInfo info, PluginFactory<T> factory) {
    add_runtime_entry(std::move(info), reinterpret_cast<void (*)()>(factory));
  }
  /// True when (kind, name) was registered at run time.
  bool is_runtime(const std::string& kind, const std::string& name) const;

  /// The declaration of plugin `name` of `kind`; throws sg::Error with "did you mean" and
  /// the list of known names when there is none.
  const PluginInfo& info(const std::string& kind, const std::string& name) const;
  const PluginInfo* find(const std::string& kind, const std::string& name) const;
  /// Plugin names of a kind, sorted; kinds, sorted.
  std::vector<std::string> names(const std::string& kind) const;
  std::vector<std::string> kinds() const;

  /// Checks `params` against the declaration and creates the plugin. Errors are prefixed
  /// by `context` ("material 3").
  template <class T>
  std::shared_ptr<T> create(const std::string& kind, const std::string& name, const ParamSet& params,
                            const PluginContext& ctx, const std::string& context) const {
    std::shared_ptr<T> out;
    run(kind, name, params, context, [&](const Entry& e, const Params& p) {
      out = reinterpret_cast<PluginFactory<T>>(e.factory)(p, ctx);
    });
    return out;
  }

 private:
  struct Entry {
    PluginInfo info;
    void (*factory)();
    bool runtime = false;
  };
  bool add_entry(PluginInfo info, void (*factory)(), const char* file);
  void add_runtime_entry(PluginInfo info, void (*factory)());
  void run(const std::string& kind, const std::string& name, const ParamSet& params, const std::string& context,
           const std::function<void(const Entry&, const Params&)>& call) const;
  const Entry* find_entry(const std::string& kind, const std::string& name) const;

  using Entries = std::map<std::pair<std::string, std::string>, Entry>;
  Entries m_entries;
  /// Replaced run-time entries, kept so that references to their declarations stay valid
  /// (map nodes keep their address when extracted).
  std::vector<Entries::node_type> m_replaced;
  /// Guards the entries: run-time plugins are added while other threads may create plugins.
  mutable std::mutex m_mutex;
};

/// Checks `params` against the declaration of (kind, name) without creating anything
/// (for plugins whose product is not a shared object, such as the render settings).
Params check_params(const std::string& kind, const std::string& name, const ParamSet& params,
                    const std::string& context);

/// Checks one value against a declaration (type, range, allowed values); throws sg::Error.
void check_param_value(const ParamDecl& decl, const ParamSet::Value& value);

/// Formats a number as short text ("0.5", "1e+04", "3").
std::string format_number(double v);

}  // namespace sg

#define SG_PLUGIN_CONCAT2(a, b) a##b
#define SG_PLUGIN_CONCAT(a, b) SG_PLUGIN_CONCAT2(a, b)
/// Registers a plugin of product type `Type` (Material, Texture, Light, ...) with its
/// declaration `info_expr` (a PluginInfo) and factory `factory` (a PluginFactory<Type>).
#define SG_REGISTER_PLUGIN(Type, info_expr, factory)                                               \
  namespace {                                                                                      \
  [[maybe_unused]] const bool SG_PLUGIN_CONCAT(sg_registered_, __LINE__) =                         \
      ::sg::Registry::instance().add<Type>((info_expr), (factory), __FILE__);                      \
  }
