// core/isolate.h: work in a child process, its result back, and every way the child can
// fail turned into a FileError naming the file. Plus the readers that use it (mesh import,
// image loading) and the PLY header check that keeps assimp from looping.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iterator>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "api/scene.h"
#include "core/error.h"
#include "core/isolate.h"
#include "io/image_io.h"

using namespace sg;

namespace {

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const FileError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("not a FileError: ") + e.what();
  }
  return "no error";
}

double seconds_of(const std::function<void()>& f) {
  auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string temp_file(const std::string& name, const std::string& bytes) {
  auto dir = std::filesystem::temp_directory_path() / ("sg-isolate-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

std::vector<std::string> sh(const std::string& script) { return {"/bin/sh", "-c", script}; }

uint32_t crc32(const std::string& bytes) {
  uint32_t c = 0xffffffffu;
  for (unsigned char b : bytes) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return ~c;
}

std::string be32(uint32_t v) {
  return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
}

std::string png_chunk(const std::string& type, const std::string& data) {
  return be32(uint32_t(data.size())) + type + data + be32(crc32(type + data));
}

/// A PNG with header chunk data `ihdr` and the image data of a 2 x 1 8-bit RGB image: pixels
/// (255, 0, 0) and (128, 128, 128); the zlib stream is one stored block (filter byte 0 + 6 bytes)
/// with its Adler-32.
std::string png_with_header(const std::string& ihdr) {
  std::string raw = std::string("\x00\xff\x00\x00\x80\x80\x80", 7);
  uint32_t a = 1, b = 0;
  for (unsigned char ch : raw) {
    a = (a + ch) % 65521;
    b = (b + a) % 65521;
  }
  std::string z = std::string("\x78\x01\x01", 3) + char(raw.size()) + char(0) + char(~raw.size()) + char(0xff) + raw +
                  be32((b << 16) | a);
  return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", z) +
         png_chunk("IEND", "");
}

std::string two_pixel_png() { return png_with_header(be32(2) + be32(1) + std::string("\x08\x02\x00\x00\x00", 5)); }

}  // namespace

TEST(isolate, writer_and_reader_round_trip) {
  Writer w;
  w.pod(int32_t(-7));
  w.vec(std::vector<float>{1.5f, 2.5f});
  w.str("hello");
  Reader r(w.bytes, "f");
  EXPECT_EQ(r.pod<int32_t>(), -7);
  EXPECT_EQ(r.vec<float>(), (std::vector<float>{1.5f, 2.5f}));
  EXPECT_EQ(r.str(), "hello");
  EXPECT_TRUE(r.done());
}

TEST(isolate, reader_refuses_to_read_past_the_end) {
  Writer w;
  w.pod(uint64_t(1) << 40);  // a vector length with no data behind it
  std::vector<char> bytes = w.bytes;
  Reader r(bytes, "f");
  EXPECT_THROW(r.vec<float>(), FileError);
  Reader r2(bytes, "f");
  EXPECT_THROW(r2.str(), FileError);
  std::vector<char> short_bytes(3);
  Reader r3(short_bytes, "f");
  EXPECT_THROW(r3.pod<uint32_t>(), FileError);
}

TEST(isolate, protocol_result_and_error) {
  EXPECT_EQ(run_isolated("f", sh("printf '\\000abc'")).str(), "abc");
  EXPECT_EQ(message_of([] { run_isolated("model.obj", sh("printf '\\001bad face'")); }), "model.obj: bad face");
  std::string m = message_of([] { run_isolated("model.obj", sh("exit 0")); });
  EXPECT_NE(m.find("model.obj: the isolated reader /bin/sh failed (exit status 0, 0 bytes of output)"), std::string::npos) << m;
  m = message_of([] { run_isolated("model.obj", {"/nonexistent/reader"}); });
  EXPECT_NE(m.find("cannot start the isolated reader /nonexistent/reader"), std::string::npos) << m;
}

TEST(isolate, a_crash_is_an_error) {
  std::string m = message_of([] { run_isolated("evil.ply", sh("kill -SEGV $$")); });
  EXPECT_EQ(m, "evil.ply: the reader crashed with a segmentation fault (SIGSEGV) on this file (a corrupt or hostile file)");
  m = message_of([] { run_isolated("evil.ply", sh("kill -ABRT $$")); });
  EXPECT_NE(m.find("an abort (SIGABRT)"), std::string::npos) << m;
}

TEST(isolate, a_hang_is_an_error_within_the_limit) {
  IsolationLimits lim;
  lim.seconds = 1;
  std::string m;
  // The reader's own CPU limit (SIGXCPU) and alarm (SIGALRM)...
  for (const char* sig : {"XCPU", "ALRM"}) {
    m = message_of([&] { run_isolated("loop.ply", sh(std::string("kill -") + sig + " $$"), lim); });
    EXPECT_EQ(m, "loop.ply: reading did not finish within 1 s (a corrupt or hostile file made the reader loop)");
  }
  // ...and the parent's wall-clock guard (limit + 5 s) for a reader that just waits.
  double t = seconds_of([&] { m = message_of([&] { run_isolated("wait.ply", sh("exec sleep 60"), lim); }); });
  EXPECT_NE(m.find("did not finish within 1 s"), std::string::npos) << m;
  EXPECT_GT(t, 5.5);
  EXPECT_LT(t, 9.0);
}

TEST(isolate, reader_loads_in_another_process) {
  // A 2 x 1 8-bit PNG: the reader decodes it (sRGB to linear) and sends the pixels back.
  std::string path = temp_file("two.png", two_pixel_png());
  ImageData img = load_image(path, ColorSpace::Auto);
  ASSERT_EQ(img.width, 2);
  ASSERT_EQ(img.height, 1);
  ASSERT_EQ(img.channels, 3);
  EXPECT_FLOAT_EQ(img.pixels[0], 1.f);
  EXPECT_FLOAT_EQ(img.pixels[1], 0.f);
  EXPECT_NEAR(img.pixels[3], 0.2158605f, 1e-5f);  // sRGB 128/255 decoded to linear

#if !defined(__SANITIZE_ADDRESS__)
  // The same header claiming 16000 x 16000 pixels: the reader's address-space limit turns the
  // allocation into an error, not the parent's.
  std::string big = png_with_header(be32(16000) + be32(16000) + std::string("\x08\x06\x00\x00\x00", 5));
  std::string big_path = temp_file("big.png", big);
  IsolationLimits lim;
  lim.memory_bytes = uint64_t(512) << 20;
  std::string m = message_of([&] {
    run_isolated(big_path, {reader_executable(), "--seconds", "20", "--memory", std::to_string(lim.memory_bytes), "image",
                            big_path, "auto"}, lim);
  });
  EXPECT_EQ(m, big_path + ": out of memory while decoding the image");
#endif
}

TEST(isolate, without_isolation_errors_still_name_the_file) {
  setenv("SYNTHGEN_NO_ISOLATION", "1", 1);
  std::string m = message_of([] {
    read_isolated("x.obj", {"mesh", "x.obj"}, []() -> std::vector<char> { throw Error("bad face"); });
  });
  unsetenv("SYNTHGEN_NO_ISOLATION");
  EXPECT_EQ(m, "x.obj: bad face");
}

TEST(isolate, ply_headers_that_loop_assimp_are_refused) {
  // Found by fuzz_mesh_import: a NUL in the format line sends assimp 5.2's PLY reader into
  // an endless loop. Refused by the header check in milliseconds.
  std::string evil = std::string("ply\nformat ascii \0# Vertex list\n\nv -0.5 -0.5 0.5\n", 50);
  std::string path = temp_file("evil.ply", evil);
  Scene s;
  std::string m;
  double t = seconds_of([&] { m = message_of([&] { s.load_mesh_file(path); }); });
  EXPECT_NE(m.find("PLY header line 2: contains a control byte"), std::string::npos) << m;
  EXPECT_LT(t, 2.0);
  std::string big = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                    "property float y\nproperty float z\nend_header\n" + std::string(36, '\0');
  m = message_of([&] { s.load_mesh_file(temp_file("big.ply", big)); });
  EXPECT_NE(m.find("PLY header declares more elements than the file holds (at least 48000000000 bytes of data, "
                   "the file has 36)"), std::string::npos) << m;
  m = message_of([&] { s.load_mesh_file(temp_file("open.ply", "ply\nformat ascii 1.0\nelement vertex 1\n")); });
  EXPECT_NE(m.find("no end_header line"), std::string::npos) << m;
  // A well-formed file still loads.
  std::string ok = "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 3\nproperty float x\nproperty float y\n"
                   "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                   "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_NO_THROW(s.load_mesh_file(temp_file("ok.ply", ok)));
}

TEST(isolate, only_regular_files_reach_the_readers) {
  // A directory sent libheif (OpenImageIO's format probing) into an endless allocation; a
  // device or FIFO would never end. Found by fuzz_plugin_params (an envmap file "/").
  EXPECT_EQ(message_of([] { load_image("/", ColorSpace::Auto); }), "/: is a directory, not an image");
  EXPECT_EQ(message_of([] { load_image("/dev/zero", ColorSpace::Auto); }),
            "/dev/zero: is not a regular file (a device, FIFO or socket), not an image");
  Scene s;
  EXPECT_EQ(message_of([&] { s.load_mesh_file("/dev/zero"); }),
            "/dev/zero: is not a regular file (a device, FIFO or socket), not a mesh file");
  // A PLY face of 0 indices aborted assimp's triangulation (found by fuzz_mesh_import).
  std::string ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n0\n";
  EXPECT_EQ(message_of([&] { s.load_mesh_file(temp_file("empty_face.ply", ply)); }).substr(0, 1000).find(
                "mesh 0, face 1: 0 vertex indices (a face has 1 to 65536)") != std::string::npos,
            true);
}

TEST(isolate, image_loading_runs_isolated_and_reports_the_file) {
  std::string path = temp_file("broken.png", std::string("\x89PNG\r\n\x1a\n", 8) + std::string(40, 'x'));
  std::string m = message_of([&] { load_image(path, ColorSpace::Auto); });
  EXPECT_EQ(m.rfind(path + ": ", 0), 0u) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
}

namespace {

/// Process ids of this process's synthgen-reader children (from /proc).
std::vector<pid_t> reader_children() {
  std::vector<pid_t> out;
  for (const auto& e : std::filesystem::directory_iterator("/proc")) {
    std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream f(e.path() / "stat");
    std::string stat((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    size_t close_paren = stat.rfind(')');
    if (close_paren == std::string::npos || stat.find("(synthgen-reade") == std::string::npos) continue;
    int ppid = 0;
    char state = 0;
    if (std::sscanf(stat.c_str() + close_paren + 1, " %c %d", &state, &ppid) == 2 && ppid == getpid() && state != 'Z')
      out.push_back(pid_t(std::stoi(name)));
  }
  return out;
}

}  // namespace

TEST(isolate, readers_are_reused_and_replaced_when_gone) {
  // Image readers are kept (starting one loads OpenImageIO); model readers are not.
  std::string png = temp_file("reuse.png", two_pixel_png());
  std::vector<pid_t> before = reader_children();
  load_image(png, ColorSpace::Auto);
  std::vector<pid_t> first = reader_children();
  ASSERT_EQ(first.size(), before.size() + 1);
  pid_t kept = 0;
  for (pid_t p : first)
    if (std::find(before.begin(), before.end(), p) == before.end()) kept = p;
  for (int i = 0; i < 3; ++i) load_image(png, ColorSpace::Auto);
  EXPECT_EQ(reader_children(), first);  // one reader, kept
  // A reader stopped from outside between requests is replaced; the file still loads.
  kill(kept, SIGKILL);
  usleep(100000);
  EXPECT_NO_THROW(load_image(png, ColorSpace::Auto));
  std::vector<pid_t> now = reader_children();
  ASSERT_EQ(now.size(), first.size());
  EXPECT_EQ(std::find(now.begin(), now.end(), kept), now.end());
  // An error in the reader (a bad file) keeps the reader; the next good file loads.
  std::string bad = temp_file("bad.png", std::string("\x89PNG\r\n\x1a\n", 8) + std::string(40, 'x'));
  EXPECT_NE(message_of([&] { load_image(bad, ColorSpace::Auto); }).find("bad.png: "), std::string::npos);
  EXPECT_EQ(reader_children(), now);
  EXPECT_NO_THROW(load_image(png, ColorSpace::Auto));
  // Model files get a reader of their own each, which is gone afterwards.
  std::string obj = temp_file("reuse.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  Scene s;
  s.load_mesh_file(obj);
  s.load_mesh_file(obj);
  EXPECT_EQ(reader_children(), now);
  std::string nan_obj = temp_file("bad.obj", "v 0 0 nan\nf 1 2 3\n");
  std::string m = message_of([&] { s.load_mesh_file(nan_obj); });
  EXPECT_NE(m.find("bad.obj: line 1: vertex coordinate 3 is non-finite (NaN)"), std::string::npos) << m;
}
