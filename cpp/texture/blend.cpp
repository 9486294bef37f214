// Texture "blend": combines two inputs (colours or textures) with a blend operation, then
// optionally shapes the result like the procedural textures (remap, colour ramp). The
// building block of masks such as "rust where the noise is high, more at the bottom".
//
// Parameters (defaults): a, b: colour or texture reference (0, 0); op "mix" | "add" |
// "subtract" | "multiply" | "min" | "max" | "screen" | "difference" ("mix"); factor: number or
// texture (0.5; mix: (1 - f) a + f b; other ops: a op (f b)); shaping only when `remap` or a
// ramp is given: the first channel is remapped [lo, hi] -> [0, 1] (smooth, invert) and
// coloured by ramp_positions / ramp_colors (grey without).
#include <algorithm>

#include "texture/procedural.h"

namespace sg {

namespace {

enum class BlendOp { Mix, Add, Subtract, Multiply, Min, Max, Screen, Difference };

class BlendTexture final : public PointTexture {
 public:
  BlendTexture(std::shared_ptr<Texture> a, std::shared_ptr<Texture> b, std::shared_ptr<Texture> f, BlendOp op,
               bool shape, ProceduralShaping shaping)
      : m_a(std::move(a)), m_b(std::move(b)), m_f(std::move(f)), m_op(op), m_shape(shape),
        m_shaping(std::move(shaping)) {
    m_position = m_a->needs_position() || m_b->needs_position() || m_f->needs_position();
    if (m_a->is_constant() && m_b->is_constant() && m_f->is_constant())
      set_constant(combine(m_a->constant_value(), m_b->constant_value(), m_f->constant_value().x));
    // The average of a non-linear combination is estimated from the inputs' averages.
    m_average = combine(m_a->average(), m_b->average(), m_f->average().x);
  }

  Color combine(const Color& a, const Color& b, float f) const {
    Color r;
    switch (m_op) {
      case BlendOp::Mix: r = a * (1.f - f) + b * f; break;
      case BlendOp::Add: r = a + b * f; break;
      case BlendOp::Subtract: r = a - b * f; break;
      case BlendOp::Multiply: r = a * (b * f); break;
      case BlendOp::Min: r = vmin(a, b * f); break;
      case BlendOp::Max: r = vmax(a, b * f); break;
      case BlendOp::Screen: r = Color(1.f) - (Color(1.f) - a) * (Color(1.f) - b * f); break;
      case BlendOp::Difference: default: r = vabs(a - b * f); break;
    }
    return m_shape ? m_shaping.color(r.x) : r;
  }

  bool needs_position() const override { return m_position; }
  float ao_radius() const override { return std::max({m_a->ao_radius(), m_b->ao_radius(), m_f->ao_radius()}); }
  int ao_samples() const override { return std::max({m_a->ao_samples(), m_b->ao_samples(), m_f->ao_samples()}); }
  float edge_radius() const override {
    return std::max({m_a->edge_radius(), m_b->edge_radius(), m_f->edge_radius()});
  }
  int edge_samples() const override {
    return std::max({m_a->edge_samples(), m_b->edge_samples(), m_f->edge_samples()});
  }
  bool needs_uv_footprint() const override {
    return m_a->needs_uv_footprint() || m_b->needs_uv_footprint() || m_f->needs_uv_footprint();
  }
  Color eval_point(const TexturePoint& q) const override {
    // Constant inputs are read without a virtual call.
    return combine(m_a->is_constant() ? m_a->constant_value() : m_a->eval_point(q),
                   m_b->is_constant() ? m_b->constant_value() : m_b->eval_point(q),
                   (m_f->is_constant() ? m_f->constant_value() : m_f->eval_point(q)).x);
  }
  Color average() const override { return m_average; }

 private:
  std::shared_ptr<Texture> m_a, m_b, m_f;
  BlendOp m_op;
  bool m_shape;
  ProceduralShaping m_shaping;
  bool m_position = false;
  Color m_average;
};

const std::vector<std::pair<std::string, BlendOp>> k_ops = {
    {"mix", BlendOp::Mix}, {"add", BlendOp::Add}, {"subtract", BlendOp::Subtract}, {"multiply", BlendOp::Multiply},
    {"min", BlendOp::Min}, {"max", BlendOp::Max}, {"screen", BlendOp::Screen}, {"difference", BlendOp::Difference}};

PluginInfo info() {
  std::vector<std::string> ops;
  for (const auto& o : k_ops) ops.push_back(o.first);
  PluginInfo i("texture", "blend",
               "Combines two inputs (colours or textures) with a blend operation, then optionally shapes the "
               "result like the procedural textures (only when `remap` or a ramp is given: the first channel is "
               "remapped and coloured).");
  i.add(param::color_texture("a", Color(0.f), "first input"))
      .add(param::color_texture("b", Color(0.f), "second input"))
      .add(param::choice("op", "mix", ops, "mix: (1 - f) a + f b; the others: a op (f b)"))
      .add(param::color_texture("factor", Color(0.5f), "blend factor f (a number, colour or texture)"));
  ProceduralShaping::declare(i, Vec2f(0.f, 1.f));
  return i;
}

std::shared_ptr<Texture> create(const Params& params, const PluginContext& ctx) {
  auto a = color_texture_param(params, "a", ctx.textures);
  auto b = color_texture_param(params, "b", ctx.textures);
  auto f = color_texture_param(params, "factor", ctx.textures);
  std::string name = params.get_string("op");
  BlendOp op = BlendOp::Mix;
  for (const auto& o : k_ops)
    if (o.first == name) op = o.second;
  // Shaping applies when any of its parameters is given (e.g. `invert` alone inverts the
  // blended value over the default remap [0, 1]).
  bool shape = params.has("remap") || params.has("ramp_positions") || params.has("smooth") || params.has("invert");
  ProceduralShaping shaping;
  if (shape) shaping = ProceduralShaping::from_params(params, Vec2f(0.f, 1.f));
  return std::make_shared<BlendTexture>(std::move(a), std::move(b), std::move(f), op, shape, std::move(shaping));
}

}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
