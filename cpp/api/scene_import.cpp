// Scene::load_mesh_file: turns an imported model into library objects.
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
  m_textures.emplace_back(TextureEntry{"embedded_image", p, t, pixels});
  return id;
}

ImportResult Scene::load_mesh_file(const std::string& path) {
  ImportedModel model = import_mesh_file(path);
  ImportResult result;
  result.removed_degenerate = model.removed_degenerate;
  std::vector<int32_t> remap(model.materials.size(), -1);
  for (size_t i = 0; i < model.materials.size(); ++i) {
    const ImportedMaterial& im = model.materials[i];
    ParamSet p;
    if (!im.texture_path.empty() || im.has_embedded_texture) {
      uint32_t tid;
      std::ostringstream key;
      // One texture per (image, base colour factor); the pixels themselves are shared by
      // every texture naming the file through the scene's ImageCache (add_texture).
      if (!im.texture_path.empty()) key << ImageCache::resolve(im.texture_path);
      key << "|" << im.base_color.x << "," << im.base_color.y << "," << im.base_color.z;
      if (!im.texture_path.empty() && m_image_cache.count(key.str())) {
        tid = m_image_cache[key.str()];
      } else if (!im.texture_path.empty()) {
        ParamSet tp;
        tp.set("filename", im.texture_path);
        tp.set("colorspace", std::string("srgb"));
        tp.set("scale", std::vector<double>{im.base_color.x, im.base_color.y, im.base_color.z});
        tid = add_texture("image", tp);
        m_image_cache[key.str()] = tid;
        result.texture_ids.push_back(tid);
      } else {
        // Embedded images are 8-bit colour: decode sRGB here.
        auto px = std::make_shared<ImageData>(im.embedded_texture);
        int cc = std::min(px->channels, 3);
        for (size_t k = 0; k < size_t(px->width) * px->height; ++k)
          for (int c = 0; c < cc; ++c) {
            float& v = px->pixels[k * px->channels + c];
            v = v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
          }
        tid = add_embedded_texture(px, im.base_color, path + "#" + im.name);
        result.texture_ids.push_back(tid);
      }
      p.set("albedo", TextureRef{tid});
    } else {
      Color c = vmin(vmax(im.base_color, Color(0.f)), Color(1.f));
      p.set("albedo", std::vector<double>{c.x, c.y, c.z});
    }
    uint32_t mid;
    if (max_component(im.emission) > 0.f) {
      p.set("radiance", std::vector<double>{im.emission.x, im.emission.y, im.emission.z});
      mid = add_material("emissive", p);
    } else {
      mid = add_material("diffuse", p);
    }
    remap[i] = int32_t(mid);
    result.material_ids.push_back(mid);
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
