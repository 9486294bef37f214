#include "core/params.h"

#include <algorithm>

#include "core/error.h"

namespace sg {

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string closest_match(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_d = std::max<size_t>(2, word.size() / 3) + 1;
  for (const auto& c : candidates) {
    size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

bool ParamSet::has(const std::string& name) const { return m_values.count(name) != 0; }

const ParamSet::Value* ParamSet::lookup(const std::string& name) const {
  m_queried.insert(name);
  auto it = m_values.find(name);
  return it == m_values.end() ? nullptr : &it->second;
}

void ParamSet::type_error(const std::string& name, const char* expected) const {
  throw Error("parameter '" + name + "': expected " + expected);
}

float ParamSet::get_float(const std::string& name, float def) const {
  const Value* v = lookup(name);
  if (!v) return def;
  double d;
  if (auto p = std::get_if<double>(v)) d = *p;
  else if (auto q = std::get_if<int64_t>(v)) d = double(*q);
  else type_error(name, "a number");
  if (!std::isfinite(d)) throw Error("parameter '" + name + "': value is not finite");
  return float(d);
}

int64_t ParamSet::get_int(const std::string& name, int64_t def) const {
  const Value* v = lookup(name);
  if (!v) return def;
  if (auto q = std::get_if<int64_t>(v)) return *q;
  type_error(name, "an integer");
}

bool ParamSet::get_bool(const std::string& name, bool def) const {
  const Value* v = lookup(name);
  if (!v) return def;
  if (auto q = std::get_if<bool>(v)) return *q;
  type_error(name, "true or false");
}

std::string ParamSet::get_string(const std::string& name, const std::string& def) const {
  const Value* v = lookup(name);
  if (!v) return def;
  if (auto q = std::get_if<std::string>(v)) return *q;
  type_error(name, "a string");
}

std::vector<float> ParamSet::get_floats(const std::string& name) const {
  const Value* v = lookup(name);
  if (!v) throw Error("parameter '" + name + "' is missing");
  std::vector<float> out;
  if (auto p = std::get_if<std::vector<double>>(v)) {
    for (double d : *p) out.push_back(float(d));
  } else if (auto d = std::get_if<double>(v)) {
    out.push_back(float(*d));
  } else if (auto n = std::get_if<int64_t>(v)) {
    out.push_back(float(*n));
  } else {
    type_error(name, "a list of numbers");
  }
  for (float f : out)
    if (!std::isfinite(f)) throw Error("parameter '" + name + "': value is not finite");
  return out;
}

Vec3f ParamSet::get_vec3(const std::string& name, const Vec3f& def) const {
  const Value* v = lookup(name);
  if (!v) return def;
  Vec3f r;
  if (auto p = std::get_if<std::vector<double>>(v)) {
    if (p->size() != 3) type_error(name, "a list of 3 numbers");
    r = Vec3f(float((*p)[0]), float((*p)[1]), float((*p)[2]));
  } else if (auto d = std::get_if<double>(v)) {
    r = Vec3f(float(*d));
  } else if (auto i = std::get_if<int64_t>(v)) {
    r = Vec3f(float(*i));
  } else {
    type_error(name, "a number or a list of 3 numbers");
  }
  if (!is_finite(r)) throw Error("parameter '" + name + "': value is not finite");
  return r;
}

Vec2f ParamSet::get_vec2(const std::string& name, const Vec2f& def) const {
  const Value* v = lookup(name);
  if (!v) return def;
  Vec2f r;
  if (auto p = std::get_if<std::vector<double>>(v)) {
    if (p->size() != 2) type_error(name, "a list of 2 numbers");
    r = Vec2f(float((*p)[0]), float((*p)[1]));
  } else if (auto d = std::get_if<double>(v)) {
    r = Vec2f(float(*d), float(*d));
  } else if (auto i = std::get_if<int64_t>(v)) {
    r = Vec2f(float(*i), float(*i));
  } else {
    type_error(name, "a number or a list of 2 numbers");
  }
  if (!std::isfinite(r.x) || !std::isfinite(r.y)) throw Error("parameter '" + name + "': value is not finite");
  return r;
}

Color ParamSet::get_color(const std::string& name, const Color& def) const { return get_vec3(name, def); }

bool ParamSet::get_texture(const std::string& name, TextureRef* out) const {
  const Value* v = lookup(name);
  if (!v) return false;
  if (auto t = std::get_if<TextureRef>(v)) {
    *out = *t;
    return true;
  }
  return false;
}

}  // namespace sg
