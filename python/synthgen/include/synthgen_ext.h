/* synthgen_ext.h -- the C interface of synthgen extensions (ABI version 1).
 *
 * An extension is one C file that adds procedural textures and geometric primitives to
 * synthgen without recompiling it (docs/extensions.md). synthgen compiles the file with the C
 * compiler that built it (cc -O2 -shared -fPIC), caches the library by the hash of the source,
 * this header and the compiler, loads it and registers what it declares as plugins by name:
 * a texture extension is then created like any texture ({type: my_texture, ...}), a shape
 * extension with Scene.add_shape. EXTENSIONS RUN WITH YOUR RIGHTS: synthgen loads them only
 * when asked to (scene.load_extension in Python; `allow_extensions: true` in a scenario or
 * scene file plus --allow-extensions on the command line).
 *
 * The library exports one function, synthgen_extension(), returning a static description:
 *
 *   #include <math.h>
 *   #include <synthgen_ext.h>
 *   static const sg_ext_param stripes_params[] = {
 *     {"frequency", SG_EXT_FLOAT, {10}, 0, 1e4, "stripes per unit of u"},
 *     {"color", SG_EXT_COLOR, {1, 0.5, 0}, 0, 1, "colour of the stripes"},
 *   };
 *   static void stripes(const sg_ext_point* q, const float* args, const sg_ext_host* host, float* out) {
 *     float s = sinf(6.2831853f * args[0] * q->uv[0]) > 0 ? 1.f : 0.f;
 *     for (int c = 0; c < 3; ++c) out[c] = s * args[1 + c];
 *   }
 *   static const sg_ext_texture textures[] = {
 *     {"stripes", "Stripes along u.", 3, 0, stripes_params, 2, stripes, 0},
 *   };
 *   SG_EXT_EXPORT const sg_ext_library* synthgen_extension(void) {
 *     static const sg_ext_library lib = {SG_EXT_ABI_VERSION, textures, 1, 0, 0};
 *     return &lib;
 *   }
 *
 * Arguments: each texture or shape declares its parameters (name, type, default, range,
 * doc); synthgen checks given values against them like any plugin's (unknown keys, ranges)
 * and passes them as a block of floats, the parameters in declaration order, 1 float for
 * SG_EXT_FLOAT / SG_EXT_INT / SG_EXT_FLOAT_TEXTURE, 3 for SG_EXT_COLOR / SG_EXT_VEC3 /
 * SG_EXT_COLOR_TEXTURE, without padding (a struct of floats can overlay it). Changing an
 * argument never recompiles: the block is built when the texture is created (Hydra's
 * argument "pseudo-stack", Sanzharov 2023). Texture parameters (SG_EXT_*_TEXTURE) take a
 * number or a texture reference; a referenced texture is evaluated by synthgen at the same
 * point before the call and its value written into the block.
 *
 * Rules: functions must be pure (the same inputs give the same outputs, whatever thread calls
 * them: synthgen calls them from all its threads at once), keep no global state, return
 * finite values (a NaN or infinity fails the render with an error naming the extension), and
 * never call exit or longjmp. Integers (SG_EXT_INT) are exact up to 2^24.
 */
#ifndef SYNTHGEN_EXT_H
#define SYNTHGEN_EXT_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define SG_EXT_ABI_VERSION 1u
#define SG_EXT_EXPORT __attribute__((visibility("default")))

/* Parameter types. */
enum {
  SG_EXT_FLOAT = 0,          /* a number: 1 float */
  SG_EXT_INT = 1,            /* an integer (seeds, counts): 1 float holding it */
  SG_EXT_COLOR = 2,          /* a colour (a number means grey): 3 floats */
  SG_EXT_VEC3 = 3,           /* a vector (a number means all three): 3 floats */
  SG_EXT_FLOAT_TEXTURE = 4,  /* a number or a texture reference (its first channel): 1 float */
  SG_EXT_COLOR_TEXTURE = 5   /* a colour or a texture reference: 3 floats */
};

typedef struct sg_ext_param {
  const char* name;   /* the key in YAML / Python (lower_snake_case) */
  int type;           /* SG_EXT_* above */
  float def[3];       /* default (the first component for 1-float types) */
  float lo, hi;       /* inclusive range of the value / each component (lo = hi = 0: any) */
  const char* doc;    /* one line */
} sg_ext_param;

/* Flags of a texture. */
enum {
  SG_EXT_NEEDS_UV_FOOTPRINT = 1  /* reads uv_footprint (uv-mapped detail); else only the world footprint */
};

/* The point a texture is evaluated at. Object space is the mesh's own (before the instance
 * transform); relative coordinates are (p_object - object_lo) / (object_hi - object_lo). */
typedef struct sg_ext_point {
  float p[3];               /* world position (metres) */
  float n[3];               /* unit shading normal, world space */
  float uv[2];              /* surface texture coordinates */
  float p_object[3];        /* object-space position */
  float n_object[3];        /* unit shading normal, object space */
  float object_lo[3];       /* the mesh's object-space bounds */
  float object_hi[3];
  float footprint;          /* width of the pixel's footprint at the point, world units (0: point sample) */
  float uv_footprint;       /* the same in uv units */
  float object_per_world;   /* object-space length per world length (instance scale) */
} sg_ext_point;

typedef struct sg_ext_noise sg_ext_noise; /* opaque: one seeded noise basis */

/* What synthgen offers an extension: its own noise functions, so that an extension computes
 * the very patterns of the built-in textures ("noise", docs/wear.md). */
typedef struct sg_ext_host {
  uint32_t abi_version;
  void* self;  /* synthgen's; pass `host` back as the first argument */
  /* The noise basis of a seed (improved Perlin noise with a permutation from the seed);
   * cached per texture, at most 16 seeds per texture (more: a null basis, and an error). */
  const sg_ext_noise* (*noise)(const struct sg_ext_host* host, uint64_t seed);
  /* Perlin noise in [-1, 1]. */
  float (*perlin)(const sg_ext_noise* b, const float p[3]);
  /* Fractal sums (fBm in [-1, 1], turbulence in [0, 1]): `octaves` (1..16), frequency ratio
   * `lacunarity`, weights lacunarity^(-H i), normalized; octaves finer than `footprint` (in
   * the units of p, 0: none) fade out. `grad` (may be null) receives the gradient. */
  float (*fbm)(const sg_ext_noise* b, const float p[3], int octaves, float lacunarity, float H, float footprint,
               float grad[3]);
  float (*turbulence)(const sg_ext_noise* b, const float p[3], int octaves, float lacunarity, float H,
                      float footprint, float grad[3]);
  /* Worley noise: out[0] = distance to the nearest feature point, out[1] to the second,
   * out[2] to the nearest cell edge; returns the nearest cell's hash in [0, 1). */
  float (*cellular)(const sg_ext_noise* b, const float p[3], float jitter, float out[3]);
} sg_ext_host;

/* A texture: writes `channels` values (1 or 3) to out. */
typedef void (*sg_ext_texture_fn)(const sg_ext_point* q, const float* args, const sg_ext_host* host, float* out);
/* Optional: the gradient of the first channel, with respect to p_object (return 1) or p
 * (return 2), for bump mapping without finite differences; 0: none at this point. */
typedef int (*sg_ext_gradient_fn)(const sg_ext_point* q, const float* args, const sg_ext_host* host,
                                  float grad[3]);

typedef struct sg_ext_texture {
  const char* name;            /* registry key: [a-z][a-z0-9_]*, not a built-in texture's */
  const char* doc;             /* one paragraph */
  int channels;                /* 1 (a value, shown as grey) or 3 (a colour) */
  int flags;                   /* SG_EXT_NEEDS_UV_FOOTPRINT */
  const sg_ext_param* params;
  int param_count;
  sg_ext_texture_fn eval;
  sg_ext_gradient_fn gradient; /* may be null */
} sg_ext_texture;

/* A ray in the shape's object space: points o + t d for t in (t_min, t_max). */
typedef struct sg_ext_ray {
  float o[3], d[3];
  float t_min, t_max;
} sg_ext_ray;

/* A hit: the ray parameter, the outward unit normal (object space) and surface coordinates. */
typedef struct sg_ext_hit {
  float t;
  float n[3];
  float uv[2];
} sg_ext_hit;

/* A geometric primitive, run as Embree user geometry: it is instanced, labelled, shadowed and
 * lit like a mesh. `bounds` gives its object-space box (it must hold every hit); `intersect`
 * returns 1 and fills `hit` for the closest hit with t_min < t < t_max, else 0. */
typedef struct sg_ext_shape {
  const char* name;
  const char* doc;
  const sg_ext_param* params;  /* numbers only (no textures) */
  int param_count;
  void (*bounds)(const float* args, float lo[3], float hi[3]);
  int (*intersect)(const float* args, const sg_ext_ray* ray, sg_ext_hit* hit);
} sg_ext_shape;

typedef struct sg_ext_library {
  uint32_t abi_version;  /* SG_EXT_ABI_VERSION */
  const sg_ext_texture* textures;
  int texture_count;
  const sg_ext_shape* shapes;
  int shape_count;
} sg_ext_library;

/* The one symbol a library exports. */
typedef const sg_ext_library* (*sg_ext_entry_fn)(void);
#define SG_EXT_ENTRY "synthgen_extension"

#ifdef __cplusplus
}
#endif

#endif /* SYNTHGEN_EXT_H */
