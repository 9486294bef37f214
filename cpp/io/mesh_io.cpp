#include "io/mesh_io.h"

#include <assimp/Importer.hpp>
#include <assimp/GltfMaterial.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/error.h"

namespace sg {

namespace fs = std::filesystem;

static ImageData decode_embedded(const aiTexture* tex, const std::string& path) {
  ImageData img;
  if (tex->mHeight != 0) {
    // Uncompressed BGRA texels.
    img.width = int(tex->mWidth);
    img.height = int(tex->mHeight);
    img.channels = 4;
    img.pixels.resize(size_t(img.width) * img.height * 4);
    for (size_t i = 0; i < size_t(img.width) * img.height; ++i) {
      const aiTexel& t = tex->pcData[i];
      img.pixels[4 * i] = t.r / 255.f;
      img.pixels[4 * i + 1] = t.g / 255.f;
      img.pixels[4 * i + 2] = t.b / 255.f;
      img.pixels[4 * i + 3] = t.a / 255.f;
    }
    return img;
  }
  std::string hint = tex->achFormatHint[0] ? std::string(tex->achFormatHint) : "png";
  return load_image_from_memory(tex->pcData, tex->mWidth, hint, path + " (embedded texture)");
}

// assimp 5.2's OBJ parser silently drops a "v" line whose first coordinate is "nan",
// shifting all later vertex indices. OBJ vertex lines are therefore validated here first.
static void check_obj_vertices(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (auto& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".obj") return;
  std::ifstream in(path);
  if (!in) throw FileError(path, "cannot open file");
  std::string line;
  size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    size_t i = line.find_first_not_of(" \t");
    if (i == std::string::npos || line.compare(i, 2, "v ") != 0) continue;
    const char* p = line.c_str() + i + 2;
    for (int k = 0; k < 3; ++k) {
      char* end = nullptr;
      float v = std::strtof(p, &end);
      if (end == p)
        throw FileError(path, "line " + std::to_string(line_no) + ": vertex coordinate " + std::to_string(k + 1) +
                                  " is not a number");
      if (!std::isfinite(v))
        throw FileError(path, "line " + std::to_string(line_no) + ": vertex coordinate " + std::to_string(k + 1) + " is " +
                                  (std::isnan(v) ? "non-finite (NaN)" : "non-finite (infinite, or beyond the float range |x| > 3.4e38)"));
      p = end;
    }
  }
}

/// Why assimp found no reader, when the file's own header tells: a glTF binary whose
/// declared length exceeds the file (truncated), an empty file; "" when nothing is known.
static std::string diagnose_unreadable(const std::string& path) {
  std::error_code ec;
  uint64_t size = fs::file_size(path, ec);
  if (ec) return "";
  if (size == 0) return "the file is empty";
  std::ifstream in(path, std::ios::binary);
  unsigned char h[12] = {0};
  in.read(reinterpret_cast<char*>(h), sizeof h);
  if (in.gcount() >= 4 && h[0] == 'g' && h[1] == 'l' && h[2] == 'T' && h[3] == 'F') {
    if (in.gcount() < 12) return "a glTF binary (GLB) cut short inside its 12-byte header";
    uint32_t declared = uint32_t(h[8]) | uint32_t(h[9]) << 8 | uint32_t(h[10]) << 16 | uint32_t(h[11]) << 24;
    if (declared > size)
      return "a glTF binary (GLB) truncated: its header declares " + std::to_string(declared) + " bytes, the file has " +
             std::to_string(size);
    return "a glTF binary (GLB) that assimp cannot parse (corrupt chunks?)";
  }
  return "";
}

ImportedModel import_mesh_file(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw FileError(path, "file not found");
  if (fs::is_directory(path, ec)) throw FileError(path, "is a directory, not a mesh file");
  check_obj_vertices(path);
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_JoinIdenticalVertices |
                aiProcess_SortByPType | aiProcess_ValidateDataStructure);
  if (!scene) {
    std::string why = diagnose_unreadable(path);
    throw FileError(path, "cannot import mesh: " + (why.empty() ? std::string(importer.GetErrorString()) : why));
  }
  if (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) throw FileError(path, "incomplete scene (the importer gave up)");

  ImportedModel model;
  model.mesh.name = fs::path(path).filename().string();
  bool all_normals = scene->mNumMeshes > 0, any_uvs = false;
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
    const aiMesh* m = scene->mMeshes[i];
    if (!(m->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    all_normals = all_normals && m->HasNormals();
    any_uvs = any_uvs || m->HasTextureCoords(0);
  }
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
    const aiMesh* m = scene->mMeshes[i];
    if (!(m->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    uint32_t base = uint32_t(model.mesh.positions.size());
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
      const aiVector3D& p = m->mVertices[v];
      model.mesh.positions.emplace_back(p.x, p.y, p.z);
      if (all_normals) {
        const aiVector3D& n = m->mNormals[v];
        Vec3f nn(n.x, n.y, n.z);
        // Zero normals occur in real files: fall back to a placeholder fixed below.
        model.mesh.normals.push_back(nn);
      }
      if (any_uvs) {
        if (m->HasTextureCoords(0)) model.mesh.uvs.emplace_back(m->mTextureCoords[0][v].x, m->mTextureCoords[0][v].y);
        else model.mesh.uvs.emplace_back(0.f, 0.f);
      }
    }
    for (unsigned f = 0; f < m->mNumFaces; ++f) {
      const aiFace& face = m->mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (int k = 0; k < 3; ++k) model.mesh.indices.push_back(base + face.mIndices[k]);
      model.mesh.material_ids.push_back(int32_t(m->mMaterialIndex));
    }
  }
  if (model.mesh.indices.empty()) throw FileError(path, "contains no triangles");
  for (const Vec3f& p : model.mesh.positions)
    if (!is_finite(p)) throw FileError(path, "contains a vertex with a non-finite (NaN or inf) coordinate");
  // Drop unusable normals altogether rather than shading with garbage.
  bool normals_ok = true;
  for (Vec3f& n : model.mesh.normals)
    if (!is_finite(n) || length_squared(n) == 0.f) normals_ok = false;
  if (!normals_ok) model.mesh.normals.clear();
  model.removed_degenerate = model.mesh.remove_degenerate_triangles();
  if (model.mesh.indices.empty()) throw FileError(path, "all triangles are degenerate (zero area)");

  fs::path dir = fs::path(path).parent_path();
  for (unsigned i = 0; i < scene->mNumMaterials; ++i) {
    const aiMaterial* am = scene->mMaterials[i];
    ImportedMaterial im;
    aiString name;
    if (am->Get(AI_MATKEY_NAME, name) == AI_SUCCESS) im.name = name.C_Str();
    aiColor4D c;
    bool has_base = am->Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS;
    if (has_base || am->Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS) im.base_color = Color(c.r, c.g, c.b);
    aiColor3D e;
    if (am->Get(AI_MATKEY_COLOR_EMISSIVE, e) == AI_SUCCESS) im.emission = Color(e.r, e.g, e.b);
    // Resolves texture slot (type, index) into `out`; false when the slot is empty.
    auto get_texture = [&](aiTextureType type, unsigned index, ImportedTexture* out) {
      aiString tex;
      if (am->GetTexture(type, index, &tex) != AI_SUCCESS || tex.length == 0) return false;
      if (const aiTexture* emb = scene->GetEmbeddedTexture(tex.C_Str())) {
        out->pixels = decode_embedded(emb, path);
        out->embedded = true;
        return true;
      }
      fs::path tp = fs::path(std::string(tex.C_Str()));
      if (tp.is_relative()) tp = dir / tp;
      if (!fs::exists(tp, ec))
        throw FileError(path, "material '" + im.name + "' references texture '" + std::string(tex.C_Str()) +
                                  "' which does not exist (looked for " + tp.string() + ")");
      out->path = tp.lexically_normal().string();
      return true;
    };
    ImportedTexture base_tex;
    if (get_texture(aiTextureType_BASE_COLOR, 0, &base_tex) || get_texture(aiTextureType_DIFFUSE, 0, &base_tex)) {
      im.texture_path = base_tex.path;
      im.has_embedded_texture = base_tex.embedded;
      im.embedded_texture = std::move(base_tex.pixels);
    }
    get_texture(aiTextureType_NORMALS, 0, &im.normal);
    get_texture(aiTextureType_EMISSIVE, 0, &im.emissive);
    float f;
    if (am->Get(AI_MATKEY_EMISSIVE_INTENSITY, f) == AI_SUCCESS && f >= 0.f) im.emission_strength = f;
    float metallic, roughness;
    if (am->Get(AI_MATKEY_METALLIC_FACTOR, metallic) == AI_SUCCESS &&
        am->Get(AI_MATKEY_ROUGHNESS_FACTOR, roughness) == AI_SUCCESS) {
      // glTF 2.0 metallic-roughness (assimp 5.2 glTF2 importer): factors, the packed
      // metallicRoughnessTexture (aiTextureType_UNKNOWN, also listed as METALNESS), the
      // normal texture scale, base colour alpha and alphaMode / alphaCutoff.
      im.metallic = metallic;
      im.roughness = roughness;
      if (!get_texture(AI_MATKEY_GLTF_PBRMETALLICROUGHNESS_METALLICROUGHNESS_TEXTURE, &im.metallic_roughness))
        get_texture(aiTextureType_METALNESS, 0, &im.metallic_roughness);
      if (im.normal.present()) {
        float scale;
        if (am->Get(AI_MATKEY_GLTF_TEXTURE_SCALE(aiTextureType_NORMALS, 0), scale) == AI_SUCCESS) im.normal_scale = scale;
      }
      if (has_base) im.alpha = c.a;
      // KHR_materials_transmission / _clearcoat / _ior factors (textures are not imported).
      float x;
      if (am->Get(AI_MATKEY_TRANSMISSION_FACTOR, x) == AI_SUCCESS) im.transmission = x;
      if (am->Get(AI_MATKEY_CLEARCOAT_FACTOR, x) == AI_SUCCESS) im.clearcoat = x;
      if (am->Get(AI_MATKEY_CLEARCOAT_ROUGHNESS_FACTOR, x) == AI_SUCCESS) im.clearcoat_roughness = x;
      if (am->Get(AI_MATKEY_REFRACTI, x) == AI_SUCCESS && x > 1.f) im.ior = x;
      aiString mode;
      if (am->Get(AI_MATKEY_GLTF_ALPHAMODE, mode) == AI_SUCCESS) {
        std::string m = mode.C_Str();
        im.alpha_mode = m == "MASK" ? "mask" : m == "BLEND" ? "blend" : "opaque";
      }
      float cutoff;
      if (am->Get(AI_MATKEY_GLTF_ALPHACUTOFF, cutoff) == AI_SUCCESS) im.alpha_cutoff = cutoff;
    } else {
      // Phong-style materials (OBJ/MTL and most legacy formats): Kd is the base colour;
      // Ks decides the dielectric specular F0 = min(luminance(Ks), 0.08), i.e. specular =
      // F0 / 0.08 (no Ks: 0); the Phong exponent Ns becomes roughness = sqrt(2 / (Ns + 2)).
      // NOTE: Walter et al. 2007, "Microfacet Models for Refraction", eq. 30 / sec. 5.2
      // relate the Phong exponent to Beckmann alpha_b = sqrt(2 / (Ns + 2)); roughness is
      // taken as that alpha (a common Phong-to-GGX mapping, e.g. three.js / Blender's MTL
      // importers use the same family), which keeps shiny (large Ns) materials sharp.
      aiColor3D ks;
      im.specular = 0.f;
      if (am->Get(AI_MATKEY_COLOR_SPECULAR, ks) == AI_SUCCESS)
        im.specular = std::min(std::max(0.2126f * ks.r + 0.7152f * ks.g + 0.0722f * ks.b, 0.f), 0.08f) / 0.08f;
      float ns;
      im.roughness = 1.f;
      if (am->Get(AI_MATKEY_SHININESS, ns) == AI_SUCCESS && ns > 0.f) im.roughness = std::sqrt(2.f / (ns + 2.f));
      float d;
      if (am->Get(AI_MATKEY_OPACITY, d) == AI_SUCCESS) im.alpha = std::min(std::max(d, 0.f), 1.f);
      get_texture(aiTextureType_OPACITY, 0, &im.opacity);
      // Partial coverage (d < 1 or map_d) is rendered as a cut-out at 0.5 (glTF BLEND).
      if (im.alpha < 1.f || im.opacity.present()) im.alpha_mode = "blend";
    }
    model.materials.push_back(std::move(im));
  }
  for (int32_t& id : model.mesh.material_ids)
    if (id < 0 || size_t(id) >= model.materials.size()) id = -1;
  return model;
}

}  // namespace sg
