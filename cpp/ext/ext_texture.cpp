// Textures of user extensions (ext/extension.h): one C function per texture, called with the
// lookup's point, the texture's parameter block and synthgen's host functions.
#include <cmath>

#include "ext/extension.h"
#include "texture/procedural.h"
#include "texture/texture.h"

namespace sg {

namespace {

/// Arguments of at most this many floats are copied to the stack per lookup when texture
/// inputs must be written into them (64 parameters of 3 floats).
constexpr size_t k_max_block = 192;

void to_ext(const TexturePoint& q, sg_ext_point* e) {
  e->p[0] = q.p_world.x; e->p[1] = q.p_world.y; e->p[2] = q.p_world.z;
  e->n[0] = q.n_world.x; e->n[1] = q.n_world.y; e->n[2] = q.n_world.z;
  e->uv[0] = q.uv.x; e->uv[1] = q.uv.y;
  e->p_object[0] = q.p_object.x; e->p_object[1] = q.p_object.y; e->p_object[2] = q.p_object.z;
  e->n_object[0] = q.n_object.x; e->n_object[1] = q.n_object.y; e->n_object[2] = q.n_object.z;
  e->object_lo[0] = q.object_lo.x; e->object_lo[1] = q.object_lo.y; e->object_lo[2] = q.object_lo.z;
  e->object_hi[0] = q.object_hi.x; e->object_hi[1] = q.object_hi.y; e->object_hi[2] = q.object_hi.z;
  e->footprint = q.world_footprint;
  float fa = std::sqrt(std::max(q.uv_axis_a.x * q.uv_axis_a.x + q.uv_axis_a.y * q.uv_axis_a.y,
                                q.uv_axis_b.x * q.uv_axis_b.x + q.uv_axis_b.y * q.uv_axis_b.y));
  e->uv_footprint = std::max(q.uv_footprint, fa);
  e->object_per_world = q.object_per_world;
}

class ExtensionTexture final : public PointTexture {
 public:
  ExtensionTexture(const sg_ext_texture& decl, ExtensionArgs args, const std::string& source)
      : m_decl(decl), m_args(std::move(args)), m_host("extension texture '" + std::string(decl.name) + "' (" + source + ")") {
    m_uv_footprint = (decl.flags & SG_EXT_NEEDS_UV_FOOTPRINT) != 0;
    for (const auto& in : m_args.inputs) {
      m_uv_footprint = m_uv_footprint || in.texture->needs_uv_footprint();
      m_ao_radius = std::max(m_ao_radius, in.texture->ao_radius());
      m_ao_samples = std::max(m_ao_samples, in.texture->ao_samples());
      m_edge_radius = std::max(m_edge_radius, in.texture->edge_radius());
      m_edge_samples = std::max(m_edge_samples, in.texture->edge_samples());
    }
    // The mean over the relative unit cube and a 16-unit cube of positions (for light power
    // estimates and albedo priors only); a non-finite value fails here, at creation.
    m_average = estimate_average([&](const Vec3f& p) {
      TexturePoint q;
      q.p_world = q.p_object = p;
      q.uv = Vec2f(p.x, p.y);
      q.object_lo = Vec3f(0.f);
      q.object_hi = Vec3f(16.f);
      q.n_world = q.n_object = Vec3f(0.f, 1.f, 0.f);
      return eval_point(q);
    });
    std::string f = m_host.failure();
    if (!f.empty()) throw Error(f + " while estimating its average at creation");
  }

  bool needs_position() const override { return true; }
  bool needs_uv_footprint() const override { return m_uv_footprint; }
  float ao_radius() const override { return m_ao_radius; }
  int ao_samples() const override { return m_ao_samples; }
  float edge_radius() const override { return m_edge_radius; }
  int edge_samples() const override { return m_edge_samples; }
  std::string failure() const override { return m_host.failure(); }

  Color eval_point(const TexturePoint& q) const override {
    sg_ext_point e;
    to_ext(q, &e);
    float out[3] = {0.f, 0.f, 0.f};
    if (m_args.inputs.empty()) {
      m_decl.eval(&e, m_args.block.data(), m_host.host(), out);
    } else {
      float block[k_max_block];
      fill_block(q, block);
      m_decl.eval(&e, block, m_host.host(), out);
    }
    if (!m_host.check(out, m_decl.channels, e.p)) return Color(0.f);
    return m_decl.channels == 1 ? Color(out[0]) : Color(out[0], out[1], out[2]);
  }

  bool eval_gradient(const TexturePoint& q, Vec3f* grad, bool* world_space) const override {
    if (!m_decl.gradient) return false;
    sg_ext_point e;
    to_ext(q, &e);
    float g[3] = {0.f, 0.f, 0.f};
    int r;
    if (m_args.inputs.empty()) {
      r = m_decl.gradient(&e, m_args.block.data(), m_host.host(), g);
    } else {
      float block[k_max_block];
      fill_block(q, block);
      r = m_decl.gradient(&e, block, m_host.host(), g);
    }
    if (r != 1 && r != 2) return false;
    if (!m_host.check(g, 3, e.p)) return false;
    *grad = Vec3f(g[0], g[1], g[2]);
    *world_space = r == 2;
    return true;
  }

  Color average() const override { return m_average; }

 private:
  /// The parameter block with the texture inputs evaluated at q (Hydra's argument stack).
  void fill_block(const TexturePoint& q, float* block) const {
    std::copy(m_args.block.begin(), m_args.block.end(), block);
    for (const auto& in : m_args.inputs) {
      Color c = in.texture->eval_point(q);
      for (int k = 0; k < in.channels; ++k) block[in.offset + size_t(k)] = c[k];
    }
  }

  const sg_ext_texture& m_decl;
  ExtensionArgs m_args;
  ExtensionHost m_host;
  bool m_uv_footprint = false;
  float m_ao_radius = 0.f, m_edge_radius = 0.f;
  int m_ao_samples = 0, m_edge_samples = 0;
  Color m_average{0.f};
};

}  // namespace

std::shared_ptr<Texture> create_extension_texture(const Params& params, const PluginContext& ctx) {
  std::string source;
  const sg_ext_texture& decl = extension_texture(params.info().name, &source);
  ExtensionArgs args = extension_args(decl.params, decl.param_count, params, ctx.textures);
  if (args.block.size() > k_max_block) throw Error("too many parameter values (at most 192 floats)");
  return std::make_shared<ExtensionTexture>(decl, std::move(args), source);
}

}  // namespace sg
