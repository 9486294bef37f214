/* shapes.c -- geometric primitives as a user extension: an analytic sphere, and a rounded box
 * and a torus given by signed distance functions (sphere tracing, Hart 1996).
 *
 * Each shape gives its object-space bounds and the closest hit of a ray (t, outward normal,
 * uv); synthgen traces it as Embree user geometry, so it is instanced, labelled (exact depth
 * and masks from the first hit), shadowed and lit like a mesh. tests/python/test_extensions.py
 * checks the depth and mask labels against the analytic intersections.
 *
 * Installed with the package (synthgen.scene.extensions.example("shapes")). Extensions run with
 * your rights.
 */
#include <math.h>
#include <synthgen_ext.h>

#define PI 3.14159265358979f

static float dot3(const float* a, const float* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void set_normal(sg_ext_hit* h, float x, float y, float z) {
  float l = sqrtf(x * x + y * y + z * z);
  if (!(l > 0.f)) { x = 0.f; y = 1.f; z = 0.f; l = 1.f; }
  h->n[0] = x / l; h->n[1] = y / l; h->n[2] = z / l;
}

/* ---- sphere (analytic) ----------------------------------------------------------------- */

static const sg_ext_param sphere_params[] = {
    {"radius", SG_EXT_FLOAT, {1.f}, 1e-6f, 1e6f, "radius (object units)"},
};

static void sphere_bounds(const float* args, float lo[3], float hi[3]) {
  for (int i = 0; i < 3; ++i) { lo[i] = -args[0]; hi[i] = args[0]; }
}

static int sphere_intersect(const float* args, const sg_ext_ray* ray, sg_ext_hit* hit) {
  /* NOTE: pbrt-v4's robust quadratic for spheres (Pharr et al. 2023, sec. 6.8.4): the
   * discriminant from the squared distance of the centre to the ray's line, and the root
   * q = -(b + sign(b) sqrt(disc)) / 2 avoiding cancellation; in double precision. */
  double r = args[0];
  double o[3] = {ray->o[0], ray->o[1], ray->o[2]}, d[3] = {ray->d[0], ray->d[1], ray->d[2]};
  double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  double b = 2.0 * (o[0] * d[0] + o[1] * d[1] + o[2] * d[2]);
  double c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - r * r;
  double f = b / (2.0 * a);
  double v[3] = {o[0] - f * d[0], o[1] - f * d[1], o[2] - f * d[2]};
  double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  double disc = 4.0 * a * (r + len) * (r - len);
  if (disc < 0.0) return 0;
  double root = sqrt(disc);
  double q = b < 0.0 ? -0.5 * (b - root) : -0.5 * (b + root);
  double t0 = q / a, t1 = c / q;
  if (t0 > t1) { double s = t0; t0 = t1; t1 = s; }
  double t = t0;
  if (!(t > ray->t_min)) t = t1;
  if (!(t > ray->t_min) || !(t < ray->t_max)) return 0;
  float p[3] = {(float)(o[0] + t * d[0]), (float)(o[1] + t * d[1]), (float)(o[2] + t * d[2])};
  hit->t = (float)t;
  if (!(hit->t > ray->t_min && hit->t < ray->t_max)) return 0;
  set_normal(hit, p[0], p[1], p[2]);
  hit->uv[0] = 0.5f + atan2f(p[2], p[0]) / (2.f * PI);
  hit->uv[1] = acosf(fmaxf(-1.f, fminf(1.f, hit->n[1]))) / PI;
  return 1;
}

/* ---- signed distance shapes -------------------------------------------------------------- */

/* Rounded box: half extents args[0..2] / 2, edge radius args[3] (Quilez, "distance functions"). */
static float rbox_sdf(const float* args, const float* p) {
  float q[3], out = 0.f, in = -1e30f;
  for (int i = 0; i < 3; ++i) {
    q[i] = fabsf(p[i]) - (0.5f * args[i] - args[3]);
    float m = q[i] > 0.f ? q[i] : 0.f;
    out += m * m;
    in = q[i] > in ? q[i] : in;
  }
  return sqrtf(out) + (in < 0.f ? in : 0.f) - args[3];
}

/* Torus around the y axis: major radius args[0], minor radius args[1]. */
static float torus_sdf(const float* args, const float* p) {
  float a = sqrtf(p[0] * p[0] + p[2] * p[2]) - args[0];
  return sqrtf(a * a + p[1] * p[1]) - args[1];
}

typedef float (*sdf_fn)(const float* args, const float* p);

/* NOTE: sphere tracing (Hart 1996, "Sphere tracing: a geometric method for the antialiased ray
 * tracing of implicit surfaces"): steps of the distance bound, from the ray's entry into the
 * bounds (slab test) to its exit; a hit when the distance falls below eps (1e-6 of the shape's
 * size), refined by one more step. A ray starting inside (negative distance: refracted or
 * offset rays) marches on |distance| until the sign changes. */
static int sdf_intersect(sdf_fn f, const float* args, const float lo[3], const float hi[3], const sg_ext_ray* ray,
                         sg_ext_hit* hit) {
  float dl = sqrtf(dot3(ray->d, ray->d));
  if (!(dl > 0.f)) return 0;
  float t0 = ray->t_min, t1 = ray->t_max;
  for (int i = 0; i < 3; ++i) {
    float inv = 1.f / ray->d[i];
    float a = (lo[i] - ray->o[i]) * inv, b = (hi[i] - ray->o[i]) * inv;
    if (a > b) { float s = a; a = b; b = s; }
    t0 = a > t0 ? a : t0;
    t1 = b < t1 ? b : t1;
    if (t0 > t1) return 0;
  }
  float size = fmaxf(hi[0] - lo[0], fmaxf(hi[1] - lo[1], hi[2] - lo[2]));
  float eps = 1e-6f * size;
  float t = t0, p[3];
  for (int i = 0; i < 3; ++i) p[i] = ray->o[i] + t * ray->d[i];
  float d0 = f(args, p);
  float side = d0 < 0.f ? -1.f : 1.f;
  for (int step = 0; step < 512 && t <= t1; ++step) {
    for (int i = 0; i < 3; ++i) p[i] = ray->o[i] + t * ray->d[i];
    float d = side * f(args, p);
    if (d < eps) {
      t += d / dl; /* one more step onto the surface */
      if (!(t > ray->t_min) || !(t < ray->t_max)) return 0;
      for (int i = 0; i < 3; ++i) p[i] = ray->o[i] + t * ray->d[i];
      float h = 1e-4f * size, n[3];
      for (int i = 0; i < 3; ++i) {
        float a[3] = {p[0], p[1], p[2]}, b[3] = {p[0], p[1], p[2]};
        a[i] += h;
        b[i] -= h;
        n[i] = f(args, a) - f(args, b);
      }
      hit->t = t;
      set_normal(hit, n[0], n[1], n[2]);
      hit->uv[0] = (p[0] - lo[0]) / (hi[0] - lo[0]);
      hit->uv[1] = (p[1] - lo[1]) / (hi[1] - lo[1]);
      return 1;
    }
    t += fmaxf(d, eps) / dl;
  }
  return 0;
}

static const sg_ext_param rbox_params[] = {
    {"size", SG_EXT_VEC3, {1.f, 1.f, 1.f}, 1e-6f, 1e6f, "edge lengths along x, y, z (centred at the origin)"},
    {"radius", SG_EXT_FLOAT, {0.1f}, 0.f, 1e6f, "radius of the rounded edges (at most half the smallest size)"},
};

static void rbox_bounds(const float* args, float lo[3], float hi[3]) {
  for (int i = 0; i < 3; ++i) { lo[i] = -0.5f * args[i]; hi[i] = 0.5f * args[i]; }
}

static int rbox_intersect(const float* args, const sg_ext_ray* ray, sg_ext_hit* hit) {
  float lo[3], hi[3], a[4] = {args[0], args[1], args[2], args[3]};
  float m = 0.5f * fminf(a[0], fminf(a[1], a[2]));
  if (a[3] > m) a[3] = m;
  rbox_bounds(a, lo, hi);
  return sdf_intersect(rbox_sdf, a, lo, hi, ray, hit);
}

static const sg_ext_param torus_params[] = {
    {"major_radius", SG_EXT_FLOAT, {1.f}, 1e-6f, 1e6f, "radius of the ring (around the y axis)"},
    {"minor_radius", SG_EXT_FLOAT, {0.25f}, 1e-6f, 1e6f, "radius of the tube"},
};

static void torus_bounds(const float* args, float lo[3], float hi[3]) {
  float r = args[0] + args[1];
  lo[0] = lo[2] = -r; hi[0] = hi[2] = r;
  lo[1] = -args[1]; hi[1] = args[1];
}

static int torus_intersect(const float* args, const sg_ext_ray* ray, sg_ext_hit* hit) {
  float lo[3], hi[3];
  torus_bounds(args, lo, hi);
  return sdf_intersect(torus_sdf, args, lo, hi, ray, hit);
}

static const sg_ext_shape shapes[] = {
    {"ext_sphere", "Sphere of a radius around the origin (analytic).", sphere_params, 1, sphere_bounds,
     sphere_intersect},
    {"rounded_box", "Box with rounded edges (signed distance, sphere tracing).", rbox_params, 2, rbox_bounds,
     rbox_intersect},
    {"torus", "Torus around the y axis (signed distance, sphere tracing).", torus_params, 2, torus_bounds,
     torus_intersect},
};

SG_EXT_EXPORT const sg_ext_library* synthgen_extension(void) {
  static const sg_ext_library lib = {SG_EXT_ABI_VERSION, 0, 0, shapes, 3};
  return &lib;
}
