// Texture "triplanar": box / triplanar mapping of another texture (usually an image) for
// models without usable uvs. The texture is looked up in three planar projections of the
// object-space (or world-space) position — (y, z), (x, z), (x, y) times `scale` — and blended
// by the normal's components: w_i = |n_i|^sharpness / sum_j |n_j|^sharpness.
//
// Parameters (defaults): texture (a texture reference, required); scale (1: repeats per unit
// of position); space "object" | "world" ("object"); sharpness (4; higher = crisper seams).
// Band-limited: each lookup is filtered over the surface footprint in projected uv units.
#include "texture/procedural.h"

namespace sg {

namespace {

class TriplanarTexture final : public Texture {
 public:
  TriplanarTexture(std::shared_ptr<Texture> tex, float scale, bool object_space, float sharpness)
      : m_tex(std::move(tex)), m_scale(scale), m_object(object_space), m_sharpness(sharpness) {}
  bool needs_position() const override { return true; }
  bool needs_uv_footprint() const override { return false; }
  Color eval_point(const TexturePoint& q) const override {
    Vec3f p = (m_object ? q.p_object : q.p_world) * m_scale;
    Vec3f n = m_object ? q.n_object : q.n_world;
    Vec3f w(std::pow(std::fabs(n.x), m_sharpness), std::pow(std::fabs(n.y), m_sharpness),
            std::pow(std::fabs(n.z), m_sharpness));
    float sum = w.x + w.y + w.z;
    if (!(sum > 0.f)) w = Vec3f(1.f / 3.f), sum = 1.f;
    w = w / sum;
    float fp = q.world_footprint * (m_object ? q.object_per_world : 1.f) * m_scale;
    auto look = [&](float u, float v) {
      TexturePoint t;
      t.uv = Vec2f(u, v);
      t.uv_footprint = fp;
      return m_tex->eval_point(t);
    };
    Color c(0.f);
    if (w.x > 1e-4f) c += look(p.z, p.y) * w.x;
    if (w.y > 1e-4f) c += look(p.x, p.z) * w.y;
    if (w.z > 1e-4f) c += look(p.x, p.y) * w.z;
    return c;
  }
  Color eval(const Vec2f& uv, float footprint) const override { return m_tex->eval(uv, footprint); }
  Color average() const override { return m_tex->average(); }

 private:
  std::shared_ptr<Texture> m_tex;
  float m_scale;
  bool m_object;
  float m_sharpness;
};

}  // namespace

namespace {

PluginInfo info() {
  return PluginInfo("texture", "triplanar",
                    "Box (triplanar) mapping of another texture for models without usable uvs: three planar "
                    "projections of the position blended by the normal, band-limited by the footprint.")
      .add(param::texture("texture", "the projected texture (usually an image)").require())
      .add(param::real("scale", 1.0, "repeats per unit of position").above(0))
      .add(param::choice("space", "object", {"object", "world"}, "coordinates of the projections"))
      .add(param::real("sharpness", 4.0, "blend exponent (higher: crisper seams)").in(1, 64));
}

std::shared_ptr<Texture> create(const Params& params, const PluginContext& ctx) {
  std::shared_ptr<Texture> tex = texture_param(params, "texture", ctx.textures);
  float scale = params.get_float("scale");
  std::string space = params.get_string("space");
  float sharp = params.get_float("sharpness");
  return std::make_shared<TriplanarTexture>(std::move(tex), scale, space == "object", sharp);
}

}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
