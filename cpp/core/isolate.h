// Reading untrusted files in a separate process with time and memory limits.
//
// synthgen reads users' files through third-party libraries (assimp, OpenImageIO and the
// format libraries under it) that are not hardened against hostile input: a crash inside
// them cannot be caught in-process, and a loop inside them cannot be interrupted. The
// readers therefore run in `synthgen-reader` (cpp/reader/main.cpp), a small executable
// kept running beside the process that uses it (a server per concurrent reader): it decodes
// a file and writes the result as bytes (Writer) into an in-memory file; the parent checks
// what comes back (Reader: bounded, typed reads). A crash, a hang or a runaway allocation
// of the reader becomes an sg::FileError naming the file, so a broken file never takes down
// a run.
//
// NOTE: the reader is exec'd, not merely forked: a forked copy of a multi-threaded process
// inherits locks held by threads that do not exist in the child (OpenEXR's and OpenImageIO's
// thread pools, Python's threads) and can deadlock; between fork and exec the child only
// makes async-signal-safe calls (POSIX.1-2017, fork(), "Application Usage").
#pragma once

#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.h"

namespace sg {

struct IsolationLimits {
  unsigned seconds = 60;                      ///< CPU and wall-clock time of the reader
  uint64_t memory_bytes = uint64_t(8) << 30;  ///< the reader's address space (not under AddressSanitizer)
};

/// Read-only bytes that own their storage (a vector, or the mapping of a reader's output).
class Bytes {
 public:
  Bytes() = default;
  explicit Bytes(std::vector<char> v);
  Bytes(const char* data, size_t size, std::shared_ptr<const void> owner)
      : m_data(data), m_size(size), m_owner(std::move(owner)) {}
  const char* data() const { return m_data; }
  size_t size() const { return m_size; }
  std::string str() const { return std::string(m_data, m_size); }

 private:
  const char* m_data = nullptr;
  size_t m_size = 0;
  std::shared_ptr<const void> m_owner;
};

/// Runs `argv` (argv[0]: the program's path) as a child process with `limits`, standard
/// input from /dev/null and standard output into an in-memory file, and returns what it
/// wrote after the status byte of the protocol (0: the result follows; 1: an error message
/// follows). An error message is thrown as FileError(path, message); a child that crashes,
/// times out, runs out of memory or does not follow the protocol gives FileError(path, what
/// happened).
Bytes run_isolated(const std::string& path, const std::vector<std::string>& argv, const IsolationLimits& limits = {});

/// The synthgen-reader executable: $SYNTHGEN_READER, else `synthgen-reader` next to the
/// library or executable holding this code. Throws Error if there is none.
std::string reader_executable();

/// Reads `path` with synthgen-reader's command `args`, or, with SYNTHGEN_NO_ISOLATION=1 in the
/// environment (debugging, fuzzing), with `in_process` here. sg::Error from `in_process`
/// becomes FileError(path, message). `fresh`: a new reader process for this file alone
/// (assimp: a reader that survived a file may have had its heap corrupted by it, so it is not
/// reused), else a kept reader (image decoding: starting one loads OpenImageIO's libraries).
Bytes read_isolated(const std::string& path, const std::vector<std::string>& args,
                    const std::function<std::vector<char>()>& in_process, bool fresh = false);

/// The reader's side of the protocol: runs `work`, writes status and result (or the error
/// message, with `path` removed from its front) to `fd`; returns the exit code.
int reader_respond(int fd, const std::string& path, const std::function<std::vector<char>()>& work);

/// The reader's server loop (`synthgen-reader --serve`): requests arrive on standard input
/// (a socket); `dispatch` maps a request's arguments (a command, the path, options) to the
/// result bytes, or throws. Returns the exit code when the socket closes.
int reader_serve(unsigned seconds, const std::function<std::vector<char>(const std::vector<std::string>&)>& dispatch);

/// Appends typed values to a byte buffer (the reader's side).
class Writer {
 public:
  std::vector<char> bytes;
  template <class T>
  void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const char* p = reinterpret_cast<const char*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    pod(uint64_t(v.size()));
    const char* p = reinterpret_cast<const char*>(v.data());
    bytes.insert(bytes.end(), p, p + v.size() * sizeof(T));
  }
  void str(const std::string& s) {
    pod(uint64_t(s.size()));
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
};

/// Reads typed values back, refusing to read past the end (the parent's side).
class Reader {
 public:
  Reader(const char* data, size_t size, std::string what) : m_data(data), m_size(size), m_what(std::move(what)) {}
  Reader(const Bytes& b, std::string what) : Reader(b.data(), b.size(), std::move(what)) {}
  Reader(const std::vector<char>& b, std::string what) : Reader(b.data(), b.size(), std::move(what)) {}
  template <class T>
  T pod() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T));
    T v;
    std::memcpy(&v, m_data + m_pos, sizeof(T));
    m_pos += sizeof(T);
    return v;
  }
  template <class T>
  std::vector<T> vec() {
    uint64_t n = pod<uint64_t>();
    if (n > (m_size - m_pos) / sizeof(T)) fail();
    std::vector<T> v(static_cast<size_t>(n));
    if (n) std::memcpy(static_cast<void*>(v.data()), m_data + m_pos, size_t(n) * sizeof(T));
    m_pos += size_t(n) * sizeof(T);
    return v;
  }
  std::string str() {
    uint64_t n = pod<uint64_t>();
    need(n);
    std::string s(m_data + m_pos, size_t(n));
    m_pos += size_t(n);
    return s;
  }
  bool done() const { return m_pos == m_size; }

 private:
  void need(uint64_t n) {
    if (n > m_size - m_pos) fail();
  }
  [[noreturn]] void fail() { throw FileError(m_what, "malformed data from the isolated reader"); }
  const char* m_data;
  size_t m_size;
  std::string m_what;
  size_t m_pos = 0;
};

}  // namespace sg
