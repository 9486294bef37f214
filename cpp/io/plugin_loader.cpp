#include "io/plugin_loader.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>

namespace sg {

std::vector<std::string> plugin_candidates(const char* file_name, const char* env_var) {
  std::vector<std::string> candidates;
  if (const char* env = std::getenv(env_var)) candidates.push_back(env);
  Dl_info info;
  if (dladdr(reinterpret_cast<void*>(&plugin_candidates), &info) && info.dli_fname) {
    std::filesystem::path here = std::filesystem::path(info.dli_fname).parent_path();
    candidates.push_back((here / file_name).string());
  }
  candidates.push_back(file_name);  // LD_LIBRARY_PATH / system
  return candidates;
}

void* plugin_symbol(const std::string& path, const char* symbol, std::string* errors) {
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) {
    const char* e = dlerror();
    *errors += "\n  " + path + ": " + (e ? e : "unknown error");
    return nullptr;
  }
  void* sym = dlsym(handle, symbol);
  if (!sym) *errors += "\n  " + path + ": no " + symbol + " (not a synthgen plugin)";
  return sym;
}

}  // namespace sg
