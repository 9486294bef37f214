// Opens synthgen's own plugin libraries (libsynthgen_oiio.so, libsynthgen_vdb.so) on first use:
// libraries whose dependencies are slow to load stay out of `import synthgen` until needed.
#pragma once

#include <string>
#include <vector>

namespace sg {

/// Where plugin `file_name` is looked for, in order: $`env_var` when set, next to the binary that
/// holds the core (the Python module, the reader, a test), then the dynamic linker's search.
std::vector<std::string> plugin_candidates(const char* file_name, const char* env_var);

/// dlopen()s `path` and returns the address of its `symbol` (nullptr, with the reason appended to
/// `errors`, when either fails).
void* plugin_symbol(const std::string& path, const char* symbol, std::string* errors);

/// The entry point `symbol` (a function returning const Api*) of the first candidate plugin whose
/// Api has `version`; nullptr with every candidate's reason in `errors` otherwise.
template <class Api>
const Api* load_plugin_api(const char* file_name, const char* env_var, const char* symbol, int version,
                           const char* what, std::string* errors) {
  for (const std::string& c : plugin_candidates(file_name, env_var)) {
    auto fn = reinterpret_cast<const Api* (*)()>(plugin_symbol(c, symbol, errors));
    if (!fn) continue;
    const Api* api = fn();
    if (api && api->version == version) return api;
    *errors += "\n  " + c + ": not a compatible synthgen " + what + " plugin";
  }
  return nullptr;
}

}  // namespace sg
