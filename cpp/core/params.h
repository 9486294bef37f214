// Typed parameter values for plugins created by name (materials, lights, textures, ...).
//
// A ParamSet is what a caller gives (a map of typed values). Plugins do not read it
// directly: the registry (core/plugin.h) checks it against the plugin's declaration and
// hands the factory a Params view with the declared defaults. The getters record which
// keys were read (`queried`), so a given key that a plugin ignores is caught.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "core/math.h"

namespace sg {

/// Reference to a texture in the scene's texture library.
struct TextureRef {
  uint32_t id = 0;
};

class ParamSet {
 public:
  using Value = std::variant<bool, int64_t, double, std::string, std::vector<double>, TextureRef>;

  void set(const std::string& name, Value v) { m_values[name] = std::move(v); }
  bool has(const std::string& name) const;
  const std::map<std::string, Value>& values() const { return m_values; }

  float get_float(const std::string& name, float def) const;
  int64_t get_int(const std::string& name, int64_t def) const;
  bool get_bool(const std::string& name, bool def) const;
  std::string get_string(const std::string& name, const std::string& def) const;
  /// Accepts a scalar (grey) or a list of three numbers.
  Color get_color(const std::string& name, const Color& def) const;
  Vec3f get_vec3(const std::string& name, const Vec3f& def) const;
  /// Accepts a scalar (both components) or a list of two numbers.
  Vec2f get_vec2(const std::string& name, const Vec2f& def) const;
  /// A list of numbers (a single number is a list of one); throws when absent.
  std::vector<float> get_floats(const std::string& name) const;
  /// Returns true and sets `out` when the parameter is a texture reference.
  bool get_texture(const std::string& name, TextureRef* out) const;

  /// True when a getter asked for `name`.
  bool queried(const std::string& name) const { return m_queried.count(name) != 0; }

 private:
  const Value* lookup(const std::string& name) const;
  [[noreturn]] void type_error(const std::string& name, const char* expected) const;

  std::map<std::string, Value> m_values;
  mutable std::set<std::string> m_queried;
};

/// Levenshtein edit distance (used for "did you mean" suggestions).
size_t edit_distance(const std::string& a, const std::string& b);
/// Closest candidate within a small edit distance, or "" when none is close.
std::string closest_match(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace sg
