#include "ext/extension.h"

#include <dlfcn.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>

#include "core/noise.h"
#include "texture/texture.h"

namespace sg {

std::shared_ptr<Texture> create_extension_texture(const Params& params, const PluginContext& ctx);
std::shared_ptr<ExtensionShape> create_extension_shape(const Params& params, const PluginContext& ctx);

namespace {

struct Loaded {
  std::mutex mutex;
  std::vector<ExtensionLibrary> libraries;
  std::map<std::string, void*> handles;  // library path -> dlopen handle (never closed)
  std::map<std::string, std::pair<const sg_ext_texture*, std::string>> textures;  // name -> decl, source
  std::map<std::string, std::pair<const sg_ext_shape*, std::string>> shapes;
};

Loaded& loaded() {
  static Loaded l;
  return l;
}

bool valid_name(const char* s) {
  if (!s || !std::islower(static_cast<unsigned char>(s[0]))) return false;
  for (const char* c = s; *c; ++c)
    if (!(std::islower(static_cast<unsigned char>(*c)) || std::isdigit(static_cast<unsigned char>(*c)) || *c == '_'))
      return false;
  return std::char_traits<char>::length(s) <= 64;
}

const char* type_name(int t) {
  switch (t) {
    case SG_EXT_FLOAT: return "SG_EXT_FLOAT";
    case SG_EXT_INT: return "SG_EXT_INT";
    case SG_EXT_COLOR: return "SG_EXT_COLOR";
    case SG_EXT_VEC3: return "SG_EXT_VEC3";
    case SG_EXT_FLOAT_TEXTURE: return "SG_EXT_FLOAT_TEXTURE";
    case SG_EXT_COLOR_TEXTURE: return "SG_EXT_COLOR_TEXTURE";
    default: return "?";
  }
}

int components(int type) {
  return (type == SG_EXT_COLOR || type == SG_EXT_VEC3 || type == SG_EXT_COLOR_TEXTURE) ? 3 : 1;
}

/// The PluginInfo of an extension's parameter list; throws naming what is wrong.
void declare_params(PluginInfo& info, const sg_ext_param* params, int count, bool textures_allowed,
                    const std::string& where) {
  if (count < 0 || count > 64) throw Error(where + ": param_count " + std::to_string(count) + " is not in [0, 64]");
  if (count > 0 && !params) throw Error(where + ": params is null but param_count is " + std::to_string(count));
  std::set<std::string> seen;
  for (int i = 0; i < count; ++i) {
    const sg_ext_param& q = params[i];
    std::string pw = where + ": parameter " + std::to_string(i);
    if (!valid_name(q.name)) throw Error(pw + ": name must match [a-z][a-z0-9_]* (at most 64 characters)");
    pw = where + ": parameter '" + std::string(q.name) + "'";
    if (!seen.insert(q.name).second) throw Error(pw + " is declared twice");
    if (q.type < SG_EXT_FLOAT || q.type > SG_EXT_COLOR_TEXTURE)
      throw Error(pw + ": unknown type " + std::to_string(q.type) + " (one of SG_EXT_FLOAT .. SG_EXT_COLOR_TEXTURE)");
    if (!textures_allowed && q.type >= SG_EXT_FLOAT_TEXTURE)
      throw Error(pw + ": a shape's parameters are numbers (" + type_name(q.type) + " is not allowed)");
    bool ranged = q.lo != 0.f || q.hi != 0.f;
    if (ranged && !(q.lo <= q.hi)) throw Error(pw + ": range [lo, hi] is empty or not a number");
    int n = components(q.type);
    for (int c = 0; c < n; ++c) {
      if (!std::isfinite(q.def[c])) throw Error(pw + ": default is not finite");
      if (ranged && (q.def[c] < q.lo || q.def[c] > q.hi))
        throw Error(pw + ": default " + format_number(q.def[c]) + " is outside its range [" + format_number(q.lo) +
                    ", " + format_number(q.hi) + "]");
    }
    if (q.type == SG_EXT_INT && (q.def[0] != std::floor(q.def[0]) || std::fabs(q.def[0]) > 16777216.f))
      throw Error(pw + ": an SG_EXT_INT default must be an integer of magnitude <= 2^24");
    std::string doc = q.doc ? q.doc : "";
    // The float limits as the C file wrote them (1e-3f as 0.001, not 0.0010000000474974513).
    auto as_written = [](float v) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.7g", double(v));
      return std::strtod(buf, nullptr);
    };
    const double d0 = as_written(q.def[0]);
    ParamDecl d;
    switch (q.type) {
      case SG_EXT_FLOAT: d = param::real(q.name, d0, doc); break;
      case SG_EXT_INT: d = param::integer(q.name, int64_t(q.def[0]), doc); break;
      case SG_EXT_COLOR: d = param::color(q.name, Color(q.def[0], q.def[1], q.def[2]), doc); break;
      case SG_EXT_VEC3: d = param::vec3(q.name, Vec3f(q.def[0], q.def[1], q.def[2]), doc); break;
      case SG_EXT_FLOAT_TEXTURE: d = param::float_texture(q.name, d0, doc); break;
      default: d = param::color_texture(q.name, Color(q.def[0], q.def[1], q.def[2]), doc); break;
    }
    if (ranged) d.in(as_written(q.lo), as_written(q.hi));
    if (q.type == SG_EXT_INT) {
      d.lo = std::max(d.lo, -16777216.0);
      d.hi = std::min(d.hi, 16777216.0);
    }
    info.add(d);
  }
}

}  // namespace

ExtensionLibrary load_extension_library(const std::string& library_path, const std::string& source) {
  Loaded& l = loaded();
  std::lock_guard<std::mutex> lock(l.mutex);
  for (const ExtensionLibrary& lib : l.libraries)
    if (lib.library == library_path) return lib;
  // NOTE: RTLD_LOCAL keeps the library's symbols out of the global scope (two extensions may
  // define the same static helper names); RTLD_NOW reports unresolved symbols at load time.
  void* handle = dlopen(library_path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) {
    const char* e = dlerror();
    throw Error(source + ": the compiled extension does not load: " + (e ? e : "unknown error"));
  }
  auto entry = reinterpret_cast<sg_ext_entry_fn>(dlsym(handle, SG_EXT_ENTRY));
  if (!entry) {
    dlclose(handle);
    throw Error(source + ": no function '" SG_EXT_ENTRY "' (an extension defines SG_EXT_EXPORT const "
                "sg_ext_library* " SG_EXT_ENTRY "(void); see synthgen_ext.h)");
  }
  const sg_ext_library* lib = entry();
  if (!lib) {
    dlclose(handle);
    throw Error(source + ": " SG_EXT_ENTRY "() returned null");
  }
  if (lib->abi_version != SG_EXT_ABI_VERSION) {
    const uint32_t version = lib->abi_version;  // read before the library is unloaded
    dlclose(handle);
    throw Error(source + ": built for extension ABI version " + std::to_string(version) +
                "; this synthgen has version " + std::to_string(SG_EXT_ABI_VERSION) +
                " (set abi_version to SG_EXT_ABI_VERSION and follow synthgen_ext.h)");
  }
  auto check_count = [&](int n, const void* p, const char* what) {
    if (n < 0 || n > 1024 || (n > 0 && !p)) {
      dlclose(handle);
      throw Error(source + ": " + what + " count " + std::to_string(n) + " is invalid (or its array is null)");
    }
  };
  check_count(lib->texture_count, lib->textures, "texture");
  check_count(lib->shape_count, lib->shapes, "shape");
  if (lib->texture_count + lib->shape_count == 0) {
    dlclose(handle);
    throw Error(source + ": the extension declares no textures and no shapes");
  }
  ExtensionLibrary out{library_path, source, {}, {}};
  std::vector<PluginInfo> tex_infos, shape_infos;
  std::set<std::string> names;
  try {
    for (int i = 0; i < lib->texture_count; ++i) {
      const sg_ext_texture& t = lib->textures[i];
      if (!valid_name(t.name))
        throw Error(source + ": texture " + std::to_string(i) + ": name must match [a-z][a-z0-9_]*");
      std::string where = source + ": texture '" + t.name + "'";
      if (!names.insert(t.name).second) throw Error(where + " is declared twice");
      if (t.channels != 1 && t.channels != 3)
        throw Error(where + ": channels must be 1 or 3 (is " + std::to_string(t.channels) + ")");
      if (!t.eval) throw Error(where + ": eval is null");
      PluginInfo info("texture", t.name, std::string(t.doc ? t.doc : "") + " (extension: " + source + ")");
      info.file = source;
      declare_params(info, t.params, t.param_count, true, where);
      tex_infos.push_back(std::move(info));
    }
    for (int i = 0; i < lib->shape_count; ++i) {
      const sg_ext_shape& s = lib->shapes[i];
      if (!valid_name(s.name)) throw Error(source + ": shape " + std::to_string(i) + ": name must match [a-z][a-z0-9_]*");
      std::string where = source + ": shape '" + s.name + "'";
      if (!names.insert(std::string("shape:") + s.name).second) throw Error(where + " is declared twice");
      if (!s.bounds || !s.intersect) throw Error(where + ": bounds and intersect must both be given");
      PluginInfo info("shape", s.name, std::string(s.doc ? s.doc : "") + " (extension: " + source + ")");
      info.file = source;
      declare_params(info, s.params, s.param_count, false, where);
      shape_infos.push_back(std::move(info));
    }
    Registry& r = Registry::instance();
    for (const PluginInfo& info : tex_infos)
      if (r.find("texture", info.name) && !r.is_runtime("texture", info.name))
        throw Error(source + ": texture '" + info.name + "' has the name of a built-in texture; rename it");
  } catch (...) {
    dlclose(handle);
    throw;
  }
  Registry& r = Registry::instance();
  for (int i = 0; i < lib->texture_count; ++i) {
    l.textures[lib->textures[i].name] = {&lib->textures[i], source};
    r.add_runtime<Texture>(std::move(tex_infos[size_t(i)]), create_extension_texture);
    out.textures.push_back(lib->textures[i].name);
  }
  for (int i = 0; i < lib->shape_count; ++i) {
    l.shapes[lib->shapes[i].name] = {&lib->shapes[i], source};
    r.add_runtime<ExtensionShape>(std::move(shape_infos[size_t(i)]), create_extension_shape);
    out.shapes.push_back(lib->shapes[i].name);
  }
  l.handles[library_path] = handle;
  l.libraries.push_back(out);
  return out;
}

std::vector<ExtensionLibrary> loaded_extension_libraries() {
  Loaded& l = loaded();
  std::lock_guard<std::mutex> lock(l.mutex);
  return l.libraries;
}

namespace {

/// The declaration registered under `name` in `table` (and its source); throws naming `what`.
template <class Decl>
const Decl& find_declaration(const std::map<std::string, std::pair<const Decl*, std::string>>& table,
                             const std::string& name, const char* what, std::string* source) {
  auto it = table.find(name);
  if (it == table.end()) throw Error(std::string("no extension ") + what + " '" + name + "' is loaded");
  if (source) *source = it->second.second;
  return *it->second.first;
}

}  // namespace

const sg_ext_texture& extension_texture(const std::string& name, std::string* source) {
  Loaded& l = loaded();
  std::lock_guard<std::mutex> lock(l.mutex);
  return find_declaration(l.textures, name, "texture", source);
}

const sg_ext_shape& extension_shape(const std::string& name, std::string* source) {
  Loaded& l = loaded();
  std::lock_guard<std::mutex> lock(l.mutex);
  return find_declaration(l.shapes, name, "shape", source);
}

ExtensionArgs extension_args(const sg_ext_param* params, int count, const Params& p, const TextureLookup& textures) {
  ExtensionArgs a;
  for (int i = 0; i < count; ++i) {
    const sg_ext_param& q = params[i];
    size_t offset = a.block.size();
    switch (q.type) {
      case SG_EXT_FLOAT: a.block.push_back(p.get_float(q.name)); break;
      case SG_EXT_INT: a.block.push_back(float(p.get_int(q.name))); break;
      case SG_EXT_COLOR: {
        Color c = p.get_color(q.name);
        a.block.insert(a.block.end(), {c.x, c.y, c.z});
        break;
      }
      case SG_EXT_VEC3: {
        Vec3f v = p.get_vec3(q.name);
        a.block.insert(a.block.end(), {v.x, v.y, v.z});
        break;
      }
      default: {
        int n = components(q.type);
        std::shared_ptr<Texture> t = texture_param(p, q.name, textures);
        if (!t) t = make_constant_texture(n == 1 ? Color(p.get_float(q.name)) : p.get_color(q.name));
        Color c = t->is_constant() ? t->constant_value() : t->average();
        for (int k = 0; k < n; ++k) a.block.push_back(c[k]);
        if (!t->is_constant()) a.inputs.push_back({offset, n, t});
      }
    }
  }
  return a;
}

// ---------------------------------------------------------------------------------------
// Host

namespace {

const NoiseBasis* basis(const sg_ext_noise* b) { return reinterpret_cast<const NoiseBasis*>(b); }

float host_perlin(const sg_ext_noise* b, const float p[3]) {
  return b ? basis(b)->perlin(Vec3f(p[0], p[1], p[2])) : 0.f;
}

FractalParams fractal(int octaves, float lacunarity, float H) {
  FractalParams f;
  f.octaves = std::max(1, std::min(Fractal::k_max_octaves, octaves));
  f.lacunarity = lacunarity;
  f.H = H;
  return f;
}

float host_fbm(const sg_ext_noise* b, const float p[3], int octaves, float lacunarity, float H, float footprint,
               float grad[3]) {
  if (!b) return 0.f;
  Vec3f q(p[0], p[1], p[2]);
  if (!grad) return fbm(*basis(b), NoiseKind::Perlin, q, fractal(octaves, lacunarity, H), footprint);
  Vec3f g;
  float v = fbm_grad(*basis(b), q, fractal(octaves, lacunarity, H), footprint, &g);
  grad[0] = g.x; grad[1] = g.y; grad[2] = g.z;
  return v;
}

float host_turbulence(const sg_ext_noise* b, const float p[3], int octaves, float lacunarity, float H,
                      float footprint, float grad[3]) {
  if (!b) return 0.f;
  Vec3f q(p[0], p[1], p[2]);
  if (!grad) return turbulence(*basis(b), NoiseKind::Perlin, q, fractal(octaves, lacunarity, H), footprint);
  Vec3f g;
  float v = turbulence_grad(*basis(b), q, fractal(octaves, lacunarity, H), footprint, &g);
  grad[0] = g.x; grad[1] = g.y; grad[2] = g.z;
  return v;
}

float host_cellular(const sg_ext_noise* b, const float p[3], float jitter, float out[3]) {
  if (!b) {
    out[0] = out[1] = out[2] = 0.f;
    return 0.f;
  }
  CellularResult r = cellular(*basis(b), Vec3f(p[0], p[1], p[2]), std::max(0.f, std::min(1.f, jitter)), true);
  out[0] = r.f1; out[1] = r.f2; out[2] = r.edge;
  return float(r.cell_hash >> 8) * 0x1p-24f;
}

}  // namespace

ExtensionHost::ExtensionHost(std::string what) : m_what(std::move(what)) {
  for (auto& b : m_bases) b.store(nullptr, std::memory_order_relaxed);
  m_host.abi_version = SG_EXT_ABI_VERSION;
  m_host.self = this;
  m_host.noise = &ExtensionHost::noise;
  m_host.perlin = host_perlin;
  m_host.fbm = host_fbm;
  m_host.turbulence = host_turbulence;
  m_host.cellular = host_cellular;
}

ExtensionHost::~ExtensionHost() {
  for (auto& b : m_bases) delete static_cast<const NoiseBasis*>(b.load(std::memory_order_relaxed));
}

const sg_ext_noise* ExtensionHost::noise(const sg_ext_host* host, uint64_t seed) {
  auto* self = static_cast<ExtensionHost*>(host->self);
  // NOTE: lock-free reads of published slots: a slot's seed is written before its basis is
  // stored with release order, and readers load the basis with acquire order first.
  int i = 0;
  for (; i < k_max_seeds; ++i) {
    const void* b = self->m_bases[i].load(std::memory_order_acquire);
    if (!b) break;
    if (self->m_seeds[i] == seed) return static_cast<const sg_ext_noise*>(b);
  }
  std::lock_guard<std::mutex> lock(self->m_mutex);
  for (i = 0; i < k_max_seeds; ++i) {
    const void* b = self->m_bases[i].load(std::memory_order_acquire);
    if (!b) break;
    if (self->m_seeds[i] == seed) return static_cast<const sg_ext_noise*>(b);
  }
  if (i == k_max_seeds) {
    if (!self->m_failed.load(std::memory_order_relaxed)) {
      self->m_failure = "more than " + std::to_string(k_max_seeds) + " noise seeds asked for (host->noise)";
      self->m_failed.store(true, std::memory_order_release);
    }
    return nullptr;
  }
  const NoiseBasis* b = new NoiseBasis(seed);
  self->m_seeds[i] = seed;
  self->m_bases[i].store(b, std::memory_order_release);
  return reinterpret_cast<const sg_ext_noise*>(b);
}

void ExtensionHost::fail(const std::string& message) const {
  if (m_failed.load(std::memory_order_acquire)) return;
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_failed.load(std::memory_order_relaxed)) return;
  m_failure = message;
  m_failed.store(true, std::memory_order_release);
}

std::string ExtensionHost::failure() const {
  if (!m_failed.load(std::memory_order_acquire)) return {};
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_what + ": " + m_failure;
}

bool ExtensionHost::check(const float* v, int n, const float p[3]) const {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) {
      if (!m_failed.load(std::memory_order_relaxed))
        fail("returned " + std::string(std::isnan(v[i]) ? "NaN" : "an infinity") + " (channel " + std::to_string(i) +
             ") at world point (" + format_number(p[0]) + ", " + format_number(p[1]) + ", " + format_number(p[2]) + ")");
      return false;
    }
  return true;
}

}  // namespace sg
