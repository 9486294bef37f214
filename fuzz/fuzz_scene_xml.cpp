// Fuzz target: the scene XML loader (Scene::load, api/scene_xml.cpp). Input: the XML text,
// optionally followed by "\0BIN\0" and the bytes of its binary sidecar. Any input must load
// or throw sg::Error -- never crash, hang or allocate without bound.
#include <string>

#include "api/scene.h"
#include "core/error.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string path = fuzz::write_with_sidecar("scene.xml", data, size);
  try {
    auto scene = sg::Scene::load(path);
    if (scene->instance_count() > 0) scene->commit();
  } catch (const sg::Error&) {
  }
  return 0;
}
