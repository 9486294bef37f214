// Fuzz target: plugin creation from arbitrary parameters (core/plugin.h: the declaration
// checks and every factory). The input is decoded into a plugin kind and name and a
// ParamSet of declared and undeclared keys with values of every type (NaN, huge, negative,
// wrong types, texture references to nothing). Every plugin must be created or refuse
// with sg::Error.
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "api/scene.h"
#include "camera/camera.h"
#include "core/error.h"
#include "core/plugin.h"
#include "fuzz_util.h"
#include "integrator/path_tracer.h"

namespace {

struct Reader {
  const uint8_t* p;
  size_t n;
  uint8_t byte() { return n ? (--n, *p++) : 0; }
  double number() {
    switch (byte() % 8) {
      case 0: return std::numeric_limits<double>::quiet_NaN();
      case 1: return std::numeric_limits<double>::infinity();
      case 2: return -1e300;
      case 3: return 0.0;
      default: {
        double d = 0;
        uint8_t b[8];
        for (auto& x : b) x = byte();
        std::memcpy(&d, b, 8);
        return std::isfinite(d) ? std::fmod(d, 1e4) : double(b[0]) / 16.0 - 4.0;
      }
    }
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Reader r{data, size};
  const sg::Registry& reg = sg::Registry::instance();
  std::vector<std::string> kinds = reg.kinds();
  const std::string kind = kinds[r.byte() % kinds.size()];
  std::vector<std::string> names = reg.names(kind);
  const std::string name = names[r.byte() % names.size()];
  const sg::PluginInfo& info = reg.info(kind, name);
  sg::ParamSet ps;
  int count = r.byte() % 8;
  for (int i = 0; i < count; ++i) {
    uint8_t pick = r.byte();
    std::string key = (pick & 0x80) || info.params.empty() ? std::string("k") + char('a' + pick % 26)
                                                             : info.params[pick % info.params.size()].name;
    switch (r.byte() % 7) {
      case 0: ps.set(key, bool(r.byte() & 1)); break;
      case 1: ps.set(key, int64_t(int8_t(r.byte())) * int64_t(1 + r.byte())); break;
      case 2: ps.set(key, r.number()); break;
      case 3: {
        std::vector<double> v(r.byte() % 20);
        for (double& x : v) x = r.number();
        ps.set(key, v);
        break;
      }
      case 4: ps.set(key, sg::TextureRef{uint32_t(r.byte() % 3)}); break;
      default: {
        const auto& d = info.params.empty() ? sg::ParamDecl() : info.params[r.byte() % info.params.size()];
        ps.set(key, d.choices.empty() ? std::string(1, char(r.byte())) : d.choices[r.byte() % d.choices.size()]);
      }
    }
  }
  try {
    sg::Scene scene;
    uint32_t tex = scene.add_texture("constant", sg::ParamSet());
    (void)tex;
    if (kind == "material") scene.add_material(name, ps);
    else if (kind == "light") scene.add_light(name, ps);
    else if (kind == "texture") scene.add_texture(name, ps);
    else if (kind == "camera") sg::PinholeCamera::from_params(ps);
    else sg::RenderSettings::from_params(ps);
  } catch (const sg::Error&) {
  }
  return 0;
}
