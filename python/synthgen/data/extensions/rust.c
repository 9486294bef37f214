/* rust.c -- synthgen's rust preset (synthgen.wear.rust) rewritten as a user extension.
 *
 * Three textures compute what the built-in preset builds from a graph of "noise", "gradient",
 * "edges" and "blend" textures: the rust mask (an fBm front denser at the bottom, vertical
 * run-off streaks, convex edges), the rust colour (fBm through a colour ramp) and the bump
 * (turbulence, with its gradient for bump mapping). They call synthgen's own noise (host->fbm,
 * host->turbulence), so the patterns are the built-in ones: tests/python/test_extensions.py
 * compares the images, bench/extension_overhead.py the render times.
 *
 * Installed with the package (synthgen.scene.extensions.example("rust")); synthgen.scene.wear_ext.rust
 * builds the preset on it. Extensions run with your rights.
 */
#include <math.h>
#include <synthgen_ext.h>

static float clamp01(float x) { return x < 0.f ? 0.f : (x > 1.f ? 1.f : x); }

/* The relative-local point (object position over the object's bounding box) and the footprint
 * of a mapping scaled by `smax`, as the built-in textures' "relative" mapping computes them. */
static float extent(const sg_ext_point* q, int i) {
  float e = q->object_hi[i] - q->object_lo[i];
  return e > 1e-12f ? e : 1.f;
}

/* ---- rust_mask ------------------------------------------------------------------------- */

typedef struct {
  float scale, seed, bottom_bias, streaks, edges, edge, threshold, softness;
} mask_args;

static const sg_ext_param mask_params[] = {
    {"scale", SG_EXT_FLOAT, {3.f}, 1e-3f, 1e3f, "fBm features across the object"},
    {"seed", SG_EXT_INT, {0.f}, 0.f, 16777216.f, "pattern seed (the streaks use seed + 3)"},
    {"bottom_bias", SG_EXT_FLOAT, {0.6f}, 0.f, 2.f, "more rust towards the bottom"},
    {"streaks", SG_EXT_FLOAT, {0.5f}, 0.f, 4.f, "weight of the vertical run-off streaks"},
    {"edges", SG_EXT_FLOAT, {1.f}, 0.f, 4.f, "weight of the convex-edge measure"},
    {"edge", SG_EXT_FLOAT_TEXTURE, {0.f}, 0.f, 1.f, "the convex-edge measure (an 'edges' texture)"},
    {"threshold", SG_EXT_FLOAT, {0.f}, -10.f, 10.f, "raw value at the rust front (calibrated for coverage)"},
    {"softness", SG_EXT_FLOAT, {0.f}, 0.f, 10.f, "width of the front in raw units (0: the raw value)"},
};

static void rust_mask(const sg_ext_point* q, const float* args, const sg_ext_host* host, float* out) {
  const mask_args* a = (const mask_args*)args;
  float r[3], emin = 1e30f;
  for (int i = 0; i < 3; ++i) {
    float e = extent(q, i);
    r[i] = (q->p_object[i] - q->object_lo[i]) / e;
    emin = e < emin ? e : emin;
  }
  if (emin < 1e-12f) emin = 1e-12f;
  float fp_rel = q->footprint * q->object_per_world / emin;
  uint64_t seed = (uint64_t)a->seed;
  float p[3] = {r[0] * a->scale, r[1] * a->scale, r[2] * a->scale};
  float n = clamp01((host->fbm(host->noise(host, seed), p, 4, 2.f, 1.f, fp_rel * a->scale, 0) + 1.f) * 0.5f);
  float raw = n + (1.f - clamp01(r[1])) * (a->bottom_bias * 0.25f);
  if (a->streaks > 0.f) {
    float s[3] = {r[0] * a->scale * 6.f, r[1] * a->scale * 0.5f, r[2] * a->scale * 6.f};
    float run = host->fbm(host->noise(host, seed + 3), s, 3, 2.f, 1.f, fp_rel * a->scale * 6.f, 0);
    raw += clamp01((run + 1.f) * 0.5f) * (a->streaks * 0.3f);
  }
  if (a->edges > 0.f) raw += a->edge * (a->edges * 1.5f);
  if (a->softness > 0.f) {
    float lo = a->threshold - 0.5f * a->softness;
    float t = clamp01((raw - lo) / a->softness);
    raw = t * t * (3.f - 2.f * t);
  }
  out[0] = raw;
}

/* ---- rust_color ------------------------------------------------------------------------ */

static const sg_ext_param color_params[] = {
    {"scale", SG_EXT_FLOAT, {12.f}, 1e-3f, 1e4f, "colour features per object-space unit"},
    {"seed", SG_EXT_INT, {1.f}, 0.f, 16777216.f, "pattern seed"},
    {"color0", SG_EXT_COLOR, {0.05f, 0.02f, 0.01f}, 0.f, 1.f, "ramp colour at 0"},
    {"color1", SG_EXT_COLOR, {0.16f, 0.05f, 0.015f}, 0.f, 1.f, "ramp colour at 0.35"},
    {"color2", SG_EXT_COLOR, {0.42f, 0.14f, 0.03f}, 0.f, 1.f, "ramp colour at 0.7"},
    {"color3", SG_EXT_COLOR, {0.55f, 0.25f, 0.06f}, 0.f, 1.f, "ramp colour at 1"},
};

static void rust_color(const sg_ext_point* q, const float* args, const sg_ext_host* host, float* out) {
  static const float pos[4] = {0.f, 0.35f, 0.7f, 1.f};
  float s = args[0];
  float p[3] = {q->p_object[0] * s, q->p_object[1] * s, q->p_object[2] * s};
  float v = host->fbm(host->noise(host, (uint64_t)args[1]), p, 4, 2.f, 1.f, q->footprint * q->object_per_world * s, 0);
  float t = clamp01((v + 0.6f) / 1.2f);
  const float* c = args + 2;  /* four colours of 3 floats */
  int k = 0;
  while (k < 2 && t > pos[k + 1]) ++k;
  float w = (t - pos[k]) / (pos[k + 1] - pos[k]);
  w = clamp01(w);
  for (int i = 0; i < 3; ++i) out[i] = c[3 * k + i] + w * (c[3 * (k + 1) + i] - c[3 * k + i]);
}

/* ---- rust_bump ------------------------------------------------------------------------- */

static const sg_ext_param bump_params[] = {
    {"scale", SG_EXT_FLOAT, {40.f}, 1e-3f, 1e4f, "bump features per object-space unit"},
    {"seed", SG_EXT_INT, {2.f}, 0.f, 16777216.f, "pattern seed"},
};

static void rust_bump(const sg_ext_point* q, const float* args, const sg_ext_host* host, float* out) {
  float s = args[0];
  float p[3] = {q->p_object[0] * s, q->p_object[1] * s, q->p_object[2] * s};
  out[0] = clamp01(host->turbulence(host->noise(host, (uint64_t)args[1]), p, 3, 2.f, 1.f,
                                    q->footprint * q->object_per_world * s, 0));
}

static int rust_bump_gradient(const sg_ext_point* q, const float* args, const sg_ext_host* host, float grad[3]) {
  float s = args[0], g[3];
  float p[3] = {q->p_object[0] * s, q->p_object[1] * s, q->p_object[2] * s};
  float v = host->turbulence(host->noise(host, (uint64_t)args[1]), p, 3, 2.f, 1.f,
                             q->footprint * q->object_per_world * s, g);
  float d = (v > 0.f && v < 1.f) ? s : 0.f; /* the clamp's derivative times the mapping's scale */
  for (int i = 0; i < 3; ++i) grad[i] = g[i] * d;
  return 1; /* object space */
}

static const sg_ext_texture textures[] = {
    {"rust_mask", "Rust coverage: fBm front, bottom bias, run-off streaks and convex edges.", 1, 0, mask_params,
     (int)(sizeof mask_params / sizeof mask_params[0]), rust_mask, 0},
    {"rust_color", "Rust colour: fBm through a four-stop colour ramp.", 3, 0, color_params,
     (int)(sizeof color_params / sizeof color_params[0]), rust_color, 0},
    {"rust_bump", "Rust bump: turbulence, with its gradient.", 1, 0, bump_params,
     (int)(sizeof bump_params / sizeof bump_params[0]), rust_bump, rust_bump_gradient},
};

SG_EXT_EXPORT const sg_ext_library* synthgen_extension(void) {
  static const sg_ext_library lib = {SG_EXT_ABI_VERSION, textures, 3, 0, 0};
  return &lib;
}
