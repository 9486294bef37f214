// Scene::load_mesh_file: turns an imported model into library objects.
#include <optional>
#include <sstream>

#include "api/scene.h"
#include "core/error.h"
#include "io/mesh_io.h"

namespace sg {

uint32_t Scene::add_embedded_texture(std::shared_ptr<ImageData> pixels, const Color& scale, const std::string& source) {
  uint32_t id = uint32_t(m_textures.size());
  ParamSet p;
  p.set("source", source);
  p.set("scale", std::vector<double>{scale.x, scale.y, scale.z});
  auto t = make_image_texture(*pixels, scale);
  m_textures.emplace_back(TextureEntry{"embedded_image", p, t, pixels, false});
  if (JournalOp* o = journal_op(JournalOp::Kind::AddTexture, id)) {
    o->type = "embedded_image";
    o->params = p;
    o->pixels = pixels;
  }
  return id;
}

ImportResult Scene::load_mesh_file(const std::string& path) {
  ImportedModel model = import_mesh_file_isolated(path);
  ImportResult result;
  result.removed_degenerate = model.removed_degenerate;
  std::vector<int32_t> remap(model.materials.size(), -1);
  // One texture per (image, colour space, scale); the pixels themselves are shared by every
  // texture naming the file through the scene's ImageCache (add_texture).
  auto make_texture = [&](const ImportedTexture& t, bool srgb, const Color& scale, const std::string& tag) {
    if (!t.embedded) {
      std::ostringstream key;
      key << ImageCache::resolve(t.path) << "|" << scale.x << "," << scale.y << "," << scale.z
          << (srgb ? "" : "|linear");
      auto it = m_image_cache.find(key.str());
      if (it != m_image_cache.end()) return it->second;
      ParamSet tp;
      tp.set("filename", t.path);
      tp.set("colorspace", std::string(srgb ? "srgb" : "linear"));
      tp.set("scale", std::vector<double>{scale.x, scale.y, scale.z});
      uint32_t tid = add_texture("image", tp);
      m_image_cache[key.str()] = tid;
      result.texture_ids.push_back(tid);
      return tid;
    }
    auto px = std::make_shared<ImageData>(t.pixels);
    if (srgb) {
      // Embedded images are 8-bit colour: decode sRGB here (not the alpha channel).
      int cc = std::min(px->channels, 3);
      for (size_t k = 0; k < size_t(px->width) * px->height; ++k)
        for (int c = 0; c < cc; ++c) {
          float& v = px->pixels[k * px->channels + c];
          v = v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
        }
    }
    uint32_t tid = add_embedded_texture(px, scale, path + "#" + tag);
    result.texture_ids.push_back(tid);
    return tid;
  };
  auto rgb = [](const Color& c) { return std::vector<double>{c.x, c.y, c.z}; };
  for (size_t i = 0; i < model.materials.size(); ++i) {
    const ImportedMaterial& im = model.materials[i];
    // Every imported material becomes "principled" (material/principled.cpp): glTF
    // metallic-roughness maps onto it one to one; OBJ/MTL through the mapping in mesh_io.
    ParamSet p;
    std::optional<uint32_t> base_tid;
    if (!im.texture_path.empty() || im.has_embedded_texture) {
      ImportedTexture bt;
      bt.path = im.texture_path;
      bt.embedded = im.has_embedded_texture;
      bt.pixels = im.embedded_texture;
      base_tid = make_texture(bt, true, im.base_color, im.name);
      p.set("base_color", TextureRef{*base_tid});
    } else {
      p.set("base_color", rgb(vmin(vmax(im.base_color, Color(0.f)), Color(1.f))));
    }
    auto clamp01 = [](float x) { return double(std::min(std::max(x, 0.f), 1.f)); };
    p.set("metallic", clamp01(im.metallic));
    p.set("roughness", clamp01(im.roughness));
    p.set("specular", clamp01(im.specular));
    if (im.transmission > 0.f) {
      p.set("transmission", clamp01(im.transmission));
      p.set("ior", double(std::min(std::max(im.ior, 1.01f), 3.f)));
    }
    if (im.clearcoat > 0.f) {
      p.set("clearcoat", clamp01(im.clearcoat));
      p.set("clearcoat_roughness", clamp01(im.clearcoat_roughness));
    }
    if (im.metallic_roughness.present())
      p.set("metallic_roughness", TextureRef{make_texture(im.metallic_roughness, false, Color(1.f), im.name + "#mr")});
    if (im.normal.present()) {
      p.set("normal_map", TextureRef{make_texture(im.normal, false, Color(1.f), im.name + "#normal")});
      p.set("normal_scale", double(std::min(std::max(im.normal_scale, -10.f), 10.f)));
    }
    Color emission = vmax(im.emission, Color(0.f));
    if (im.emissive.present()) {
      p.set("emission", TextureRef{make_texture(im.emissive, true, emission, im.name + "#emissive")});
      p.set("emission_strength", double(im.emission_strength));
    } else if (max_component(emission) > 0.f) {
      p.set("emission", rgb(emission));
      p.set("emission_strength", double(im.emission_strength));
    }
    // Coverage: glTF base colour alpha (factor x the base texture's alpha channel), or the
    // MTL d factor x map_d (its alpha channel, else its first channel). BLEND is rendered
    // as a cut-out at 0.5 (see principled's alpha_mode).
    p.set("alpha_mode", im.alpha_mode);
    if (im.alpha_mode != "opaque") {
      p.set("alpha_cutoff", clamp01(im.alpha_cutoff));
      p.set("alpha_factor", clamp01(im.alpha));
      if (im.opacity.present()) p.set("alpha", TextureRef{make_texture(im.opacity, false, Color(1.f), im.name + "#alpha")});
      else if (base_tid && m_textures[*base_tid] && m_textures[*base_tid]->object->has_alpha_channel())
        p.set("alpha", TextureRef{*base_tid});  // an RGB image without alpha: the factor alone
    }
    // NOTE: a purely Lambertian material (OBJ/MTL with Ks = 0 and nothing else: no metal,
    // specular, coat, transmission, normal map or cut-out) becomes the exact and much
    // cheaper "diffuse" (or "emissive" with that albedo): principled with specular 0 is the
    // same BSDF up to its roughness-dependent diffuse retro-reflection.
    bool plain = im.specular <= 0.f && im.metallic <= 0.f && im.transmission <= 0.f && im.clearcoat <= 0.f &&
                 !im.metallic_roughness.present() && !im.normal.present() && !im.emissive.present() &&
                 im.alpha_mode == "opaque";
    uint32_t mid;
    if (plain) {
      ParamSet d;
      if (base_tid) d.set("albedo", TextureRef{*base_tid});
      else d.set("albedo", rgb(vmin(vmax(im.base_color, Color(0.f)), Color(1.f))));
      if (max_component(emission) > 0.f) {
        d.set("radiance", rgb(emission * im.emission_strength));
        mid = add_material("emissive", d);
      } else {
        mid = add_material("diffuse", d);
      }
    } else {
      mid = add_material("principled", p);
    }
    remap[i] = int32_t(mid);
    result.material_ids.push_back(mid);
    result.material_names.push_back(im.name);
  }
  for (int32_t& id : model.mesh.material_ids) id = id >= 0 ? remap[size_t(id)] : -1;
  try {
    result.mesh_id = add_mesh(std::move(model.mesh));
  } catch (const Error& e) {
    throw FileError(path, e.what());
  }
  return result;
}

}  // namespace sg
