// Texture "constant": the same value everywhere.
#include "core/error.h"
#include "texture/texture.h"

namespace sg {

class ConstantTexture final : public Texture {
 public:
  explicit ConstantTexture(const Color& v) : m_value(v) { set_constant(v); }
  Color eval(const Vec2f&, float) const override { return m_value; }
  Color average() const override { return m_value; }
  bool needs_uv_footprint() const override { return false; }

 private:
  Color m_value;
};

std::shared_ptr<Texture> make_constant_texture(const Color& value) {
  return std::make_shared<ConstantTexture>(value);
}

namespace {
PluginInfo info() {
  return PluginInfo("texture", "constant", "The same value everywhere.")
      .add(param::color("value", Color(1.f), "the constant colour"));
}
std::shared_ptr<Texture> create(const Params& p, const PluginContext&) { return make_constant_texture(p.get_color("value")); }
}  // namespace

SG_REGISTER_PLUGIN(Texture, info(), create)

}  // namespace sg
