// Mesh import through assimp (the only file using its API: mesh_io.cpp).
#pragma once

#include <string>
#include <vector>

#include "core/math.h"
#include "geometry/mesh.h"
#include "io/image_io.h"

namespace sg {

struct ImportedMaterial {
  std::string name;
  Color base_color{0.8f, 0.8f, 0.8f};
  Color emission{0.f, 0.f, 0.f};
  std::string texture_path;  ///< resolved absolute path of the base colour image, or ""
  bool has_embedded_texture = false;
  ImageData embedded_texture;  ///< decoded pixels of an embedded (GLB) base colour image
};

struct ImportedModel {
  TriangleMesh mesh;  ///< node transforms applied; material_ids index `materials`
  std::vector<ImportedMaterial> materials;
  size_t removed_degenerate = 0;
};

/// Reads OBJ (+MTL), PLY, glTF 2.0 / GLB and every other format assimp knows.
/// Throws sg::FileError naming the file and the reason.
ImportedModel import_mesh_file(const std::string& path);

}  // namespace sg
