// The change journal of the integration API (Scene::begin_journal): every edit recorded as it
// happens, with commit boundaries, so that a scene seen failing inside a dataset can be saved
// (Scene::save_journal: the vocabulary of the XML scene format plus a binary sidecar) and
// replayed outside it (Scene::replay), bit-identically. After Hydra Render (Sanzharov 2023),
// whose integration layer streams changes, not whole scenes.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "camera/camera.h"
#include "core/math.h"
#include "core/params.h"
#include "geometry/mesh.h"
#include "io/image_io.h"

namespace sg {

/// One recorded edit. Meshes and pixels are shared with the scene (recording copies no
/// arrays); the fields an operation does not use keep their defaults.
struct JournalOp {
  enum class Kind : uint8_t {
    AddMesh, UpdateMesh, RemoveMesh, AddShape,
    AddTexture, RemoveTexture,
    AddMaterial, UpdateMaterial, RemoveMaterial,
    AddInstance, SetInstanceTransform, SetInstanceLabels, SetInstanceMaterial, SetInstanceMaterialMap,
    SetInstanceMesh, RemoveInstance, SetInstanceVisible, SetInstanceCatcher,
    AddLight, UpdateLight, RemoveLight,
    SetMedium, ClearMedium, SetCamera,
    SlotCounts, Commit, Extension, Render,
  };
  Kind kind = Kind::Commit;
  uint32_t id = 0;                 ///< the object edited (its id, assigned or given)
  std::string type;                ///< plugin name; an extension's source path
  ParamSet params;                 ///< plugin parameters; render settings
  std::shared_ptr<const TriangleMesh> mesh;
  std::shared_ptr<ImageData> pixels;  ///< textures from pixels in memory
  bool flag = false;               ///< visible, catcher; pixels from integers
  Transform transform;             ///< world_from_object
  PinholeCamera camera;
  uint32_t a = 0, b = 0;           ///< mesh id; class id and instance id
  int64_t material = -1;
  std::vector<std::pair<int32_t, int64_t>> pairs;  ///< material map
  std::vector<uint64_t> counts;    ///< slot counts (meshes, textures, materials, instances, lights)
  std::string text;                ///< an extension's source text; its sha256 in `params`
};

/// An extension a journal needs: its source file, sha256 and source text (embedded).
struct JournalExtension {
  std::string source, sha256, text;
};

/// Name of an operation in the file ("add_mesh", ...); the kind of a name (false: unknown).
const char* journal_op_name(JournalOp::Kind k);
bool journal_op_kind(const std::string& name, JournalOp::Kind* k);

}  // namespace sg
