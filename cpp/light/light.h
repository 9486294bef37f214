// Lights: what next-event estimation samples.
//
// Explicit lights ("point", "spot", "sun", "environment", "envmap", "sky") are created by
// name from a ParamSet; area lights are made by the scene from instances with emissive
// materials.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/params.h"
#include "material/material.h"

namespace sg {

/// Where a light is sampled from: the shading point and its error bound.
struct LightSampleContext {
  Vec3f p;
  Vec3f p_error;
  /// The shading normal on the side the surface reflects to, when it only reflects (zero
  /// otherwise, and away from surfaces): lights whose light spans the sky may sample their
  /// directions by the cosine around it (Light::pdf_li).
  Vec3f n{0.f};
};

struct LightSample {
  Vec3f wi;          ///< unit direction from the reference point towards the light
  Color li;          ///< radiance (or, for delta lights, irradiance-like intensity) arriving
  float pdf = 0.f;   ///< solid-angle pdf (1 for delta lights)
  Vec3f p_light;     ///< sampled point (finite lights)
  Vec3f p_light_error;
  Vec3f n_light;     ///< surface normal at the sampled point (area lights)
  bool delta = false;
  bool infinite = false;  ///< the shadow ray goes to infinity
};

/// Fills `out` with a sample of an infinite light (no point, no normal; not a delta): direction,
/// radiance and solid-angle pdf.
inline void set_infinite_sample(LightSample* out, const Vec3f& wi, const Color& li, float pdf) {
  out->wi = wi;
  out->li = li;
  out->pdf = pdf;
  out->delta = false;
  out->infinite = true;
  out->p_light_error = Vec3f(0.f);
  out->n_light = Vec3f(0.f);
}

/// Fills `out` with the sample of a point emitter at `pos` seen from ctx.p (a delta light): its
/// `intensity` times `profile(w)` -- in [0, 1] along the unit direction w from the emitter; 0: no
/// light that way, no sample -- over the squared distance (point, spot, headlamp).
template <typename Profile>
bool sample_point_emitter(const LightSampleContext& ctx, const Vec3f& pos, const Color& intensity,
                          const Profile& profile, LightSample* out) {
  const Vec3f d = pos - ctx.p;
  const float dist2 = length_squared(d);
  if (!(dist2 > 0.f)) return false;
  const Vec3f wi = d / std::sqrt(dist2);
  const float f = profile(-wi);
  if (!(f > 0.f)) return false;
  out->wi = wi;
  out->li = intensity * (f / dist2);
  out->pdf = 1.f;
  out->p_light = pos;
  out->p_light_error = Vec3f(0.f);
  out->n_light = Vec3f(0.f);
  out->delta = true;
  out->infinite = false;
  return true;
}

class Light {
 public:
  virtual ~Light() = default;
  virtual bool sample(const LightSampleContext& ctx, const Vec2f& u, LightSample* out) const = 0;
  /// Approximate emitted power (luminance-weighted), for light selection.
  virtual float power() const = 0;
  virtual bool is_delta() const { return false; }
  virtual bool is_infinite() const { return false; }
  /// Infinite lights: radiance arriving along -dir, i.e. seen when looking along `dir`.
  virtual Color le(const Vec3f& dir) const { return Color(0.f); }
  /// Infinite lights: solid-angle pdf with which `sample` produces `dir`, for a context
  /// without a normal (see pdf_li).
  virtual float pdf_le(const Vec3f& dir) const { return 0.f; }
  /// Infinite lights: solid-angle pdf with which `sample(ctx, ...)` produces `dir` (lights
  /// that sample by the context's normal depend on it; the others return pdf_le(dir)).
  virtual float pdf_li(const LightSampleContext& ctx, const Vec3f& dir) const { return pdf_le(dir); }
  /// A light over the whole sky ("environment", "envmap", the dome of "sky"): next-event
  /// estimation samples such lights at every vertex apart from the others (a sun, lamps),
  /// each set by its own strategy, combined with BSDF sampling by MIS (RenderScene groups).
  virtual bool is_dome() const { return false; }
  /// The lights the renderer samples in this one's place: itself, or its parts sampled apart
  /// ("sky": its dome and its sun). Parts live as long as this light.
  virtual std::vector<const Light*> parts() const { return {this}; }
  /// Infinite lights: whether camera rays see le() directly (false hides an environment
  /// from the camera while it still lights the scene and shows in reflections).
  virtual bool visible_to_camera() const { return true; }
  /// An infinite light seen only at the end of camera paths of glossy or specular bounces (what
  /// the camera sees reflected or refracted), never lighting a diffuse surface: not sampled by
  /// next-event estimation, not seen by camera rays. Cycles' world shaders do the like with the
  /// "is glossy ray" light path: a photo's surroundings for what objects reflect.
  virtual bool reflection_only() const { return false; }
  /// Called once per commit with the world bounds of the scene.
  virtual void preprocess(const Bounds3& scene_bounds) {}
  /// Lights at a place (area, point, spot): a sphere holding the emitter, for choosing lights
  /// by their distance to the shading point (RenderScene::pick_light). False: no place.
  virtual bool bounding_sphere(Vec3f* centre, float* radius) const { return false; }
  /// One-sided emitters: a cone (unit axis, half-angle in radians) holding the normals of the
  /// sides that emit. False: it emits in every direction.
  virtual bool normal_cone(Vec3f* axis, float* half_angle) const { return false; }
  /// Delta lights whose intensity varies with direction ("spot", "headlamp"): true when
  /// selection_intensity() gives it, for light selection.
  virtual bool has_selection_intensity() const { return false; }
  /// The luminance of the intensity sent towards p (W/sr): light selection weighs such a light
  /// by it / d^2, its exact unoccluded irradiance at p (RenderScene::light_weight).
  virtual float selection_intensity(const Vec3f& p) const { return 0.f; }
};

/// Creates a light plugin (see light_types()) from parameters. Throws sg::Error naming `context`.
std::shared_ptr<Light> create_light(const std::string& type, const ParamSet& params, const std::string& context);
/// Registry keys of all light plugins.
std::vector<std::string> light_types();

/// One emitting triangle in world space (built by the scene at commit).
struct EmissiveTriangle {
  Vec3f p0, p1, p2;
  Vec3f n;  ///< unit geometric normal, oriented like SurfaceInteraction::ng
  Vec2f uv0, uv1, uv2;
  /// Absolute floating-point error bound of points computed on this triangle: the bound of
  /// make_interaction for its instance (from the *object-space* vertices) plus the
  /// interpolation error in world space.
  float p_error = 0.f;
  uint32_t prim;
  const Material* material;
  /// Set by AreaLight from Material::uniform_emission(): the radiance of every point
  /// towards the emitting face(s), so sampling needs no emission lookup.
  bool uniform = false, two_sided = false;
  Color uniform_le{0.f};
};

/// All emissive triangles of one instance; triangles are chosen by area x luminance.
class AreaLight final : public Light {
 public:
  AreaLight(uint32_t inst, uint32_t prim_count, std::vector<EmissiveTriangle> tris);
  bool sample(const LightSampleContext& ctx, const Vec2f& u, LightSample* out) const override;
  float power() const override { return m_power; }
  /// Area pdf of the sampling strategy at a point on triangle `prim` (0 if not emissive).
  float area_pdf(uint32_t prim) const { return prim < m_area_pdf.size() ? m_area_pdf[prim] : 0.f; }
  bool bounding_sphere(Vec3f* centre, float* radius) const override;
  bool normal_cone(Vec3f* axis, float* half_angle) const override;

 private:
  uint32_t m_inst;
  std::vector<EmissiveTriangle> m_tris;
  std::vector<float> m_area_pdf;  // indexed by primitive
  std::vector<float> m_cdf;       // over m_tris
  float m_power = 0.f;
};

}  // namespace sg
