// User extensions: procedural textures and geometric primitives written as small C functions
// against the C ABI of synthgen_ext.h (python/synthgen/include), compiled by the caller
// (synthgen.ext: the system C compiler, a cache keyed by source hash) and loaded here.
//
// Loading a library dlopens it, checks its ABI version and declarations, and registers each
// texture as a "texture" plugin and each shape as a "shape" plugin under its own name, with
// the parameters it declares (checked and documented like any plugin's, core/plugin.h).
// After the Hydra Render extension mechanism (Sanzharov 2023): arguments live in a
// parameter block built when the object is created, so changing them never recompiles.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/plugin.h"
#include "geometry/mesh.h"
#include "synthgen_ext.h"

namespace sg {

/// What loading a library registered.
struct ExtensionLibrary {
  std::string library;   ///< the shared object loaded
  std::string source;    ///< the user's file (named in errors and in the plugins' `file`)
  std::vector<std::string> textures, shapes;  ///< plugin names registered
};

/// Loads the compiled extension `library_path` built from `source` and registers its plugins.
/// Loading the same library again registers nothing new; a library of another build replaces
/// earlier run-time plugins of the same names (objects made from them keep the old code; the
/// old library stays loaded). Throws sg::Error naming `source`: a library that does not load,
/// lacks the entry symbol synthgen_extension, was built for another ABI version, or declares
/// something invalid (names, channels, parameter types, ranges, defaults, a built-in's name).
ExtensionLibrary load_extension_library(const std::string& library_path, const std::string& source);
/// Every library loaded in this process, in loading order.
std::vector<ExtensionLibrary> loaded_extension_libraries();

/// The parameter block of an extension object: the given parameters in declaration order,
/// 1 or 3 floats each (synthgen_ext.h), and the texture inputs to evaluate per lookup.
struct ExtensionArgs {
  std::vector<float> block;
  struct Input {
    size_t offset = 0;
    int channels = 1;
    std::shared_ptr<class Texture> texture;
  };
  std::vector<Input> inputs;  ///< texture parameters given as (non-constant) texture references
};
/// Builds the block of a declaration from checked parameters; texture references are resolved
/// through `textures` (null: none allowed).
ExtensionArgs extension_args(const sg_ext_param* params, int count, const Params& p, const TextureLookup& textures);
/// The declaration of plugin (kind, name) loaded from a library, with its source file; throws
/// sg::Error when no extension of that name is loaded.
const sg_ext_texture& extension_texture(const std::string& name, std::string* source = nullptr);
const sg_ext_shape& extension_shape(const std::string& name, std::string* source = nullptr);

/// The host side of an extension object (synthgen_ext.h sg_ext_host): its noise bases, made on
/// first use per seed (at most k_max_seeds) and shared by all threads, and the first failure
/// (a non-finite output) seen by any thread.
class ExtensionHost {
 public:
  static constexpr int k_max_seeds = 16;
  explicit ExtensionHost(std::string what);
  ~ExtensionHost();
  ExtensionHost(const ExtensionHost&) = delete;
  ExtensionHost& operator=(const ExtensionHost&) = delete;
  const sg_ext_host* host() const { return &m_host; }
  /// Records a failure (the first one is kept); thread-safe, cheap after the first.
  void fail(const std::string& message) const;
  /// "" when nothing failed, else "<what>: <message>".
  std::string failure() const;
  /// Checks `n` values for finiteness, recording a failure at `p` otherwise.
  bool check(const float* v, int n, const float p[3]) const;

 private:
  static const sg_ext_noise* noise(const sg_ext_host* host, uint64_t seed);
  std::string m_what;
  sg_ext_host m_host{};
  std::atomic<const void*> m_bases[k_max_seeds];
  uint64_t m_seeds[k_max_seeds] = {};
  mutable std::mutex m_mutex;
  mutable std::atomic<bool> m_failed{false};
  mutable std::string m_failure;
};

/// A shape of a user extension (an "shape" plugin): the extension's bounds and intersection
/// functions with the shape's parameter block, as a UserShape traced by Embree. Hits that are
/// not finite, outside (t_min, t_max) or without a normal are dropped and recorded as the
/// shape's failure (the render then fails naming it).
class ExtensionShape final : public UserShape {
 public:
  ExtensionShape(const sg_ext_shape& decl, std::vector<float> args, const std::string& source);
  Bounds3 bounds() const override { return m_bounds; }
  bool intersect(const Vec3f& o, const Vec3f& d, float t_min, float t_max, float* t, Vec3f* n,
                 Vec2f* uv) const override;
  std::string failure() const override { return m_host.failure(); }
  const std::string& name() const { return m_name; }

 private:
  const sg_ext_shape& m_decl;
  std::vector<float> m_args;
  std::string m_name;
  Bounds3 m_bounds;
  ExtensionHost m_host;
};

}  // namespace sg
