// Texture "projector": projective texture mapping. A pinhole projector (a pose and
// intrinsics, like a camera) projects another texture (an image or a procedural one) onto
// whatever it faces, for models with no or unusable uvs: decals, stickers, graffiti, stripes.
//
// Parameters (defaults):
//   texture            the projected texture (a texture reference; required)
//   world_from_projector  16 numbers, row-major 4x4 (the projector looks along its +z, x right,
//                      y down: the OpenCV convention of PinholeCamera) ...
//   position, look_at, up ... or a position looking at a point (up [0, 1, 0])
//   fov                vertical field of view in degrees (40) ... or fx, fy, cx, cy in pixels
//   width, height      the projected image's size in pixels (1, 1: only the aspect and fx
//                      matter); pixel (x, y) maps to texture uv (x / width, 1 - y / height),
//                      so image row 0 lands at the top of the projection
//   space              "world" or "object" (the projector moves with each object) ("world")
//   output             "color": the texture inside the frustum, `outside` elsewhere; "mask":
//                      1 inside the frustum, 0 outside (a mix weight) ("color")
//   outside            colour outside the frustum (0)
//   depth_map          optional occlusion test: a texture holding, for each projected
//                      pixel, the projector-space depth (z) of the first surface seen from the
//                      projector (a shadow map, e.g. a label-only render from the projector's
//                      pose: synthgen.wear.decal makes it); points farther than that by more
//                      than `depth_bias` (0.01 m + 1%) are occluded: outside the projection
//   facing             only surfaces whose shading normal faces the projector are inside
//                      (false): a cheap occlusion test that keeps the projection off the
//                      far side of an object (exact for convex parts; needs outward normals)
// Band-limited: the projected texture is looked up with the footprint the surface footprint
// covers in the projected image.
// Without a depth_map, surfaces behind others (seen from the projector) are projected onto too
// (with `facing`, only those that face the projector).
#include <array>

#include "texture/procedural.h"

namespace sg {

namespace {

class ProjectorTexture final : public PointTexture {
 public:
  ProjectorTexture(std::shared_ptr<Texture> tex, const Transform& world_from_projector, float fx, float fy, float cx,
                   float cy, float width, float height, bool object_space, bool mask, const Color& outside,
                   std::shared_ptr<Texture> depth_map, float depth_bias, bool facing)
      : m_tex(std::move(tex)), m_T(world_from_projector), m_fx(fx), m_fy(fy), m_cx(cx), m_cy(cy), m_w(width),
        m_h(height), m_object(object_space), m_mask(mask), m_outside(outside), m_depth(std::move(depth_map)),
        m_bias(depth_bias), m_facing(facing), m_eye(world_from_projector.apply_point(Vec3f(0.f))) {}

  bool needs_position() const override { return true; }
  bool needs_uv_footprint() const override { return false; }

  /// Projected texture coordinates of point p (in the projector's space); false outside the
  /// frustum. `depth` receives the distance along the projector's axis.
  bool project(const Vec3f& p, Vec2f* uv, float* depth) const {
    Vec3f q = m_T.apply_inverse_point(p);
    if (!(q.z > 0.f)) return false;
    float x = m_fx * q.x / q.z + m_cx, y = m_fy * q.y / q.z + m_cy;
    if (!(x >= 0.f && x <= m_w && y >= 0.f && y <= m_h)) return false;
    *uv = Vec2f(x / m_w, 1.f - y / m_h);
    *depth = q.z;
    if (m_depth) {
      // NOTE: shadow-map test (Williams 1978, "Casting Curved Shadows on Curved Surfaces"),
      // point-sampled, with a constant plus relative bias against self-occlusion.
      float d = m_depth->eval(*uv, 0.f).x;
      if (q.z > d + m_bias + 0.01f * d) return false;
    }
    return true;
  }

  Color eval_point(const TexturePoint& qp) const override {
    Vec2f uv;
    float z;
    Vec3f p = m_object ? qp.p_object : qp.p_world;
    bool inside = project(p, &uv, &z) && (!m_facing || dot(m_object ? qp.n_object : qp.n_world, m_eye - p) > 0.f);
    if (!inside) return m_mask ? Color(0.f) : m_outside;
    if (m_mask) return Color(1.f);
    // NOTE: a surface footprint of width f at projector depth z covers f fx / (z width) of
    // the projected image's uv range (isotropic; pbrt-v4's projection texture mapping
    // differentiates the same mapping).
    float f = qp.world_footprint * (m_object ? qp.object_per_world : 1.f);
    TexturePoint t;
    t.uv = uv;
    t.uv_footprint = f * std::max(m_fx / m_w, m_fy / m_h) / z;
    return m_tex->eval_point(t);
  }
  bool has_alpha_channel() const override { return true; }
  float eval_alpha(const Vec2f&, float) const override { return 1.f; }
  Color average() const override { return m_mask ? Color(0.5f) : m_tex->average() * 0.5f + m_outside * 0.5f; }

 private:
  std::shared_ptr<Texture> m_tex;
  Transform m_T;
  float m_fx, m_fy, m_cx, m_cy, m_w, m_h;
  bool m_object, m_mask;
  Color m_outside;
  std::shared_ptr<Texture> m_depth;
  float m_bias;
  bool m_facing;
  Vec3f m_eye;  ///< the projector's centre (in its space: world or object)
};

}  // namespace

namespace {

PluginInfo info() {
  return PluginInfo("texture", "projector",
                    "Projective texture mapping: a pinhole projector (a pose and intrinsics, like a camera) "
                    "projects another texture onto whatever it faces: decals, stickers, graffiti, stripes.")
      .add(param::texture("texture", "the projected texture (an image or a procedural one)").require())
      .add(param::matrix4("world_from_projector",
                          "projector pose, row-major 4x4 (looks along +z, x right, y down: OpenCV)"))
      .add(param::vec3("position", "projector position (with look_at and up, instead of world_from_projector)"))
      .add(param::vec3("look_at", Vec3f(0.f, 0.f, 1.f), "point the projector looks at"))
      .add(param::vec3("up", Vec3f(0.f, 1.f, 0.f), "up direction of the projected image"))
      .add(param::real("fov", 40.0, "vertical field of view in degrees").above(0).below(179))
      .add(param::real("fx", "focal length in pixels (instead of fov)").above(0))
      .add(param::real("fy", "focal length along y in pixels").above(0).default_is("fx"))
      .add(param::real("cx", "principal point x in pixels").default_is("width / 2"))
      .add(param::real("cy", "principal point y in pixels").default_is("height / 2"))
      .add(param::real("width", 1.0, "projected image width in pixels (with fov only the aspect matters)").above(0))
      .add(param::real("height", 1.0, "projected image height in pixels").above(0))
      .add(param::choice("space", "world", {"world", "object"}, "object: the projector moves with each object"))
      .add(param::choice("output", "color", {"color", "mask"},
                         "color: the texture inside the frustum, `outside` elsewhere; mask: 1 inside, 0 outside"))
      .add(param::color("outside", Color(0.f), "colour outside the frustum"))
      .add(param::texture("depth_map", "shadow map: projector-space depth of the first surface per projected pixel"))
      .add(param::real("depth_bias", 0.01, "occlusion tolerance in metres (+1% of the depth)").at_least(0))
      .add(param::boolean("facing", false, "only surfaces whose normal faces the projector are inside"))
      .exactly_one_of({"world_from_projector", "position"})
      .exclusive_of({"world_from_projector"}, {"look_at", "up"})
      .exclusive_of({"fov"}, {"fx", "fy", "cx", "cy"})
      .requires_all("fy", {"fx"})
      .requires_all("cx", {"fx"})
      .requires_all("cy", {"fx"});
}

std::shared_ptr<Texture> create(const Params& params, const PluginContext& ctx) {
  std::shared_ptr<Texture> tex = texture_param(params, "texture", ctx.textures);
  Transform T;
  if (params.has("world_from_projector")) {
    std::vector<float> m = params.get_floats("world_from_projector");
    T = Transform::from_row_major(m.data(), "world_from_projector");
  } else {
    Vec3f eye = params.get_vec3("position"), at = params.get_vec3("look_at");
    Vec3f up = params.get_vec3("up");
    Vec3f z = at - eye;
    if (!(length(z) > 0.f)) throw Error("parameters 'position' and 'look_at' must differ");
    z = normalize(z);
    Vec3f x = cross(z, up);  // as PinholeCamera::look_at: x right, y = z x x down
    if (!(length(x) > 1e-6f)) throw Error("parameter 'up' is parallel to the viewing direction");
    x = normalize(x);
    Vec3f y = cross(z, x);
    float m[16] = {x.x, y.x, z.x, eye.x, x.y, y.y, z.y, eye.y, x.z, y.z, z.z, eye.z, 0, 0, 0, 1};
    T = Transform::from_row_major(m, "projector look_at");
  }
  float w = params.get_float("width"), h = params.get_float("height");
  float fx, fy, cx, cy;
  if (params.has("fx")) {
    fx = params.get_float("fx");
    fy = params.get_float_or("fy", fx);
    cx = params.get_float_or("cx", 0.5f * w);
    cy = params.get_float_or("cy", 0.5f * h);
  } else {
    float fov = params.get_float("fov");
    fy = fx = 0.5f * h / std::tan(0.5f * fov * k_pi / 180.f);
    cx = 0.5f * w;
    cy = 0.5f * h;
  }
  std::string space = params.get_string("space");
  std::string output = params.get_string("output");
  Color outside = params.get_color("outside");
  std::shared_ptr<Texture> depth = texture_param(params, "depth_map", ctx.textures);
  float bias = params.get_float("depth_bias");
  bool facing = params.get_bool("facing");
  return std::make_shared<ProjectorTexture>(std::move(tex), T, fx, fy, cx, cy, w, h, space == "object",
                                            output == "mask", outside, std::move(depth), bias, facing);
}

}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
