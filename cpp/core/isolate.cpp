#include "core/isolate.h"

#include <dlfcn.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <new>

extern char** environ;

namespace sg {

Bytes::Bytes(std::vector<char> v) {
  auto owner = std::make_shared<std::vector<char>>(std::move(v));
  m_data = owner->data();
  m_size = owner->size();
  m_owner = owner;
}

namespace {

bool write_all(int fd, const char* p, size_t n) {
  while (n) {
    ssize_t w = write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= size_t(w);
  }
  return true;
}

std::string signal_text(int sig) {
  switch (sig) {
    case SIGSEGV: return "a segmentation fault (SIGSEGV)";
    case SIGABRT: return "an abort (SIGABRT)";
    case SIGBUS: return "a bus error (SIGBUS)";
    case SIGFPE: return "an arithmetic fault (SIGFPE)";
    case SIGILL: return "an illegal instruction (SIGILL)";
    default: return "signal " + std::to_string(sig);
  }
}

double now_seconds() {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

bool isolation_disabled() {
  const char* off = std::getenv("SYNTHGEN_NO_ISOLATION");
  return off && *off && std::string(off) != "0";
}

void reap(pid_t pid, int* status) {
  while (waitpid(pid, status, 0) < 0 && errno == EINTR) {
  }
}

/// Starts argv with `fd_map` ((from, to) descriptor pairs); stdin is /dev/null unless mapped.
pid_t spawn(const std::string& path, const std::vector<std::string>& argv, const std::vector<std::pair<int, int>>& fd_map) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  bool maps_stdin = false;
  for (auto [from, to] : fd_map) maps_stdin = maps_stdin || to == 0;
  if (!maps_stdin) posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  for (auto [from, to] : fd_map) posix_spawn_file_actions_adddup2(&actions, from, to);
  // NOTE: transparent huge pages for the reader's heap (glibc >= 2.35 tunable; ignored by
  // older ones): a fresh process page-faults every buffer a reader clears (assimp's OBJ reader
  // clears 16 MiB), and 2 MiB pages make that ~3x faster here (77 -> 25 ms per OBJ file).
  std::vector<char*> env;
  bool has_tunables = false;
  for (char** e = environ; e && *e; ++e) {
    has_tunables = has_tunables || std::strncmp(*e, "GLIBC_TUNABLES=", 15) == 0;
    env.push_back(*e);
  }
  static char k_tunables[] = "GLIBC_TUNABLES=glibc.malloc.hugetlb=1";
  if (!has_tunables) env.push_back(k_tunables);
  env.push_back(nullptr);
  pid_t pid = 0;
  // NOTE: posix_spawn, not fork + exec: glibc starts the child with clone(CLONE_VM |
  // CLONE_VFORK), which costs the same whatever the parent's size and runs nothing of the
  // parent's in the child before exec.
  int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), env.data());
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw FileError(path, "cannot start the isolated reader " + argv[0] + " (" + std::strerror(rc) + ")");
  return pid;
}

/// Waits for `pid` to exit until `deadline`; false on timeout (the child still runs).
bool wait_until(pid_t pid, double deadline, int* status) {
  // NOTE: a pidfd (Linux >= 5.3) becomes readable when the process exits, so the wait is one
  // poll with a timeout; without it, waitpid(WNOHANG) is polled every millisecond.
  int pidfd = int(syscall(SYS_pidfd_open, pid, 0));
  bool exited = false;
  for (;;) {
    pid_t r = waitpid(pid, status, WNOHANG);
    if (r == pid || (r < 0 && errno != EINTR)) {
      exited = true;
      break;
    }
    double left = deadline - now_seconds();
    if (left <= 0) break;
    if (pidfd >= 0) {
      struct pollfd p = {pidfd, POLLIN, 0};
      poll(&p, 1, int(std::min(left, 1.0) * 1000.0) + 1);
    } else {
      struct timespec ms = {0, 1000000};
      nanosleep(&ms, nullptr);
    }
  }
  if (pidfd >= 0) close(pidfd);
  return exited;
}

int new_output(const std::string& path) {
  int fd = memfd_create("synthgen-reader-output", MFD_CLOEXEC);
  if (fd < 0) throw FileError(path, std::string("cannot create the isolated reader's output (") + std::strerror(errno) + ")");
  return fd;
}

/// The bytes written to an output file (mapped), and the file closed.
Bytes take_output(const std::string& path, int fd) {
  struct stat info;
  size_t n = fstat(fd, &info) == 0 ? size_t(info.st_size) : 0;
  if (!n) {
    close(fd);
    return Bytes();
  }
  void* m = mmap(nullptr, n, PROT_READ, MAP_PRIVATE, fd, 0);
  int err = errno;
  close(fd);
  if (m == MAP_FAILED) throw FileError(path, std::string("cannot map the isolated reader's output (") + std::strerror(err) + ")");
  return Bytes(static_cast<const char*>(m), n, std::shared_ptr<const void>(m, [n](const void* p) {
                 munmap(const_cast<void*>(p), n);
               }));
}

[[noreturn]] void throw_for_exit(const std::string& path, const std::string& program, int st, bool timed_out,
                                 const IsolationLimits& limits, size_t output_size) {
  if (timed_out || (WIFSIGNALED(st) && (WTERMSIG(st) == SIGALRM || WTERMSIG(st) == SIGXCPU)))
    throw FileError(path, "reading did not finish within " + std::to_string(limits.seconds) +
                              " s (a corrupt or hostile file made the reader loop)");
  if (WIFSIGNALED(st) && WTERMSIG(st) == SIGXFSZ)
    throw FileError(path, "the reader's output exceeded its limit of " + std::to_string(limits.memory_bytes >> 20) + " MiB");
  if (WIFSIGNALED(st))
    throw FileError(path, "the reader crashed with " + signal_text(WTERMSIG(st)) + " on this file (a corrupt or hostile file)");
  throw FileError(path, "the isolated reader " + program + " failed (exit status " +
                            std::to_string(WIFEXITED(st) ? WEXITSTATUS(st) : -1) + ", " + std::to_string(output_size) +
                            " bytes of output)");
}

/// The protocol's result: status byte 0 + result, or 1 + error message.
Bytes parse_output(const std::string& path, const std::string& program, const Bytes& out, int st) {
  if (out.size() == 0 || (out.data()[0] != 0 && out.data()[0] != 1)) throw_for_exit(path, program, st, false, {}, out.size());
  if (out.data()[0] == 1) throw FileError(path, std::string(out.data() + 1, out.size() - 1));
  return Bytes(out.data() + 1, out.size() - 1, std::shared_ptr<const void>(std::make_shared<Bytes>(out), nullptr));
}

}  // namespace

Bytes run_isolated(const std::string& path, const std::vector<std::string>& argv, const IsolationLimits& limits) {
  if (argv.empty()) throw Error("run_isolated: no program");
  // The reader's standard output is an in-memory file: nothing to drain while waiting, and
  // the result is mapped, not copied through a pipe in 64 KiB pieces.
  int out = new_output(path);
  pid_t pid;
  try {
    pid = spawn(path, argv, {{out, 1}});
  } catch (...) {
    close(out);
    throw;
  }
  // The reader limits its own CPU time (RLIMIT_CPU) and sets an alarm; this wall-clock guard
  // covers a reader that waits on something forever.
  int st = 0;
  bool timed_out = !wait_until(pid, now_seconds() + double(limits.seconds) + 5.0, &st);
  if (timed_out) {
    kill(pid, SIGKILL);
    reap(pid, &st);
  }
  Bytes bytes = take_output(path, out);
  if (timed_out || !WIFEXITED(st)) throw_for_exit(path, argv[0], st, timed_out, limits, bytes.size());
  Bytes result = parse_output(path, argv[0], bytes, st);
  if (WEXITSTATUS(st) != 0) throw_for_exit(path, argv[0], st, false, limits, bytes.size());
  return result;
}

std::string reader_executable() {
  if (const char* env = std::getenv("SYNTHGEN_READER"); env && *env) return env;
  Dl_info info;
  std::string tried;
  if (dladdr(reinterpret_cast<void*>(&reader_executable), &info) && info.dli_fname) {
    std::filesystem::path p = std::filesystem::absolute(info.dli_fname).parent_path() / "synthgen-reader";
    if (access(p.c_str(), X_OK) == 0) return p.string();
    tried = p.string();
  }
  throw Error("cannot find the isolated file reader synthgen-reader (looked for " + tried +
              "); set SYNTHGEN_READER to its path, or SYNTHGEN_NO_ISOLATION=1 to read files in-process");
}

// Reader servers ------------------------------------------------------------------------
//
// Starting a reader costs ~0.4 s once OpenImageIO's libraries are loaded, so readers are
// kept: `synthgen-reader --serve` answers requests on a socket until the socket closes. A
// request is the command's arguments plus an in-memory file (passed with SCM_RIGHTS) for
// the output; the reply is one byte once the output is written. A reader that crashes or
// times out is killed and not reused; requests from several threads use several readers.

namespace {

struct Server {
  pid_t pid = -1;
  int sock = -1;
};

constexpr size_t k_max_idle_servers = 8;
constexpr size_t k_max_request = 64 * 1024;

std::mutex g_servers_mutex;
std::vector<Server> g_idle_servers;
pid_t g_servers_owner = 0;

void stop_server(Server s) {
  close(s.sock);  // the reader exits at end of input
  int st;
  reap(s.pid, &st);
}

/// An idle reader, or a new one. Readers inherited through fork() belong to the parent.
Server acquire_server(const std::string& path, const IsolationLimits& limits) {
  {
    std::lock_guard<std::mutex> lock(g_servers_mutex);
    if (g_servers_owner != getpid()) {
      for (const Server& s : g_idle_servers) close(s.sock);  // the parent's; not ours to stop
      g_idle_servers.clear();
      g_servers_owner = getpid();
    }
    if (!g_idle_servers.empty()) {
      Server s = g_idle_servers.back();
      g_idle_servers.pop_back();
      return s;
    }
  }
  int sv[2];
  if (socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv) != 0)
    throw FileError(path, std::string("cannot create a socket for the isolated reader (") + std::strerror(errno) + ")");
  int null_out = open("/dev/null", O_WRONLY | O_CLOEXEC);
  Server s;
  try {
    s.pid = spawn(path,
                  {reader_executable(), "--seconds", std::to_string(limits.seconds), "--memory",
                   std::to_string(limits.memory_bytes), "--serve"},
                  {{sv[1], 0}, {null_out, 1}});
  } catch (...) {
    close(sv[0]);
    close(sv[1]);
    close(null_out);
    throw;
  }
  close(sv[1]);
  close(null_out);
  s.sock = sv[0];
  return s;
}

void release_server(Server s) {
  std::lock_guard<std::mutex> lock(g_servers_mutex);
  if (g_servers_owner == getpid() && g_idle_servers.size() < k_max_idle_servers) {
    g_idle_servers.push_back(s);
    return;
  }
  stop_server(s);
}

bool send_request(const Server& s, const std::vector<char>& request, int out_fd) {
  struct iovec iov = {const_cast<char*>(request.data()), request.size()};
  alignas(struct cmsghdr) char control[CMSG_SPACE(sizeof(int))] = {};
  struct msghdr msg = {};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  struct cmsghdr* c = CMSG_FIRSTHDR(&msg);
  c->cmsg_level = SOL_SOCKET;
  c->cmsg_type = SCM_RIGHTS;
  c->cmsg_len = CMSG_LEN(sizeof(int));
  std::memcpy(CMSG_DATA(c), &out_fd, sizeof(int));
  for (;;) {
    ssize_t n = sendmsg(s.sock, &msg, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    return n == ssize_t(request.size());
  }
}

}  // namespace

Bytes read_isolated(const std::string& path, const std::vector<std::string>& args,
                    const std::function<std::vector<char>()>& in_process, bool fresh) {
  if (isolation_disabled()) {
    try {
      return Bytes(in_process());
    } catch (const FileError&) {
      throw;
    } catch (const Error& e) {
      throw FileError(path, e.what());
    }
  }
  IsolationLimits limits;
  if (fresh) {
    std::vector<std::string> argv = {reader_executable(), "--seconds", std::to_string(limits.seconds), "--memory",
                                     std::to_string(limits.memory_bytes)};
    argv.insert(argv.end(), args.begin(), args.end());
    return run_isolated(path, argv, limits);
  }
  Writer w;
  w.pod(uint32_t(args.size()));
  for (const std::string& a : args) w.str(a);
  if (w.bytes.size() > k_max_request) throw FileError(path, "the path is too long for the isolated reader");
  // A reader that was idle may have been stopped from outside (a failed send): one retry
  // with a new reader.
  for (int attempt = 0;; ++attempt) {
    Server s = acquire_server(path, limits);
    int out = new_output(path);
    if (!send_request(s, w.bytes, out)) {
      close(out);
      kill(s.pid, SIGKILL);
      stop_server(s);
      if (attempt == 0) continue;
      throw FileError(path, "cannot send the request to the isolated reader");
    }
    // The reply, or the reader's end: the wall-clock guard covers a reader that waits
    // forever (its own CPU limit and alarm cover a loop).
    const double deadline = now_seconds() + double(limits.seconds) + 5.0;
    char reply = 0;
    ssize_t got = -1;
    bool timed_out = false;
    for (;;) {
      int left_ms = int((deadline - now_seconds()) * 1000.0);
      if (left_ms <= 0) {
        timed_out = true;
        break;
      }
      struct pollfd p = {s.sock, POLLIN, 0};
      int r = poll(&p, 1, std::min(left_ms, 1000));
      if (r < 0 && errno != EINTR) break;
      if (r <= 0) continue;
      got = recv(s.sock, &reply, 1, 0);
      if (got < 0 && errno == EINTR) continue;
      break;
    }
    if (got == 1 && reply == 'd') {
      release_server(s);
      Bytes bytes = take_output(path, out);
      return parse_output(path, "synthgen-reader", bytes, 0);
    }
    // The reader died or hung on this file.
    if (timed_out) kill(s.pid, SIGKILL);
    close(s.sock);
    int st = 0;
    reap(s.pid, &st);
    Bytes bytes = take_output(path, out);
    throw_for_exit(path, "synthgen-reader", st, timed_out, limits, bytes.size());
  }
}

int reader_respond(int fd, const std::string& path, const std::function<std::vector<char>()>& work) {
  char status = 0;
  std::vector<char> out;
  try {
    out = work();
  } catch (const std::bad_alloc&) {
    status = 1;
    std::string m = "out of memory while reading (more than the reader's limit)";
    out.assign(m.begin(), m.end());
  } catch (const std::exception& e) {
    status = 1;
    // A FileError's message starts with the path; the parent adds it again.
    std::string m = e.what();
    if (m.rfind(path + ": ", 0) == 0) m = m.substr(path.size() + 2);
    out.assign(m.begin(), m.end());
  }
  bool ok = write_all(fd, &status, 1) && write_all(fd, out.data(), out.size());
  return ok ? 0 : 3;
}

int reader_serve(unsigned seconds, const std::function<std::vector<char>(const std::vector<std::string>&)>& dispatch) {
  std::vector<char> buf(k_max_request);
  for (;;) {
    struct iovec iov = {buf.data(), buf.size()};
    alignas(struct cmsghdr) char control[CMSG_SPACE(sizeof(int))] = {};
    struct msghdr msg = {};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    ssize_t n = recvmsg(0, &msg, MSG_CMSG_CLOEXEC);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return 0;  // the parent is gone or done
    int fd = -1;
    for (struct cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c))
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_RIGHTS) std::memcpy(&fd, CMSG_DATA(c), sizeof(int));
    if (fd < 0 || (msg.msg_flags & (MSG_TRUNC | MSG_CTRUNC))) return 2;
    std::vector<std::string> args;
    try {
      Reader r(buf.data(), size_t(n), "request");
      uint32_t count = r.pod<uint32_t>();
      if (count > 16) return 2;
      for (uint32_t i = 0; i < count; ++i) args.push_back(r.str());
    } catch (const Error&) {
      return 2;
    }
    // This request's CPU time: the limit is cumulative, so it is moved on each time.
    struct rusage use;
    getrusage(RUSAGE_SELF, &use);
    rlim_t used = rlim_t(use.ru_utime.tv_sec + use.ru_stime.tv_sec) + 1;
    struct rlimit cpu = {used + seconds, used + seconds + 1};
    setrlimit(RLIMIT_CPU, &cpu);
    alarm(seconds);
    std::string path = args.size() > 1 ? args[1] : "";
    reader_respond(fd, path, [&] { return dispatch(args); });
    alarm(0);
    close(fd);
    char done = 'd';
    if (send(0, &done, 1, MSG_NOSIGNAL) != 1) return 0;
  }
}

}  // namespace sg
