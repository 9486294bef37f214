// The integration API: typed object libraries with stable integer ids.
//
// Designed after HydraAPI: meshes, textures, materials, instances and lights live
// in libraries; `add_*` returns a stable id (never reused), `update_*` / `set_*`
// edit an object. Edits accumulate and `commit()` applies only what changed: only
// new or edited meshes get a new BVH; moving, relabelling or re-materialing an
// instance touches only the top-level BVH. `render()` commits pending edits first.
// `save()` writes the whole scene (XML + binary mesh data) and `load()` replays it.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "api/journal.h"
#include "camera/camera.h"
#include "core/error.h"
#include "core/params.h"
#include "film/film.h"
#include "geometry/accel.h"
#include "geometry/mesh.h"
#include "io/image_io.h"
#include "integrator/path_tracer.h"
#include "integrator/render_scene.h"
#include "integrator/texture_estimate.h"
#include "light/light.h"
#include "medium/medium.h"
#include "material/material.h"
#include "texture/image_cache.h"
#include "texture/texture.h"

namespace sg {

/// What the texture resolution estimate (integrator/texture_estimate.h) found for one image
/// texture of the scene; Scene::estimate_texture_resolution. Textures sharing a pyramid (one
/// file under several uv transforms) share `pyramid` and its figures.
struct TextureResolution {
  uint32_t texture_id = 0;
  std::string source;  ///< the file (a "memory:" key for in-memory pixels)
  int pyramid = 0;     ///< index of the distinct pyramid among the results
  int width = 0, height = 0, channels = 0, levels = 0;
  bool alpha = false;
  bool seen = false;        ///< the pyramid was looked up by the estimate
  uint64_t lookups = 0;     ///< lookups of the pyramid
  int needed_level = 0;     ///< the pyramid's coarsest level keeping >= 1 texel per pixel (0 unseen)
  int needed_width = 0, needed_height = 0;
  int texture_level = 0;    ///< the same for this texture's own lookups (its uv transform)
  float min_rho = 0.f;      ///< smallest footprint of a lookup in level-0 texels (inf unseen)
  uint64_t bytes_full = 0;  ///< the pyramid's texel memory, every level
  uint64_t bytes_needed = 0;  ///< levels needed_level (its needed tiles) and coarser
  int tiles = 0;              ///< tiles of level needed_level (MipMap::k_tile texels on a side)
  int needed_tiles = 0;       ///< of those, the ones a lookup falls in (the others stay on disk)
  int first_resident = 0;     ///< the pyramid's finest level in memory now
  int first_used = 0;         ///< the pyramid's finest level lookups read now
  int tail_level = 0;         ///< the finest level that always stays resident
  uint64_t bytes_resident = 0;  ///< the pyramid's texel memory now (levels and tiles in memory)
};

/// What a file import produced.
struct ImportResult {
  uint32_t mesh_id = 0;
  std::vector<uint32_t> material_ids;  ///< materials created from the file's materials
  std::vector<std::string> material_names;  ///< the file's name of each (same order)
  std::vector<uint32_t> texture_ids;   ///< textures created (one per distinct image)
  size_t removed_degenerate = 0;       ///< zero-area triangles dropped on import
};

struct CommitStats {
  uint64_t mesh_bvh_builds = 0;        ///< total since the scene was created
  uint64_t mesh_bvh_builds_last_commit = 0;   ///< during the last commit
  uint64_t top_level_builds = 0;
  uint64_t commits = 0;
  uint64_t alpha_tested_meshes = 0;    ///< meshes traversed with the alpha test (cut-outs)
};

/// A slot of the scene's textures or materials: its entry on the heap, so that a removed one
/// leaves an empty pointer behind instead of the entry's storage. A dataset run adds and removes
/// dozens a frame (signs, plates, wear) and slots are never reused (ids stay unique): kept inline
/// (std::optional, 176 bytes each) they grew a worker by about 8 kB a frame
/// (bench/memory_soak.py). The interface is std::optional's, as far as the scene uses it.
template <class T>
class Slot {
 public:
  Slot() = default;
  Slot(T&& value) : m_entry(std::make_unique<T>(std::move(value))) {}  // NOLINT: as optional's
  Slot(const Slot& other) : m_entry(other.m_entry ? std::make_unique<T>(*other.m_entry) : nullptr) {}
  Slot(Slot&&) noexcept = default;
  Slot& operator=(const Slot& other) {
    m_entry = other.m_entry ? std::make_unique<T>(*other.m_entry) : nullptr;
    return *this;
  }
  Slot& operator=(Slot&&) noexcept = default;
  bool has_value() const { return m_entry != nullptr; }
  explicit operator bool() const { return m_entry != nullptr; }
  T& operator*() { return *m_entry; }
  const T& operator*() const { return *m_entry; }
  T* operator->() { return m_entry.get(); }
  const T* operator->() const { return m_entry.get(); }
  void reset() { m_entry.reset(); }

 private:
  std::unique_ptr<T> m_entry;
};

class Scene {
 public:
  Scene();
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // Meshes ---------------------------------------------------------------------------
  /// Adds a validated mesh; throws sg::Error on bad data.
  uint32_t add_mesh(TriangleMesh mesh);
  void update_mesh(uint32_t id, TriangleMesh mesh);
  void remove_mesh(uint32_t id);
  const TriangleMesh& mesh(uint32_t id) const;
  /// A user shape (a "shape" plugin of a loaded extension, ext/extension.h) in the mesh
  /// library: instanced, labelled, shadowed and lit like a mesh (it does not emit as a light
  /// source: emissive materials on it are seen, not sampled). Throws sg::Error for an unknown
  /// shape or bad parameters.
  uint32_t add_shape(const std::string& type, const ParamSet& params);
  /// Imports OBJ (+MTL), PLY, glTF 2.0 / GLB via assimp, flattening node transforms into
  /// one mesh with per-triangle materials ("principled": glTF metallic-roughness, OBJ/MTL
  /// mapped, textures resolved relative to the file). Throws sg::FileError naming the file.
  ImportResult load_mesh_file(const std::string& path);

  // Textures -------------------------------------------------------------------------
  uint32_t add_texture(const std::string& type, const ParamSet& params);
  /// Texture from decoded linear pixels (embedded images of GLB files); `scale` multiplies.
  uint32_t add_embedded_texture(std::shared_ptr<ImageData> pixels, const Color& scale, const std::string& source);
  /// Texture "image" of pixels held in memory instead of a file (generated plates, signs,
  /// decals, shadow maps): `params` are the image plugin's without `filename` (colorspace,
  /// wrap, scale, uv transform). `integer_source`: the values came from 8/16-bit integers
  /// (colorspace auto then decodes sRGB, as for such files). Identical pixels share one
  /// mip pyramid (the image cache keys them by content); they are saved with the scene.
  uint32_t add_image_texture(std::shared_ptr<ImageData> pixels, bool integer_source, const ParamSet& params);

  // Materials ------------------------------------------------------------------------
  uint32_t add_material(const std::string& type, const ParamSet& params);
  void update_material(uint32_t id, const std::string& type, const ParamSet& params);

  // Instances ------------------------------------------------------------------------
  /// `instance_id` defaults to (instance handle + 1); `material_id` < 0 keeps the
  /// mesh's per-triangle materials (or the default grey diffuse).
  uint32_t add_instance(uint32_t mesh_id, const Transform& world_from_object, uint32_t class_id = 0,
                        std::optional<uint32_t> instance_id = std::nullopt, int64_t material_id = -1);
  void set_instance_transform(uint32_t id, const Transform& world_from_object);
  void set_instance_labels(uint32_t id, uint32_t class_id, uint32_t instance_id);
  void set_instance_material(uint32_t id, int64_t material_id);
  /// Replaces, for this instance only, the materials of its mesh's triangles: a triangle whose
  /// mesh material id is a key of `map` uses the mapped material instead (key -1: triangles
  /// without a material). HydraAPI's per-instance remap lists: wear or decals can wrap each
  /// material of a multi-material model without copying the mesh. An instance material
  /// override (set_instance_material >= 0) takes precedence. An empty map removes it.
  void set_instance_material_map(uint32_t id, const std::vector<std::pair<int32_t, int64_t>>& map);
  const std::vector<std::pair<int32_t, int64_t>>& instance_material_map(uint32_t id) const;
  /// Points an instance at another mesh (no BVH build: the mesh's BVH exists; only the top
  /// level is rebuilt). Lets a caller keep a fixed pool of instance ids across frames.
  void set_instance_mesh(uint32_t id, uint32_t mesh_id);
  void remove_instance(uint32_t id);
  /// Hides an instance from every ray (camera, shadow, labels) and from light sampling
  /// without removing it: showing it again needs no BVH build (only the top level). Used for
  /// amodal masks (one object rendered alone) and by randomizers that toggle objects.
  void set_instance_visible(uint32_t id, bool visible);
  bool instance_visible(uint32_t id) const;
  /// Makes an instance a shadow catcher: a stand-in of a photo's world (its ground, proxy
  /// geometry) into which the other instances are inserted. When a scene has catchers, render()
  /// also estimates, with the same samples, the radiance of the scene without the other
  /// instances (differential rendering; Film::differential): what photo compositing needs
  /// (synthgen.post.composite). Give catchers labels 0: they are the photo's, never labelled.
  void set_instance_catcher(uint32_t id, bool catcher);
  bool instance_catcher(uint32_t id) const;
  size_t instance_count() const;
  /// Live (not removed) textures and materials: for tools checking that a long run keeps
  /// its libraries bounded.
  size_t texture_count() const;
  size_t material_count() const;

  // Lights ---------------------------------------------------------------------------
  uint32_t add_light(const std::string& type, const ParamSet& params);
  void update_light(uint32_t id, const std::string& type, const ParamSet& params);
  void remove_light(uint32_t id);
  /// Removes a texture / material from the library (its id becomes a hole). Refused while
  /// another texture or material refers to it (or, for materials, an instance or a mesh's
  /// per-triangle ids), so a saved scene always replays. Lets long runs that create
  /// per-frame textures and materials (wear masks, generated plates) keep the library bounded.
  void remove_texture(uint32_t id);
  void remove_material(uint32_t id);

  // Medium ---------------------------------------------------------------------------
  /// The scene's global participating medium (fog, haze: medium/medium.h), replacing any;
  /// clear_medium() removes it. Labels never see it (they are the camera ray's first hit).
  void set_medium(const std::string& type, const ParamSet& params);
  void clear_medium();
  struct MediumEntry { std::string type; ParamSet params; std::shared_ptr<Medium> object; };
  const std::optional<MediumEntry>& medium() const { return m_medium; }
  /// Per pixel (row-major, the camera's size), the medium's transmittance along the ray through
  /// the pixel centre up to `distance` (the render's distance label; inf: the whole ray). All 1
  /// without a medium. For labels: how much of an object the fog lets through.
  std::vector<float> camera_transmittance(const std::vector<float>& distance) const;

  // Camera ---------------------------------------------------------------------------
  void set_camera(const PinholeCamera& camera);
  const PinholeCamera& camera() const { return m_camera; }

  // Commit and render ----------------------------------------------------------------
  void commit();
  bool has_pending_edits() const;
  const CommitStats& commit_stats() const { return m_stats; }
  /// The committed view that the integrator renders (after commit()): lights and their
  /// selection distribution, instance records. For tests and tools.
  const RenderScene& render_scene() const { return m_render_scene; }
  /// The scene's texture cache: each image file is decoded once per (path, colour space).
  const ImageCache& image_cache() const { return m_images; }
  /// Renders with the current camera (committing pending edits first). Thread-safe
  /// with respect to the GIL: touches no Python objects.
  void render(const RenderSettings& settings, Film* film);

  /// Amodal masks of many instances from one ray per pixel (api/scene_queries.cpp): per pixel
  /// of `camera` (row-major; the scene's camera is not changed), ceil(n / 64) words whose bit
  /// i % 64 of word i / 64 is set when the ray through the pixel centre hits `instances[i]`
  /// anywhere along it (Accel::all_hits) -- exactly the pixels of that instance's id in a
  /// label-only render of it alone (every other instance hidden): cut-outs are respected, a
  /// hidden listed instance covers nothing, instances not listed are ignored. With `first_hit`,
  /// only where instances[i] is the ray's first hit among all shown instances (its visible
  /// mask: where a label-only render shows its id). Rays are traced only in the pixels where
  /// a listed instance's bounds project. Commits pending edits first; `threads` 0: all. Throws
  /// sg::Error for an unknown or repeated instance id.
  std::vector<uint64_t> instance_coverage(const PinholeCamera& camera, const std::vector<uint32_t>& instances,
                                          uint32_t threads = 0, bool first_hit = false);

  /// The texture resolution estimate for the current camera (integrator/texture_estimate.h),
  /// committing pending edits first: one entry per image texture, by texture id.
  std::vector<TextureResolution> estimate_texture_resolution(const TextureEstimateSettings& settings,
                                                             TextureEstimate* raw = nullptr);

  /// Makes mip levels `level` and coarser of each listed texture's pyramid resident (its
  /// pyramid shared with other listed textures: the finest level any asks for), freeing finer
  /// levels where they can be read back (docs/texture_lod.md); levels are clamped to
  /// [0, tail]. Textures not listed keep their levels. Throws sg::Error for an unknown id or
  /// a texture that is not an image.
  void set_texture_levels(const std::vector<std::pair<uint32_t, int>>& texture_levels);
  /// Tiled mip-mapped copies of image files in `dir` (ImageCache::set_mip_cache_dir); files
  /// loaded afterwards are read lazily. Empty: off.
  void set_mip_cache_dir(const std::string& dir) { m_images.set_mip_cache_dir(dir); }

  // Persistence ----------------------------------------------------------------------
  void save(const std::string& path) const;
  static std::unique_ptr<Scene> load(const std::string& path);

  // Change journal (api/journal.h) -------------------------------------------------------
  /// Starts recording (dropping what was recorded): the journal begins with the scene as it
  /// is now (its objects as add operations with their ids, the extensions noted, the camera,
  /// the slot counts) and then receives every edit through this API as it succeeds, commits
  /// included. Off until called: a recording scene keeps removed meshes and pixels alive.
  void begin_journal();
  /// Stops recording and drops the journal.
  void end_journal();
  bool journaling() const { return m_journaling; }
  /// Operations recorded so far.
  size_t journal_size() const { return m_journal.size(); }
  /// Writes the journal: XML in the scene file's vocabulary (<op kind="add_texture" id=...>
  /// with <param> children) and a binary sidecar "<path>.bin" (mesh arrays, pixels, the
  /// extensions' sources). Throws when not recording.
  void save_journal(const std::string& path) const;
  /// A fresh scene with a journal's operations applied in order (ids checked): it renders
  /// bit-identically to the scene that recorded it. `render_params` receives the settings of
  /// the last render recorded (empty when none). The extensions the journal notes must be
  /// loaded first (journal_extensions: their embedded sources). Throws sg::FileError naming
  /// the file and the operation.
  static std::unique_ptr<Scene> replay(const std::string& path, ParamSet* render_params = nullptr);
  /// The extensions a journal file notes, with their embedded sources.
  static std::vector<JournalExtension> journal_extensions(const std::string& path);
  /// Records that an extension was loaded for this scene (its source is embedded in saved
  /// journals, so that a replay elsewhere can compile it).
  void note_extension(const std::string& source, const std::string& sha256, const std::string& text);
  /// Render() first writes the journal to `path` ("" = off): a process that dies inside the
  /// render leaves the journal of the scene it was rendering.
  void set_journal_autosave(const std::string& path) { m_journal_autosave = path; }

  // Read access used by the scene file writer.
  struct TextureEntry {
    std::string type;
    ParamSet params;
    std::shared_ptr<Texture> object;
    std::shared_ptr<ImageData> pixels;  ///< in-memory images ("embedded_image", add_image_texture)
    bool pixels_integer = false;        ///< `pixels` came from 8/16-bit integers
  };
  struct MaterialEntry {
    std::string type;
    ParamSet params;
    std::shared_ptr<Material> object;
    std::vector<uint32_t> depends_on;  ///< materials looked up while creating it (e.g. by "mix")
  };
  struct LightEntry { std::string type; ParamSet params; std::shared_ptr<Light> object; };
  struct MeshEntry {
    std::shared_ptr<TriangleMesh> mesh;
    std::string shape_type;  ///< a user shape's plugin name ("" for triangle meshes)
    ParamSet shape_params;
    Bounds3 bounds;
    std::vector<const Material*> triangle_materials;  // resolved at commit
    bool dirty = true;
  };
  struct InstanceEntry {
    uint32_t mesh_id = 0;
    Transform world_from_object;
    uint32_t class_id = 0, instance_id = 0;
    int64_t material_id = -1;
    std::vector<std::pair<int32_t, int64_t>> material_map;  ///< mesh material id -> material id
    bool visible = true;
    bool catcher = false;
    bool dirty = true;
  };
  const std::vector<std::optional<MeshEntry>>& meshes() const { return m_meshes; }
  const std::vector<Slot<TextureEntry>>& textures() const { return m_textures; }
  const std::vector<Slot<MaterialEntry>>& materials() const { return m_materials; }
  const std::vector<std::optional<InstanceEntry>>& instances() const { return m_instances; }
  const std::vector<std::optional<LightEntry>>& lights() const { return m_lights; }

  // Restoring ids exactly (used by load()).
  void restore_slot_counts(size_t meshes, size_t textures, size_t materials, size_t instances, size_t lights);

 private:
  /// The entry in slot `id` of `v` (a vector of std::optional or Slot); throws sg::Error
  /// naming `what` when there is none.
  template <class V>
  static auto& get_slot(V& v, uint32_t id, const char* what) {
    if (id >= v.size() || !v[id]) throw Error(std::string(what) + " " + std::to_string(id) + " does not exist");
    return *v[id];
  }
  void check_material_id(int64_t id, const char* context) const;
  MaterialContext material_context(std::vector<uint32_t>* depends_on = nullptr) const;
  /// Sets a material's ambient-occlusion needs from the textures and materials it refers to.
  void assign_ao(MaterialEntry& e) const;
  void build_render_scene();
  /// Throws naming the first texture or shape of a user extension that produced a non-finite
  /// value (or an invalid hit) so far.
  void check_extension_failures() const;
  /// Every level of every pyramid used (read back where dropped): a render without
  /// RenderSettings::texture_lod sees full-resolution textures whatever an earlier one kept.
  void use_every_texture_level();
  /// RenderSettings::texture_lod: the estimate for the camera, its levels made resident, the
  /// memory budget kept by dropping unseen pyramids least recently used first; fills the
  /// texture fields of `stats`.
  void apply_texture_lod(const RenderSettings& settings, RenderStats* stats);
  /// Texel memory of the distinct pyramids of the scene's image textures: every level, and
  /// the resident ones.
  void texture_memory(uint64_t* full, uint64_t* resident) const;
  /// Per pyramid, the number of the last apply_texture_lod that saw it (least recently used).
  std::map<const MipMap*, uint64_t> m_pyramid_last_seen;
  uint64_t m_texture_lod_count = 0;
  /// Per mesh slot: 1 when some instance uses it with a material that has alpha (cut-outs).
  std::vector<char> meshes_needing_alpha_test() const;

  std::vector<std::optional<MeshEntry>> m_meshes;
  std::vector<Slot<TextureEntry>> m_textures;
  std::vector<Slot<MaterialEntry>> m_materials;
  std::vector<std::optional<InstanceEntry>> m_instances;
  std::vector<std::optional<LightEntry>> m_lights;
  std::optional<MediumEntry> m_medium;
  std::vector<uint32_t> m_removed_instances;
  /// Per instance slot with a material map: its triangles' materials (resolved at commit).
  std::vector<std::vector<const Material*>> m_instance_triangle_materials;
  std::map<std::string, uint32_t> m_image_cache;  // imports: (resolved path, scale) -> texture id
  ImageCache m_images;  // decoded pixels and mip maps shared by all image textures
  PinholeCamera m_camera;
  bool m_camera_set = false;
  bool m_structure_dirty = true;  // materials / lights / labels changed

  /// A texture as save() and the journal write it: from pixels in memory ("embedded_image":
  /// add_embedded_texture; "image": add_image_texture, its in-memory "file" key dropped) or by
  /// its plugin.
  uint32_t add_texture_entry(const std::string& type, const ParamSet& params, std::shared_ptr<ImageData> pixels,
                             bool integer_source);
  /// The journal's next operation when recording (null otherwise); edits call it once they
  /// succeeded and fill its fields.
  JournalOp* journal_op(JournalOp::Kind kind, uint32_t id = 0);
  /// The current state as journal operations (begin_journal's start).
  void journal_state();
  bool m_journaling = false;
  int m_journal_muted = 0;  ///< > 0 while an edit makes others internally (not recorded twice)
  std::vector<JournalOp> m_journal;
  std::vector<JournalExtension> m_extensions;
  std::string m_journal_autosave;

  std::unique_ptr<Accel> m_accel;
  std::shared_ptr<Material> m_default_material;
  std::vector<std::shared_ptr<AreaLight>> m_area_lights;
  /// Per instance with emitters, its triangles' area light indices (InstanceRecord::prim_light).
  std::vector<std::unique_ptr<std::vector<int32_t>>> m_prim_lights;
  RenderScene m_render_scene;
  CommitStats m_stats;
};

}  // namespace sg
