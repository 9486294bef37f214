// Participating media: the Medium interface (plugins of kind "medium", one per file in this
// folder) and the Henyey-Greenstein phase function they scatter with.
//
// A medium fills a region of space (the scene's global medium: RenderScene::medium) and is
// described by its extinction coefficient sigma_t (grey: the same for every wavelength, so
// free-flight sampling needs no spectral MIS), its single-scattering albedo
// sigma_s / sigma_t (RGB) and a Henyey-Greenstein phase function of asymmetry g. The path
// tracer asks it two things per ray segment: where a free flight along the segment ends
// (sample_distance; a scattering event before the segment's end, or none) and, for shadow
// rays, the transmittance over the segment.
#pragma once

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/params.h"
#include "core/rng.h"

namespace sg {

/// Henyey-Greenstein phase function of asymmetry g in (-1, 1): > 0 scatters forwards.
/// Convention (pbrt-v4): wo points back along the incoming ray (towards where the light goes
/// to), wi towards where light comes from; both unit.
/// NOTE: Henyey & Greenstein 1941, "Diffuse radiation in the galaxy"; the density of
/// p(cos) = (1 - g^2) / (4 pi (1 + g^2 + 2 g cos)^(3/2)) with cos = dot(wo, wi) (the sign of
/// the 2 g cos term makes g > 0 forward scattering with this convention: wi = -wo), and its
/// inversion as in Pharr, Jakob, Humphreys, "Physically Based Rendering" 4th ed., sec. 11.3.1
/// (SampleHenyeyGreenstein).
struct HenyeyGreenstein {
  float g = 0.f;

  /// The phase function's value (= the pdf of sample()) for directions with dot(wo, wi) = cos.
  static float eval(float g, float cos_theta) {
    const float denom = 1.f + g * g + 2.f * g * cos_theta;
    return 0.25f * k_inv_pi * (1.f - g * g) / (denom * std::sqrt(std::max(denom, 1e-12f)));
  }
  float eval(const Vec3f& wo, const Vec3f& wi) const { return eval(g, dot(wo, wi)); }

  /// A direction wi distributed as the phase function around wo; its pdf (= the value).
  Vec3f sample(const Vec3f& wo, const Vec2f& u, float* pdf) const {
    float cos_theta;
    if (std::fabs(g) < 1e-3f) {
      cos_theta = 1.f - 2.f * u.x;
    } else {
      const float q = (1.f - g * g) / (1.f + g - 2.f * g * u.x);
      cos_theta = -(1.f + g * g - q * q) / (2.f * g);
    }
    cos_theta = std::clamp(cos_theta, -1.f, 1.f);
    const float sin_theta = std::sqrt(std::max(0.f, 1.f - cos_theta * cos_theta));
    const float phi = 2.f * k_pi * u.y;
    const Vec3f local(sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta);
    *pdf = eval(g, cos_theta);
    return normalize(Frame(wo).to_world(local));
  }
};

/// A deterministic stream of uniform numbers in [0, 1) for one query of a medium: delta and ratio
/// tracking draw as many as their tentative collisions need. A counter-based hash of a 64-bit key
/// (PixelSampler::independent_key of one sample dimension): a pure function of (key, index), so
/// renders stay bit-identical for any thread count. Its first number is the key's own high bits,
/// i.e. exactly PixelSampler::get_independent of that dimension: a medium that needs one number
/// (the homogeneous one) sees what it saw before streams existed.
class MediumRng {
 public:
  explicit MediumRng(uint64_t key) : m_key(key) {}
  float next() {
    // NOTE: SplitMix64's finalizer of key xor a Weyl sequence (Steele, Lea, Flood 2014): each
    // index gives an independent-looking hash; index 0 is the key itself (see the class doc).
    const uint64_t h = m_index ? mix64(m_key ^ (m_index * 0xd1b54a32d192ed03ull)) : m_key;
    ++m_index;
    return bits_to_unit_float(uint32_t(h >> 32));
  }

 private:
  uint64_t m_key;
  uint64_t m_index = 0;
};

/// A participating medium. Rays are o + t d with any non-zero d (t in units of |d|).
///
/// Homogeneous media answer exactly (closed forms). Heterogeneous ones (medium/tracking.h) track
/// against a majorant grid: free flights by delta tracking, transmittance by ratio tracking --
/// unbiased estimates, drawn from a MediumRng.
class Medium {
 public:
  virtual ~Medium() = default;
  /// Transmittance exp(-optical depth) over the ray's parameters [0, t_max) (t_max may be inf),
  /// deterministic: exact, or a quadrature of the optical depth (heterogeneous media). For labels
  /// and tests; rendering uses transmittance_estimate().
  virtual float transmittance(const Vec3f& o, const Vec3f& d, float t_max) const = 0;
  /// An unbiased estimate of the transmittance (shadow rays); the exact value where there is one.
  virtual float transmittance_estimate(const Vec3f& o, const Vec3f& d, float t_max, MediumRng& rng) const {
    return transmittance(o, d, t_max);
  }
  /// Samples a free flight from o along d within [0, t_max): returns true and the ray parameter
  /// *t of a scattering event (density sigma_t T(t) along the path length), false when the flight
  /// reaches t_max (probability T(t_max)). Either way the estimator's weight is what
  /// albedo() / 1 says: the ratios of contribution to probability.
  virtual bool sample_distance(const Vec3f& o, const Vec3f& d, float t_max, MediumRng& rng, float* t) const = 0;
  /// Samples a scattering point along [0, t_max) for decoupled next-event estimation: returns
  /// false when the segment does not cross the medium, else *t and *weight such that
  /// E[weight f(t)] = integral over the segment of sigma_t(s) T(s) f(s) ds for any f (the
  /// in-scattered light's estimator besides the albedo). Homogeneous: t from the free-flight
  /// density conditioned on scattering before t_max, weight 1 - T(t_max).
  virtual bool sample_in_segment(const Vec3f& o, const Vec3f& d, float t_max, MediumRng& rng, float* t,
                                 float* weight) const = 0;
  /// sigma_s / sigma_t: the throughput's factor at a scattering event.
  virtual Color albedo() const = 0;
  /// The phase function at scattering events.
  virtual HenyeyGreenstein phase() const = 0;
};

/// Names of the registered medium plugins.
std::vector<std::string> medium_types();
/// Creates medium `type` from `params` (checked against its declaration; errors name `context`).
std::shared_ptr<Medium> create_medium(const std::string& type, const ParamSet& params, const std::string& context);

}  // namespace sg
