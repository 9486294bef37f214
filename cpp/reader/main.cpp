// synthgen-reader: decodes untrusted files in its own process (core/isolate.h).
//
//   synthgen-reader [--seconds S] [--memory BYTES] mesh PATH
//   synthgen-reader [--seconds S] [--memory BYTES] image PATH auto|srgb|linear [finite|nonfinite]
//   synthgen-reader [--seconds S] [--memory BYTES] --serve
//
// Sets its own CPU-time and address-space limits and reads files with the same code the
// library uses in-process: one file, written to standard output, or (--serve) the requests
// that arrive on standard input, as core/isolate.h sends them.
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/isolate.h"
#include "io/image_io.h"
#include "io/mesh_io.h"

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: synthgen-reader [--seconds S] [--memory BYTES] mesh PATH\n"
               "       synthgen-reader [--seconds S] [--memory BYTES] image PATH auto|srgb|linear [finite|nonfinite]\n"
               "       synthgen-reader [--seconds S] [--memory BYTES] --serve\n");
  return 2;
}

std::vector<char> dispatch(const std::vector<std::string>& args) {
  if (args.size() == 2 && args[0] == "mesh") return sg::import_mesh_file_bytes(args[1]);
  if ((args.size() == 3 || args.size() == 4) && args[0] == "image") {
    const std::string& s = args[2];
    sg::ColorSpace space = s == "srgb" ? sg::ColorSpace::SRGB : s == "linear" ? sg::ColorSpace::Linear : sg::ColorSpace::Auto;
    return sg::load_image_bytes(args[1], space, args.size() == 4 && args[3] == "nonfinite");
  }
  throw sg::Error("synthgen-reader: unknown request");
}

}  // namespace

int main(int argc, char** argv) {
  unsigned long long seconds = 60, memory = 0;
  bool serve = false;
  int i = 1;
  for (; i < argc && argv[i][0] == '-'; ++i) {
    std::string k = argv[i];
    if (k == "--serve") {
      serve = true;
    } else if (k == "--seconds" && i + 1 < argc) {
      seconds = std::strtoull(argv[++i], nullptr, 10);
    } else if (k == "--memory" && i + 1 < argc) {
      memory = std::strtoull(argv[++i], nullptr, 10);
    } else {
      return usage();
    }
  }
#if defined(__SANITIZE_ADDRESS__)
  const bool asan = true;
#elif defined(__has_feature)
  const bool asan = __has_feature(address_sanitizer);
#else
  const bool asan = false;
#endif
  // AddressSanitizer reserves terabytes of shadow memory: no address-space limit under it.
  if (memory && !asan) {
    struct rlimit as = {rlim_t(memory), rlim_t(memory)};
    setrlimit(RLIMIT_AS, &as);
  }
  if (memory) {
    // The output (an in-memory file of the parent's) is bounded too.
    struct rlimit fsize = {rlim_t(memory), rlim_t(memory)};
    setrlimit(RLIMIT_FSIZE, &fsize);
  }
  if (serve) return i == argc ? sg::reader_serve(unsigned(seconds), dispatch) : usage();
  std::vector<std::string> args(argv + i, argv + argc);
  if (args.size() < 2) return usage();
  struct rlimit cpu = {rlim_t(seconds), rlim_t(seconds + 1)};
  setrlimit(RLIMIT_CPU, &cpu);
  alarm(unsigned(seconds));
  return sg::reader_respond(1, args[1], [&] { return dispatch(args); });
}
