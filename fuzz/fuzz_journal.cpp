// Fuzz target: the change journal's replay (Scene::replay, api/scene_journal.cpp). Input: the
// journal's XML, optionally followed by "\0BIN\0" and the bytes of its binary sidecar. Any input
// must replay or throw sg::Error -- never crash, hang or allocate without bound.
#include <cstring>
#include <string>

#include "api/scene.h"
#include "core/error.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const char k_sep[] = "\0BIN\0";
  const uint8_t* sep = nullptr;
  for (size_t i = 0; i + 5 <= size; ++i)
    if (std::memcmp(data + i, k_sep, 5) == 0) {
      sep = data + i;
      break;
    }
  size_t xml_size = sep ? size_t(sep - data) : size;
  std::string path = fuzz::write_file("journal.xml", data, xml_size);
  const uint8_t* bin = sep ? sep + 5 : data + size;
  fuzz::write_file("journal.xml.bin", bin, size_t(data + size - bin));
  try {
    sg::ParamSet render;
    auto scene = sg::Scene::replay(path, &render);
    if (scene->instance_count() > 0) scene->commit();
  } catch (const sg::Error&) {
  }
  return 0;
}
