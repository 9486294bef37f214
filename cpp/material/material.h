// Materials: the BSDF interface seen by the integrator.
//
// Directions are world-space unit vectors pointing away from the surface.
// `eval` returns f(wo, wi) * |cos(theta_i)| (cosine foreshortening included, as in
// Mitsuba 3), `pdf` the solid-angle density of `sample`, and `sample` returns the
// weight f * |cos| / pdf. A later material (conductor, dielectric, coated, mix)
// implements the same four calls; the integrator never looks inside a material.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/params.h"
#include "core/plugin.h"
#include "texture/texture.h"

namespace sg {

/// Local geometry at a ray hit, everything in world space.
/// Values of non-constant textures already evaluated at one shading point. A material calls
/// eval/pdf/sample several times per hit and a mix re-evaluates its mask in each call; the
/// values are exact functions of the hit, so the first evaluation is kept (per hit, on the
/// stack: no sharing between threads). `tag` 0 is a texture value, 1 a bump gradient.
struct TextureValueCache {
  static constexpr int k_size = 8;
  // NOTE: only `count` and `next` are initialized: a SurfaceInteraction is built per hit, and
  // zeroing the arrays would cost more than most lookups save.
  int count = 0, next = 0;
  const void* key[k_size];
  int tag[k_size];
  float value[k_size][3];
  bool find(const void* k, int t, Color* out) const {
    for (int i = 0; i < count; ++i)
      if (key[i] == k && tag[i] == t) {
        *out = Color(value[i][0], value[i][1], value[i][2]);
        return true;
      }
    return false;
  }
  void put(const void* k, int t, const Color& v) {
    int i;
    if (count < k_size) {
      i = count++;
    } else {
      i = next;
      next = (next + 1) % k_size;
    }
    key[i] = k;
    tag[i] = t;
    value[i][0] = v.x;
    value[i][1] = v.y;
    value[i][2] = v.z;
  }
  void clear() { count = next = 0; }
};

struct SurfaceInteraction {
  Vec3f p;        ///< position
  Vec3f p_error;  ///< conservative absolute floating-point error bound of `p`
  Vec3f ng;       ///< unit geometric normal (follows the mesh winding / handedness)
  Vec3f ns;       ///< unit shading normal, in the same hemisphere as `ng`
  Vec2f uv;       ///< texture coordinates
  /// Unit tangent along increasing u (world space), orthogonal to `ns`; an arbitrary
  /// tangent when the mesh has no uvs. Anisotropic BSDFs and normal maps use it.
  Vec3f dpdu;
  /// Width of the ray footprint in texture space (for filtered texture lookups); 0 means
  /// a point sample.
  float uv_footprint = 0.f;
  /// Footprint ellipse in texture space (conjugate axes, full widths) for anisotropic
  /// filtering; zero when unknown (then only `uv_footprint` is used). See eval_texture and
  /// integrator/ray_cone.h.
  Vec2f uv_axis_a, uv_axis_b;
  uint32_t inst = 0, prim = 0;
  /// For procedural textures (TexturePoint): the hit in object space, the mesh's object
  /// bounds, the footprint width in world units and the instance's object-per-world scale.
  Vec3f p_object;
  Vec3f n_object;  ///< unit (unperturbed) shading normal in object space
  Vec3f object_lo, object_hi;
  float world_footprint = 0.f;
  float object_per_world = 1.f;
  /// Ambient occlusion at the point (fraction of unoccluded short rays, 1 = open), computed by
  /// the integrator when the material needs it (k_needs_ao); 1 otherwise.
  float ao = 1.f;
  /// Convex-edge measure at the point (fraction of short rays along the surface that find no
  /// surface: 0 on an open panel, up to 1 at a thin edge), computed by the integrator when the
  /// material needs it (k_needs_edges); 0 otherwise.
  float edge = 0.f;
  /// True at the hit of a camera ray (set by the integrator): materials that trade noise
  /// for speed (the stochastic "mix") stay exact there, where the surface is seen directly.
  bool primary = false;
  /// The instance transform (3D bump mapping of procedural heights shifts p_object with it).
  const Transform* world_from_object = nullptr;
  /// Texture values evaluated at this point (see TextureValueCache); whoever moves the
  /// point (p, uv) must clear it.
  mutable TextureValueCache tex_cache;

  /// Local shading frame: s = dpdu, t = ns x dpdu, n = ns.
  Frame shading_frame() const {
    // dpdu is left zero when the material declared it does not need a tangent
    // (Material::needs): any frame around ns is then correct.
    if (dpdu.x == 0.f && dpdu.y == 0.f && dpdu.z == 0.f) return Frame(ns);
    Frame f;
    f.n = ns;
    f.s = dpdu;
    f.t = cross(ns, dpdu);
    return f;
  }
};

/// Everything a texture may read at an interaction.
inline TexturePoint texture_point(const SurfaceInteraction& si) {
  TexturePoint q;
  q.uv = si.uv;
  q.uv_footprint = si.uv_footprint;
  q.uv_axis_a = si.uv_axis_a;
  q.uv_axis_b = si.uv_axis_b;
  q.p_world = si.p;
  q.p_object = si.p_object;
  q.object_lo = si.object_lo;
  q.object_hi = si.object_hi;
  q.world_footprint = si.world_footprint;
  q.object_per_world = si.object_per_world;
  q.ao = si.ao;
  q.edge = si.edge;
  q.n_world = si.ns;
  q.n_object = si.n_object;
  return q;
}

inline Color eval_texture_uncached(const Texture& t, const SurfaceInteraction& si) {
  if (t.needs_position()) return t.eval_point(texture_point(si));
  if (si.uv_axis_a.x != 0.f || si.uv_axis_a.y != 0.f) return t.eval_ellipse(si.uv, si.uv_axis_a, si.uv_axis_b);
  return t.eval(si.uv, si.uv_footprint);
}

/// Texture lookup at an interaction, filtered over its footprint: anisotropically when the
/// integrator provided the footprint ellipse, else isotropically over `uv_footprint`; each
/// texture's value is computed once per hit (tex_cache). Materials should look textures up
/// through this rather than Texture::eval.
inline Color eval_texture(const Texture& t, const SurfaceInteraction& si) {
  if (t.is_constant()) return t.constant_value();
  Color c;
  if (si.tex_cache.find(&t, 0, &c)) return c;
  Color v = eval_texture_uncached(t, si);
  si.tex_cache.put(&t, 0, v);
  return v;
}

/// Coverage from a texture used as an alpha map: its alpha channel when it has one (image
/// files with 2 channels, grey + alpha, or 4+, RGBA), else its first channel (grey masks,
/// constants). Point-sampled (bilinear in the full-resolution level), since the cut-out test
/// runs with footprint 0 (see Material::has_alpha).
inline float eval_alpha_texture(const Texture& t, const SurfaceInteraction& si) {
  if (t.has_alpha_channel()) return t.eval_alpha(si.uv, 0.f);
  return t.eval(si.uv, 0.f).x;
}

enum MaterialNeeds : uint32_t {
  k_needs_tangent = 1u << 0,    ///< SurfaceInteraction::dpdu (anisotropy, normal maps)
  k_needs_footprint = 1u << 1,  ///< uv footprint (filtered textures)
  k_needs_ao = 1u << 2,         ///< SurfaceInteraction::ao (an "ao" texture): short occlusion rays
  k_needs_edges = 1u << 3,      ///< SurfaceInteraction::edge (an "edges" texture): rays along the surface
};

enum BsdfFlags : uint32_t {
  k_bsdf_none = 0,
  k_bsdf_diffuse = 1u << 0,
  k_bsdf_glossy = 1u << 1,
  k_bsdf_delta = 1u << 2,  ///< Dirac lobe: excluded from light sampling and MIS
  k_bsdf_reflection = 1u << 3,
  k_bsdf_transmission = 1u << 4,
};

struct BsdfSample {
  Vec3f wi;
  Color weight;  ///< f * |cos| / pdf
  float pdf = 0.f;
  uint32_t flags = 0;
  float eta = 1.f;  ///< relative index of refraction of a transmission event (1 otherwise)
};

/// A sharp lobe the texture resolution estimate follows (integrator/texture_estimate.h):
/// mirror reflection about the shading normal, or refraction with relative index `eta`
/// (interior over exterior, for a ray arriving from the side the shading normal points to;
/// 1 for a thin slab, which the ray passes straight through).
struct SpecularEvent {
  bool refract = false;
  float eta = 1.f;
};

/// Lobes at most this rough (GGX roughness, alpha = roughness^2) count as sharp for the
/// texture resolution estimate: textures seen in them are seen about as sharply as directly.
constexpr float k_sharp_roughness = 0.2f;

/// The MaterialNeeds bits of a texture: k_needs_footprint when it is filtered over the uv
/// footprint (not for constants or 3D-mapped procedural textures).
inline uint32_t texture_needs(const Texture& t) {
  return (t.is_constant() || !t.needs_uv_footprint()) ? 0u : uint32_t(k_needs_footprint);
}

class Material {
 public:
  /// flags(), needs() and is_emissive(), which are fixed once a material is built.
  struct Traits {
    uint32_t flags = 0, needs = 0;
    bool emissive = false;
  };

  virtual ~Material() = default;
  /// The traits without virtual calls once cache_traits() ran (create_material does).
  Traits traits() const { return m_traits_cached ? m_traits : Traits{flags(), needs(), is_emissive()}; }
  /// Ambient occlusion wanted by the material's textures ("ao"): the ray length (0 = none)
  /// and the number of rays. Set by the scene from the textures the material refers to.
  float ao_radius() const { return m_ao_radius; }
  int ao_samples() const { return m_ao_samples; }
  void set_ao(float radius, int samples) {
    m_ao_radius = radius;
    m_ao_samples = samples;
    if (radius > 0.f) m_traits.needs |= k_needs_ao;
  }
  /// Convex-edge rays wanted by the material's textures ("edges"), as set_ao.
  float edge_radius() const { return m_edge_radius; }
  int edge_samples() const { return m_edge_samples; }
  void set_edges(float radius, int samples) {
    m_edge_radius = radius;
    m_edge_samples = samples;
    if (radius > 0.f) m_traits.needs |= k_needs_edges;
  }
  void cache_traits() {
    m_traits = Traits{flags(), needs(), is_emissive()};
    m_traits_cached = true;
  }

  virtual Color eval(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const = 0;
  virtual float pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi) const = 0;
  /// eval() and pdf() together (next-event estimation needs both); materials override it
  /// when the two share work. Must equal the separate calls.
  virtual Color eval_pdf(const SurfaceInteraction& si, const Vec3f& wo, const Vec3f& wi, float* pdf_out) const {
    *pdf_out = pdf(si, wo, wi);
    return eval(si, wo, wi);
  }
  /// `u_lobe` selects a lobe, `u` warps the direction. Returns false when no direction
  /// is produced (the path ends).
  virtual bool sample(const SurfaceInteraction& si, const Vec3f& wo, float u_lobe, const Vec2f& u,
                      BsdfSample* out) const = 0;
  /// What the material reads from a SurfaceInteraction beyond position, normals and uv
  /// (MaterialNeeds bits). The integrator skips computing what no material needs; the
  /// default (everything) is always correct.
  virtual uint32_t needs() const { return k_needs_tangent | k_needs_footprint; }
  /// Nesting depth of "mix" materials (0 for any other material).
  virtual int mix_depth() const { return 0; }
  /// Diffuse-equivalent reflectance for the albedo output (a denoiser feature).
  virtual Color albedo(const SurfaceInteraction& si) const = 0;
  /// Union of BsdfFlags of all lobes; materials without non-delta lobes skip light sampling.
  virtual uint32_t flags() const = 0;

  /// The sharp lobes at `si` (delta lobes, and glossy ones no rougher than
  /// k_sharp_roughness) that the texture resolution estimate follows, at most 4, written to
  /// `out`; returns their number. Default: none (diffuse and rough materials).
  virtual int specular_events(const SurfaceInteraction& si, SpecularEvent out[4]) const { return 0; }

  /// Emitted radiance towards `wo` (zero for non-emitters).
  virtual Color emission(const SurfaceInteraction& si, const Vec3f& wo) const { return Color(0.f); }
  virtual bool is_emissive() const { return false; }
  /// Mean emitted radiance over the surface (for light power estimates).
  virtual Color average_emission() const { return Color(0.f); }
  /// True when emission leaves both faces.
  virtual bool two_sided_emission() const { return false; }
  /// True when emission(si, wo) is exactly average_emission() towards the emitting face(s)
  /// (the front, or both with two_sided_emission()) and zero otherwise, wherever si is:
  /// light sampling then skips building an interaction for the emission lookup.
  virtual bool uniform_emission() const { return false; }
  /// Coverage for alpha cut-outs in [0, 1]: 1 = opaque surface, 0 = a hole the ray passes.
  virtual float alpha(const SurfaceInteraction& si) const { return 1.f; }
  /// True when alpha() can be below alpha_cutoff() somewhere. Only then are the meshes
  /// using this material alpha-tested during traversal (Accel filter callback): a hit with
  /// alpha < alpha_cutoff is not a surface at all, for camera, shadow and label rays alike
  /// (glTF alphaMode MASK). The test runs inside traversal with only `uv`, `inst` and
  /// `prim` of `si` filled (footprint 0): alpha() must not use anything else, and must be
  /// deterministic (labels stay exact).
  virtual bool has_alpha() const { return false; }
  /// Threshold of the cut-out test (glTF alphaCutoff, default 0.5).
  virtual float alpha_cutoff() const { return 0.5f; }
  /// The cut-out test: false when a hit at `si` must be ignored.
  bool alpha_opaque(const SurfaceInteraction& si) const { return !has_alpha() || alpha(si) >= alpha_cutoff(); }

 private:
  Traits m_traits;
  bool m_traits_cached = false;
  float m_ao_radius = 0.f;
  int m_ao_samples = 0;
  float m_edge_radius = 0.f;
  int m_edge_samples = 0;
};

/// What a material plugin may look up while it is created: textures and (for materials
/// made of other materials, such as "mix") materials, by id (core/plugin.h).
using MaterialContext = PluginContext;

/// Creates a material plugin by registry key (core/plugin.h: the parameters are checked
/// against the plugin's declaration first). Throws sg::Error naming `context` for unknown
/// types, unknown, ill-typed or out-of-range parameters.
std::shared_ptr<Material> create_material(const std::string& type, const ParamSet& params,
                                          const MaterialContext& ctx, const std::string& context);
/// Registry keys of all material plugins.
std::vector<std::string> material_types();

}  // namespace sg
