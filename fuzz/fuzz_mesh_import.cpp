// Fuzz target: mesh import (OBJ, PLY, glTF, GLB). The first byte picks the format.
//
// Our checks before assimp (check_mesh_file) run here, instrumented and coverage-guided;
// the import itself runs as in synthgen: in synthgen-reader (core/isolate.h), a process of
// its own per file, where assimp -- Debian's uninstrumented build, which crashes and writes
// out of bounds on some inputs -- cannot take the fuzzer down. The reader is built with the
// sanitizers too: bench/fuzz.sh makes a sanitizer report in it exit with status 86, which
// this target turns into a crash (our conversion code's bug); a crash inside assimp is the
// FileError synthgen gives. The model that comes back is then built into a Scene here
// (mesh validation, materials: coverage-guided again).
#define SG_FUZZ_ISOLATED 1
#include <cstdio>
#include <cstdlib>
#include <string>

#include "api/scene.h"
#include "core/error.h"
#include "fuzz_util.h"
#include "io/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* k_ext[] = {"obj", "ply", "gltf", "glb"};
  std::string path = fuzz::write_file(std::string("model.") + k_ext[data[0] % 4], data + 1, size - 1);
  try {
    sg::check_mesh_file(path);
    sg::Scene scene;
    sg::ImportResult r = scene.load_mesh_file(path);
    (void)r;
  } catch (const sg::Error& e) {
    if (std::string(e.what()).find("(exit status 86,") != std::string::npos) {
      std::fprintf(stderr, "synthgen-reader reported a sanitizer error (above): %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}
