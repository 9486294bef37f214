// Texture "triplanar": box / triplanar mapping of another texture (usually an image) for
// models without usable uvs. The texture is looked up in three planar projections of the
// object-space (or world-space) position — (y, z), (x, z), (x, y) times `scale` — and blended
// by the normal's components: w_i = |n_i|^sharpness / sum_j |n_j|^sharpness.
//
// Parameters (defaults): texture (a texture reference, required); scale (1: repeats per unit
// of position); space "object" | "world" ("object"); sharpness (4; higher = crisper seams).
// Band-limited: each lookup is filtered over the surface footprint in projected uv units.
#include "texture/procedural.h"
#include "texture/texture_registry.h"

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

std::shared_ptr<Texture> create_triplanar_texture(const ParamSet& params, const TextureInputs& inputs) {
  TextureRef ref;
  if (!params.get_texture("texture", &ref)) throw Error("parameter 'texture': a texture reference is required");
  std::shared_ptr<Texture> tex = inputs ? inputs(ref.id) : nullptr;
  if (!tex) throw Error("parameter 'texture': texture " + std::to_string(ref.id) + " does not exist");
  float scale = params.get_float("scale", 1.f);
  if (!(scale > 0.f)) throw Error("parameter 'scale': must be positive");
  std::string space = params.get_string("space", "object");
  if (space != "object" && space != "world") throw Error("parameter 'space': must be object or world");
  float sharp = params.get_float("sharpness", 4.f);
  if (!(sharp >= 1.f && sharp <= 64.f)) throw Error("parameter 'sharpness': must lie in [1, 64]");
  return std::make_shared<TriplanarTexture>(std::move(tex), scale, space == "object", sharp);
}

}  // namespace sg
