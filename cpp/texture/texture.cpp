#include "texture/texture.h"

#include "texture/baked.h"

#include "core/error.h"

namespace sg {

std::shared_ptr<Texture> create_texture(const std::string& type, const ParamSet& params,
                                        const std::string& context, ImageCache* images,
                                        const TextureInputs& inputs) {
  PluginContext ctx{inputs, nullptr, images};
  std::shared_ptr<Texture> t = Registry::instance().create<Texture>("texture", type, params, ctx, context);
  // `bake: auto` (procedural textures with uv mapping, checked by the plugin): made bakeable.
  if (params.get_string("bake", "off") == "auto") return make_baked_texture(std::move(t));
  return t;
}

std::vector<std::string> texture_types() { return Registry::instance().names("texture"); }

std::shared_ptr<Texture> texture_param(const Params& p, const std::string& name, const TextureLookup& lookup) {
  TextureRef ref;
  if (!p.get_texture(name, &ref)) return nullptr;
  auto t = lookup ? lookup(ref.id) : nullptr;
  if (!t) throw Error("parameter '" + name + "': texture " + std::to_string(ref.id) + " does not exist");
  return t;
}

std::shared_ptr<Texture> color_texture_param(const Params& p, const std::string& name, const TextureLookup& lookup) {
  if (auto t = texture_param(p, name, lookup)) {
    const ParamDecl* d = p.info().find(name);
    Color avg = t->average();
    for (int c = 0; c < 3; ++c)
      if (d && !d->in_range(avg[c]))
        throw Error("parameter '" + name + "': components of the texture's average must lie in " + d->range_text() +
                    ", got " + format_number(avg[c]));
    return t;
  }
  return make_constant_texture(p.get_color(name));
}

}  // namespace sg
