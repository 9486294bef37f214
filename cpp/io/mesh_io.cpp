#include "io/mesh_io.h"

#include "core/isolate.h"

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
#include <vector>
#include <algorithm>

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

// assimp 5.2's PLY reader loops forever on some malformed headers (a NUL byte in the
// "format" line, no end_header) and reads element counts without comparing them with the
// file size. A PLY file's header is therefore checked here first: printable ASCII lines, a
// known format, an end_header within the first 64 KiB, and element counts the file's bytes
// can hold (at least 2 bytes per ASCII value, the property sizes for binary ones).
static void check_ply_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return;  // reported by the importer
  char magic[4] = {0};
  in.read(magic, 4);
  std::string ext = fs::path(path).extension().string();
  for (auto& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  bool is_ply = in.gcount() >= 3 && magic[0] == 'p' && magic[1] == 'l' && magic[2] == 'y';
  if (!is_ply && (ext != ".ply" || in.gcount() == 0)) return;  // an empty file is diagnosed later
  if (!is_ply) throw FileError(path, "not a PLY file (it does not start with the line 'ply')");
  in.seekg(0);
  std::string head(64 * 1024, '\0');
  in.read(&head[0], std::streamsize(head.size()));
  head.resize(size_t(in.gcount()));
  std::error_code ec;
  uint64_t size = fs::file_size(path, ec);
  size_t pos = 0, line_no = 0;
  std::string format;
  bool ended = false;
  // (count, bytes per element) for every element, to compare with the data's size.
  std::vector<std::pair<uint64_t, uint64_t>> elements;
  auto fail = [&](const std::string& why) { throw FileError(path, "PLY header line " + std::to_string(line_no) + ": " + why); };
  while (pos < head.size()) {
    size_t eol = head.find('\n', pos);
    if (eol == std::string::npos) break;
    std::string line = head.substr(pos, eol - pos);
    pos = eol + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    for (char c : line)
      if (static_cast<unsigned char>(c) < 32 && c != '\t') fail("contains a control byte (a binary or corrupt header)");
    std::vector<std::string> w;
    {
      size_t i = 0;
      while (i < line.size()) {
        size_t j = line.find_first_of(" \t", i);
        if (j == std::string::npos) j = line.size();
        if (j > i) w.push_back(line.substr(i, j - i));
        i = j + 1;
      }
    }
    if (line_no == 1) {
      if (w.size() != 1 || w[0] != "ply") fail("the first line must be 'ply'");
      continue;
    }
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      ended = true;
      break;
    }
    if (w[0] == "format") {
      if (w.size() != 3 || (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian"))
        fail("unknown format (expected 'format ascii|binary_little_endian|binary_big_endian 1.0')");
      format = w[1];
    } else if (w[0] == "element") {
      if (w.size() != 3 || w[2].empty() || w[2].size() > 19 || w[2].find_first_not_of("0123456789") != std::string::npos)
        fail("expected 'element NAME COUNT'");
      elements.emplace_back(std::stoull(w[2]), 0);
    } else if (w[0] == "property") {
      if (elements.empty()) fail("a property before any element");
      static const std::pair<const char*, int> k_types[] = {
          {"char", 1}, {"uchar", 1}, {"int8", 1}, {"uint8", 1}, {"short", 2}, {"ushort", 2}, {"int16", 2},
          {"uint16", 2}, {"int", 4}, {"uint", 4}, {"int32", 4}, {"uint32", 4}, {"float", 4}, {"float32", 4},
          {"double", 8}, {"float64", 8}};
      auto type_size = [&](const std::string& t) {
        for (const auto& k : k_types)
          if (t == k.first) return k.second;
        fail("unknown property type '" + t + "'");
        return 0;
      };
      // A list stores at least its count; a scalar its size.
      if (w.size() >= 2 && w[1] == "list") {
        if (w.size() != 5) fail("expected 'property list COUNT_TYPE ITEM_TYPE NAME'");
        type_size(w[3]);
        elements.back().second += uint64_t(type_size(w[2]));
      } else {
        if (w.size() != 3) fail("expected 'property TYPE NAME'");
        elements.back().second += uint64_t(type_size(w[1]));
      }
    }  // other lines (free text some exporters write) are left to the reader
  }
  if (!ended) throw FileError(path, "PLY header has no end_header line within its first 64 KiB");
  if (format.empty()) throw FileError(path, "PLY header has no format line");
  uint64_t data = size > pos ? size - pos : 0;
  // Lower bounds on the bytes an element needs: an ASCII element with properties holds at
  // least one value, written as a digit and a separator.
  long double need = 0;
  for (const auto& e : elements) {
    uint64_t per = format == "ascii" ? (e.second ? 2 : 0) : e.second;
    need += (long double)e.first * (long double)per;
  }
  if (need > (long double)data)
    throw FileError(path, "PLY header declares more elements than the file holds (at least " +
                              std::to_string((unsigned long long)std::min<long double>(need, 1e19L)) + " bytes of data, the file has " +
                              std::to_string(data) + "): truncated or corrupt");
}

// assimp 5.2 allocates what a GLB's header and chunk headers declare before it checks them
// against the file (a 200-byte file asked for 4 GiB). The 12-byte header and the chunk
// headers are therefore checked first: magic, version 2, the declared length equal to the
// file's, every chunk inside it (glTF 2.0 spec, "Binary glTF Layout").
static void check_glb_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return;
  unsigned char h[12] = {0};
  in.read(reinterpret_cast<char*>(h), sizeof h);
  if (in.gcount() < 4 || h[0] != 'g' || h[1] != 'l' || h[2] != 'T' || h[3] != 'F') return;  // not a GLB
  auto u32 = [](const unsigned char* p) {
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
  };
  std::error_code ec;
  uint64_t size = fs::file_size(path, ec);
  if (in.gcount() < 12) throw FileError(path, "a glTF binary (GLB) cut short inside its 12-byte header");
  uint64_t declared = u32(h + 8);
  if (declared > size)
    throw FileError(path, "a glTF binary (GLB) truncated: its header declares " + std::to_string(declared) +
                              " bytes, the file has " + std::to_string(size));
  if (u32(h + 4) == 1) {  // glTF 1.0 (KHR_binary_glTF): one content block after a 20-byte header
    unsigned char c[4];
    in.read(reinterpret_cast<char*>(c), sizeof c);
    if (in.gcount() < 4 || 20 + uint64_t(u32(c)) > declared)
      throw FileError(path, "a glTF 1.0 binary whose content block runs past the end of the file");
    return;
  }
  if (u32(h + 4) != 2) return;  // an unknown version: the importer reports it
  uint64_t pos = 12;
  for (int chunk = 0; pos < declared; ++chunk) {
    unsigned char c[8];
    in.seekg(std::streamoff(pos));
    in.read(reinterpret_cast<char*>(c), sizeof c);
    if (in.gcount() < 8 || pos + 8 > declared)
      throw FileError(path, "a glTF binary (GLB) whose chunk " + std::to_string(chunk) + " header is cut short");
    uint64_t length = u32(c);
    if (pos + 8 + length > declared)
      throw FileError(path, "a glTF binary (GLB) whose chunk " + std::to_string(chunk) + " declares " +
                                std::to_string(length) + " bytes past the end of the file (" + std::to_string(declared) +
                                " bytes)");
    pos += 8 + length;
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

/// The raw meshes of a reader, before assimp's post-processing sees them: arrays present,
/// every face with 1 to 2^16 indices inside its mesh's vertices.
static void check_raw_scene(const aiScene& scene, const std::string& path) {
  if (scene.mNumMeshes && !scene.mMeshes) throw FileError(path, "the reader produced no mesh array");
  for (unsigned i = 0; i < scene.mNumMeshes; ++i) {
    const aiMesh* m = scene.mMeshes[i];
    const std::string where = "mesh " + std::to_string(i);
    if (!m) throw FileError(path, where + " is missing");
    if ((m->mNumVertices && !m->mVertices) || (m->mNumFaces && !m->mFaces))
      throw FileError(path, where + " declares vertices or faces it does not have");
    for (unsigned f = 0; f < m->mNumFaces; ++f) {
      const aiFace& face = m->mFaces[f];
      if (face.mNumIndices == 0 || face.mNumIndices > (1u << 16) || !face.mIndices)
        throw FileError(path, where + ", face " + std::to_string(f) + ": " + std::to_string(face.mNumIndices) +
                                  " vertex indices (a face has 1 to 65536)");
      for (unsigned k = 0; k < face.mNumIndices; ++k)
        if (face.mIndices[k] >= m->mNumVertices)
          throw FileError(path, where + ", face " + std::to_string(f) + ": vertex index " +
                                    std::to_string(face.mIndices[k]) + " out of range (" +
                                    std::to_string(m->mNumVertices) + " vertices)");
    }
  }
}

void check_mesh_file(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw FileError(path, "file not found");
  if (fs::is_directory(path, ec)) throw FileError(path, "is a directory, not a mesh file");
  if (!fs::is_regular_file(path, ec))
    throw FileError(path, "is not a regular file (a device, FIFO or socket), not a mesh file");
  check_obj_vertices(path);
  check_ply_header(path);
  check_glb_header(path);
}

ImportedModel import_mesh_file(const std::string& path) {
  check_mesh_file(path);
  std::error_code ec;
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // Read without post-processing, check what the reader made, then post-process: assimp's
  // steps assert (abort) on data its readers let through (a PLY face of 0 indices aborts
  // the triangulation; found by fuzz_mesh_import).
  const aiScene* scene = importer.ReadFile(path, 0);
  if (!scene) {
    std::string why = diagnose_unreadable(path);
    throw FileError(path, "cannot import mesh: " + (why.empty() ? std::string(importer.GetErrorString()) : why));
  }
  if (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) throw FileError(path, "incomplete scene (the importer gave up)");
  check_raw_scene(*scene, path);
  scene = importer.ApplyPostProcessing(aiProcess_ValidateDataStructure);
  if (scene)
    scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_PreTransformVertices |
                                         aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (!scene) throw FileError(path, "cannot import mesh: " + std::string(importer.GetErrorString()));

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
  // AC3D's "emis" is OpenGL fixed-function emission, a constant added to the lit colour of an
  // unlit-looking game model (TORCS gives every car "emis 0.2"), not a light: read as emission
  // it made whole car bodies glow and light the ground. AC3D files carry no emitters.
  std::string lower_ext = fs::path(path).extension().string();
  for (char& ch : lower_ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  const bool ac3d = lower_ext == ".ac" || lower_ext == ".acc" || lower_ext == ".ac3d";
  for (unsigned i = 0; i < scene->mNumMaterials; ++i) {
    const aiMaterial* am = scene->mMaterials[i];
    ImportedMaterial im;
    aiString name;
    if (am->Get(AI_MATKEY_NAME, name) == AI_SUCCESS) im.name = name.C_Str();
    aiColor4D c;
    bool has_base = am->Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS;
    if (has_base || am->Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS) im.base_color = Color(c.r, c.g, c.b);
    aiColor3D e;
    if (!ac3d && am->Get(AI_MATKEY_COLOR_EMISSIVE, e) == AI_SUCCESS) im.emission = Color(e.r, e.g, e.b);
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

// Isolated import ----------------------------------------------------------------------

namespace {

void put(Writer& w, const ImportedTexture& t) {
  w.str(t.path);
  w.pod(t.embedded);
  write_image_data(w, t.pixels);
}

ImportedTexture get_texture(Reader& r, const std::string& path) {
  ImportedTexture t;
  t.path = r.str();
  t.embedded = r.pod<bool>();
  t.pixels = read_image_data(r, path);
  return t;
}

}  // namespace

std::vector<char> import_mesh_file_bytes(const std::string& path) {
  ImportedModel m = import_mesh_file(path);
  Writer w;
  w.str(m.mesh.name);
  w.vec(m.mesh.positions);
  w.vec(m.mesh.normals);
  w.vec(m.mesh.uvs);
  w.vec(m.mesh.indices);
  w.vec(m.mesh.material_ids);
  w.pod(uint64_t(m.removed_degenerate));
  w.pod(uint64_t(m.materials.size()));
  for (const ImportedMaterial& im : m.materials) {
    w.str(im.name);
    w.pod(im.base_color);
    w.pod(im.emission);
    w.str(im.texture_path);
    w.pod(im.has_embedded_texture);
    write_image_data(w, im.embedded_texture);
    for (float f : {im.metallic, im.roughness, im.specular, im.transmission, im.clearcoat, im.clearcoat_roughness,
                    im.ior, im.emission_strength, im.alpha, im.alpha_cutoff, im.normal_scale})
      w.pod(f);
    w.str(im.alpha_mode);
    put(w, im.metallic_roughness);
    put(w, im.normal);
    put(w, im.emissive);
    put(w, im.opacity);
  }
  return std::move(w.bytes);
}

ImportedModel import_mesh_file_isolated(const std::string& path) {
  // A fresh reader per model file: assimp is the least hardened library synthgen reads with
  // (fuzz_mesh_import found reads and writes out of bounds inside it), and a reader whose heap
  // a file corrupted without crashing must not read the next file.
  Bytes bytes = read_isolated(path, {"mesh", path}, [&] { return import_mesh_file_bytes(path); }, /*fresh=*/true);
  Reader r(bytes, path);
  ImportedModel m;
  m.mesh.name = r.str();
  m.mesh.positions = r.vec<Vec3f>();
  m.mesh.normals = r.vec<Vec3f>();
  m.mesh.uvs = r.vec<Vec2f>();
  m.mesh.indices = r.vec<uint32_t>();
  m.mesh.material_ids = r.vec<int32_t>();
  m.removed_degenerate = size_t(r.pod<uint64_t>());
  uint64_t n = r.pod<uint64_t>();
  if (n > bytes.size()) throw FileError(path, "malformed model from the isolated reader");
  for (uint64_t i = 0; i < n; ++i) {
    ImportedMaterial im;
    im.name = r.str();
    im.base_color = r.pod<Color>();
    im.emission = r.pod<Color>();
    im.texture_path = r.str();
    im.has_embedded_texture = r.pod<bool>();
    im.embedded_texture = read_image_data(r, path);
    for (float* f : {&im.metallic, &im.roughness, &im.specular, &im.transmission, &im.clearcoat,
                     &im.clearcoat_roughness, &im.ior, &im.emission_strength, &im.alpha, &im.alpha_cutoff,
                     &im.normal_scale})
      *f = r.pod<float>();
    im.alpha_mode = r.str();
    im.metallic_roughness = get_texture(r, path);
    im.normal = get_texture(r, path);
    im.emissive = get_texture(r, path);
    im.opacity = get_texture(r, path);
    m.materials.push_back(std::move(im));
  }
  if (!r.done()) throw FileError(path, "malformed model from the isolated reader (trailing data)");
  for (int32_t id : m.mesh.material_ids)
    if (id < -1 || (id >= 0 && size_t(id) >= m.materials.size()))
      throw FileError(path, "malformed model from the isolated reader (material id out of range)");
  return m;
}

}  // namespace sg
