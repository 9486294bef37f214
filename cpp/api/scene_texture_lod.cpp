// Scene::estimate_texture_resolution: the texture resolution estimate of the scene's camera,
// per image texture (docs/texture_lod.md).
#include <algorithm>
#include <map>

#include "api/scene.h"
#include "core/error.h"
#include "texture/mipmap.h"

namespace sg {

std::vector<TextureResolution> Scene::estimate_texture_resolution(const TextureEstimateSettings& settings,
                                                                  TextureEstimate* raw) {
  if (!m_camera_set) throw Error("estimate_texture_resolution: no camera has been set");
  if (has_pending_edits()) commit();
  m_render_scene.camera = m_camera;
  TextureEstimate est = estimate_texture_footprints(m_render_scene, settings);
  std::vector<TextureResolution> out;
  std::map<const MipMap*, int> pyramids;
  for (size_t id = 0; id < m_textures.size(); ++id) {
    if (!m_textures[id] || !m_textures[id]->object) continue;
    const Texture& tex = *m_textures[id]->object;
    const MipMap* mip = tex.mipmap();
    if (!mip) continue;
    TextureResolution r;
    r.texture_id = uint32_t(id);
    const ParamSet& p = m_textures[id]->params;
    r.source = p.get_string("file", p.get_string("filename", p.get_string("source", m_textures[id]->type)));
    r.pyramid = pyramids.emplace(mip, int(pyramids.size())).first->second;
    r.width = mip->width(0);
    r.height = mip->height(0);
    r.channels = mip->channels();
    r.levels = mip->levels();
    r.alpha = mip->alpha() != nullptr;
    r.min_rho = k_inf;
    auto m = est.recorded.by_mip.find(mip);
    if (m != est.recorded.by_mip.end() && m->second.lookups > 0) {
      r.seen = true;
      r.lookups = m->second.lookups;
      r.needed_level = m->second.needed_level();
      r.min_rho = m->second.min_rho.empty() ? k_inf : m->second.min_rho[0];
    }
    auto t = est.recorded.by_texture.find(&tex);
    if (t != est.recorded.by_texture.end()) r.texture_level = t->second.needed_level();
    r.needed_width = mip->width(r.needed_level);
    r.needed_height = mip->height(r.needed_level);
    r.bytes_full = mip->bytes(0);
    r.bytes_needed = mip->bytes(r.needed_level);
    out.push_back(std::move(r));
  }
  if (raw) *raw = std::move(est);
  return out;
}

}  // namespace sg
