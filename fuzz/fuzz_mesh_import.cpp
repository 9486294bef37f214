// Fuzz target: mesh import (Scene::load_mesh_file: the OBJ pre-check, assimp's readers for
// OBJ, PLY, glTF and GLB, our conversion, mesh validation, material creation). The first
// byte picks the format. The import runs in this process (fuzz_util.h); in synthgen it runs
// in synthgen-reader with limits (core/isolate.h, tested by test_isolate).
#include <string>

#include "api/scene.h"
#include "core/error.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* k_ext[] = {"obj", "ply", "gltf", "glb"};
  std::string path = fuzz::write_file(std::string("model.") + k_ext[data[0] % 4], data + 1, size - 1);
  try {
    sg::Scene scene;
    sg::ImportResult r = scene.load_mesh_file(path);
    (void)r;
  } catch (const sg::Error&) {
  }
  return 0;
}
