// Mesh import through assimp (the only file using its API: mesh_io.cpp).
#pragma once

#include <string>
#include <vector>

#include "core/math.h"
#include "geometry/mesh.h"
#include "io/image_io.h"

namespace sg {

/// An image referenced by a material: a file or pixels embedded in the model (GLB).
struct ImportedTexture {
  std::string path;  ///< resolved absolute path, or ""
  bool embedded = false;
  ImageData pixels;  ///< decoded, not colour-converted pixels of an embedded image
  bool present() const { return embedded || !path.empty(); }
};

/// A material as the file describes it, mapped to the parameters of "principled" (see
/// import_mesh_file for the glTF and OBJ/MTL mappings).
struct ImportedMaterial {
  std::string name;
  Color base_color{0.8f, 0.8f, 0.8f};
  Color emission{0.f, 0.f, 0.f};
  std::string texture_path;  ///< resolved absolute path of the base colour image, or ""
  bool has_embedded_texture = false;
  ImageData embedded_texture;  ///< decoded pixels of an embedded (GLB) base colour image
  float metallic = 0.f, roughness = 0.5f, specular = 0.5f;
  float transmission = 0.f, clearcoat = 0.f, clearcoat_roughness = 0.f, ior = 1.5f;  ///< glTF KHR extensions
  float emission_strength = 1.f;
  float alpha = 1.f;                ///< base colour alpha factor (glTF) or MTL `d`
  std::string alpha_mode = "opaque";  ///< opaque, mask or blend (glTF alphaMode)
  float alpha_cutoff = 0.5f;
  ImportedTexture metallic_roughness;  ///< glTF packed texture: B = metallic, G = roughness
  ImportedTexture normal;              ///< tangent-space normal map (linear)
  float normal_scale = 1.f;
  ImportedTexture emissive;  ///< emission colour image (sRGB), times `emission`
  ImportedTexture opacity;   ///< separate alpha map (MTL map_d)
};

struct ImportedModel {
  TriangleMesh mesh;  ///< node transforms applied; material_ids index `materials`
  std::vector<ImportedMaterial> materials;
  size_t removed_degenerate = 0;
};

/// Reads OBJ (+MTL), PLY, glTF 2.0 / GLB and every other format assimp knows.
/// Throws sg::FileError naming the file and the reason.
ImportedModel import_mesh_file(const std::string& path);

/// The checks import_mesh_file makes before assimp sees a file (a regular file; OBJ vertex
/// lines, PLY headers, GLB headers); FileError naming the file and the reason.
void check_mesh_file(const std::string& path);

/// import_mesh_file in the synthgen-reader process with time and memory limits
/// (core/isolate.h): a crash, hang or runaway allocation inside assimp becomes an
/// sg::FileError. What the reader sends back is checked before use. Scene::load_mesh_file
/// reads files this way.
ImportedModel import_mesh_file_isolated(const std::string& path);

/// import_mesh_file's result as the bytes synthgen-reader sends.
std::vector<char> import_mesh_file_bytes(const std::string& path);

}  // namespace sg
