// Fuzz target: the change journal's replay (Scene::replay, api/scene_journal.cpp). Input: the
// journal's XML, optionally followed by "\0BIN\0" and the bytes of its binary sidecar. Any input
// must replay or throw sg::Error -- never crash, hang or allocate without bound.
#include <string>

#include "api/scene.h"
#include "core/error.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string path = fuzz::write_with_sidecar("journal.xml", data, size);
  try {
    sg::ParamSet render;
    auto scene = sg::Scene::replay(path, &render);
    if (scene->instance_count() > 0) scene->commit();
  } catch (const sg::Error&) {
  }
  return 0;
}
