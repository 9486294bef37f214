// Scene::estimate_texture_resolution: the texture resolution estimate of the scene's camera,
// per image texture (docs/texture_lod.md).
#include <algorithm>
#include <chrono>
#include <map>
#include <set>

#include "api/scene.h"
#include "core/error.h"
#include "texture/baked.h"
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
    std::vector<uint8_t> tiles;
    if (m != est.recorded.by_mip.end() && m->second.lookups > 0) {
      r.seen = true;
      r.lookups = m->second.lookups;
      r.needed_level = m->second.needed_level();
      r.min_rho = m->second.min_rho.empty() ? k_inf : m->second.min_rho[0];
      tiles = m->second.tiles(*mip, r.needed_level);
    }
    r.tiles = mip->tiles_x(r.needed_level) * mip->tiles_y(r.needed_level);
    r.needed_tiles = r.seen ? int(std::count(tiles.begin(), tiles.end(), uint8_t(1))) : r.tiles;
    auto t = est.recorded.by_texture.find(&tex);
    if (t != est.recorded.by_texture.end()) r.texture_level = t->second.needed_level();
    r.needed_width = mip->width(r.needed_level);
    r.needed_height = mip->height(r.needed_level);
    r.bytes_full = mip->bytes(0);
    r.bytes_needed = r.needed_level < mip->tail_level() ? mip->bytes(r.needed_level, tiles) : mip->bytes(r.needed_level);
    r.first_resident = mip->first_resident();
    r.first_used = mip->first_used();
    r.tail_level = mip->tail_level();
    r.bytes_resident = mip->resident_bytes();
    out.push_back(std::move(r));
  }
  if (raw) *raw = std::move(est);
  return out;
}

void Scene::set_texture_levels(const std::vector<std::pair<uint32_t, int>>& texture_levels) {
  std::map<const MipMap*, int> level;
  for (const auto& [id, l] : texture_levels) {
    if (id >= m_textures.size() || !m_textures[id] || !m_textures[id]->object)
      throw Error("texture " + std::to_string(id) + " does not exist");
    const MipMap* mip = m_textures[id]->object->mipmap();
    if (!mip) throw Error("texture " + std::to_string(id) + ": not an image texture (it has no mip levels)");
    auto it = level.emplace(mip, l).first;
    it->second = std::min(it->second, l);
  }
  for (const auto& [mip, l] : level) mip->make_resident(l);
}

void Scene::use_every_texture_level() {
  for (const auto& e : m_textures)
    if (e && e->object) {
      if (const MipMap* mip = e->object->mipmap()) mip->use_levels(0);
      // Without texture_lod, bakeable textures are evaluated (docs/texture_lod.md).
      if (const auto* baked = dynamic_cast<const BakedTexture*>(e->object.get())) baked->clear();
    }
}

void Scene::texture_memory(uint64_t* full, uint64_t* resident) const {
  std::set<const MipMap*> seen;
  *full = *resident = 0;
  for (const auto& e : m_textures)
    if (e && e->object)
      if (const MipMap* mip = e->object->mipmap(); mip && seen.insert(mip).second) {
        *full += mip->bytes(0);
        *resident += mip->resident_bytes();
      }
}

void Scene::apply_texture_lod(const RenderSettings& settings, RenderStats* stats) {
  auto t0 = std::chrono::steady_clock::now();
  TextureEstimateSettings es;
  es.threads = settings.threads;
  TextureEstimate est;
  std::vector<TextureResolution> res = estimate_texture_resolution(es, &est);
  const uint64_t now = ++m_texture_lod_count;
  // Lookups read the estimate's level (the margin finer) of a seen pyramid, in the tiles its
  // lookups fell in, and the tail of an unseen one, whatever is in memory: the image depends
  // on this frame alone, never on what a worker rendered before (determinism across worker
  // counts).
  std::map<const MipMap*, int> level;
  for (const TextureResolution& r : res) {
    const MipMap* mip = m_textures[r.texture_id]->object->mipmap();
    auto it = level.emplace(mip, r.tail_level).first;
    if (r.seen) it->second = std::min(it->second, std::max(0, r.needed_level - int(settings.texture_lod_margin)));
    if (r.seen) m_pyramid_last_seen[mip] = now;
  }
  // Bakeable procedural textures (bake: auto): an image for this frame's camera, or none.
  for (const auto& e : m_textures)
    if (e && e->object)
      if (const auto* baked = dynamic_cast<const BakedTexture*>(e->object.get())) {
        auto u = est.recorded.by_uv.find(baked);
        if (u == est.recorded.by_uv.end()) baked->clear();
        else if (baked->bake(u->second, int(settings.threads))) stats->texture_baked_bytes += baked->bytes();
      }
  for (const auto& [mip, l] : level) {
    auto m = est.recorded.by_mip.find(mip);
    if (m != est.recorded.by_mip.end() && m->second.lookups > 0) mip->use_tiles(l, m->second.tiles(*mip, l));
    else mip->use_levels(l);
  }
  // Forget pyramids no texture holds any more (their addresses may be reused).
  for (auto it = m_pyramid_last_seen.begin(); it != m_pyramid_last_seen.end();)
    it = level.count(it->first) ? std::next(it) : m_pyramid_last_seen.erase(it);
  // Levels finer than those used stay in memory (the next frames may need them) while the
  // texture memory fits the budget; beyond it they are freed, least recently seen pyramid
  // first (never seen: first of all; ties in address order, which changes no image).
  std::vector<std::pair<uint64_t, const MipMap*>> order;
  for (const auto& [mip, l] : level) {
    auto it = m_pyramid_last_seen.find(mip);
    order.emplace_back(it == m_pyramid_last_seen.end() ? 0 : it->second, mip);
  }
  std::sort(order.begin(), order.end());
  uint64_t full = 0, resident = 0;
  texture_memory(&full, &resident);
  const double budget = double(settings.texture_budget_mib) * 1024.0 * 1024.0;
  for (const auto& [last, mip] : order) {
    if (double(resident) <= budget) break;
    uint64_t before = mip->resident_bytes();
    mip->drop_unused();
    resident -= before - mip->resident_bytes();
  }
  stats->texture_lod_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace sg
