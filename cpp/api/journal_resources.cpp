// Files a change journal names, by content; see journal_resources.h.
#include "api/journal_resources.h"

#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <tuple>

#include "api/xml_util.h"
#include "core/error.h"
#include "core/plugin.h"
#include "core/sha256.h"

namespace sg {

using namespace xml;  // NOLINT: append_blob / read_blob of the journal's sidecar

namespace {

/// Files of at most this many bytes are embedded in the journal's sidecar; larger ones go to
/// the resource store. Also the bound of an embedded resource a journal may claim.
constexpr uint64_t k_embed_max = uint64_t(1) << 20;

/// $SYNTHGEN_CACHE/resources (default ~/.cache/synthgen/resources): synthgen.scene.assets's
/// cache directory.
std::filesystem::path resource_store() {
  const char* c = std::getenv("SYNTHGEN_CACHE");
  if (c && *c) return std::filesystem::path(c) / "resources";
  const char* home = std::getenv("HOME");
  return std::filesystem::path(home && *home ? home : ".") / ".cache" / "synthgen" / "resources";
}

/// The extension of `path` when it is short and alphanumeric (".exr"), else "": a stored copy
/// keeps it (readers pick the format by it); nothing of a hostile path gets further.
std::string safe_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (ext.size() < 2 || ext.size() > 10) return "";
  for (size_t i = 1; i < ext.size(); ++i)
    if (!std::isalnum(static_cast<unsigned char>(ext[i]))) return "";
  return ext;
}

/// The sha256 of a file's content and its size; false (and `error`) when it cannot be read.
/// `copy_to` (non-empty): the bytes are also written there.
bool hash_file(const std::filesystem::path& path, std::string* sha, uint64_t* size, std::string* error,
               const std::filesystem::path& copy_to = {}) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = "cannot open it";
    return false;
  }
  std::ofstream out;
  if (!copy_to.empty()) {
    out.open(copy_to, std::ios::binary | std::ios::trunc);
    if (!out) {
      *error = "cannot write " + copy_to.string();
      return false;
    }
  }
  Sha256 h;
  std::vector<char> block(1 << 20);
  *size = 0;
  while (in) {
    in.read(block.data(), std::streamsize(block.size()));
    std::streamsize got = in.gcount();
    if (got <= 0) break;
    h.update(block.data(), size_t(got));
    if (out.is_open()) out.write(block.data(), got);
    *size += uint64_t(got);
  }
  if (in.bad()) {
    *error = "read error";
    return false;
  }
  if (out.is_open() && !out.flush()) {
    *error = "cannot write " + copy_to.string();
    return false;
  }
  *sha = h.hex();
  return true;
}

/// hash_file, remembered per (path, size, modification time): a run saving every frame's
/// journal hashes its large files once.
bool hash_file_cached(const std::string& path, std::string* sha, uint64_t* size, std::string* error) {
  static std::mutex mutex;
  static std::map<std::string, std::tuple<uint64_t, int64_t, std::string>> known;
  std::error_code ec;
  const uint64_t fsize = std::filesystem::file_size(path, ec);
  const auto mtime = ec ? 0 : std::filesystem::last_write_time(path, ec).time_since_epoch().count();
  if (!ec) {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = known.find(path);
    if (it != known.end() && std::get<0>(it->second) == fsize && std::get<1>(it->second) == int64_t(mtime)) {
      *sha = std::get<2>(it->second);
      *size = fsize;
      return true;
    }
  }
  if (!hash_file(path, sha, size, error)) return false;
  if (!ec && *size == fsize) {
    std::lock_guard<std::mutex> lock(mutex);
    known[path] = {fsize, int64_t(mtime), *sha};
  }
  return true;
}

/// A temporary name next to `dest`, unique in this process and among processes.
std::filesystem::path temp_name(const std::filesystem::path& dest) {
  static std::atomic<uint64_t> counter{0};
  return dest.string() + ".tmp" + std::to_string(getpid()) + "-" + std::to_string(counter++);
}

/// Copies `src` (content `sha`) into the store as SHA.EXT unless it is there; "" or the reason
/// it could not.
std::string store_file(const std::string& src, const std::string& sha, uint64_t size) {
  std::error_code ec;
  const std::filesystem::path dir = resource_store();
  const std::filesystem::path dest = dir / (sha + safe_extension(src));
  if (std::filesystem::is_regular_file(dest, ec) && std::filesystem::file_size(dest, ec) == size && !ec) return "";
  std::filesystem::create_directories(dir, ec);
  if (ec) return "cannot create " + dir.string() + ": " + ec.message();
  const std::filesystem::path tmp = temp_name(dest);
  std::string got, error;
  uint64_t got_size = 0;
  if (!hash_file(src, &got, &got_size, &error, tmp)) {
    std::filesystem::remove(tmp, ec);
    return error;
  }
  if (got != sha) {
    std::filesystem::remove(tmp, ec);
    return "it changed while it was copied";
  }
  std::filesystem::rename(tmp, dest, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    return "cannot write " + dest.string();
  }
  return "";
}

}  // namespace

void write_resources(pugi::xml_node n, const char* kind, const std::string& type, const ParamSet& params,
                     std::ofstream& bin, std::map<std::string, uint64_t>* embedded, const char* skip) {
  const PluginInfo* info = Registry::instance().find(kind, type);
  if (!info) return;
  for (const auto& [name, value] : params.values()) {
    const std::string* file = std::get_if<std::string>(&value);
    const ParamDecl* decl = info->find(name);
    if (!file || !decl || decl->type != ParamType::Path || (skip && decl->name == skip)) continue;
    pugi::xml_node r = n.append_child("resource");
    r.append_attribute("param") = name.c_str();
    r.append_attribute("path") = file->c_str();
    std::string sha, error;
    uint64_t size = 0;
    if (!hash_file_cached(*file, &sha, &size, &error)) {
      r.append_attribute("unreadable") = error.c_str();
      continue;
    }
    std::vector<char> bytes;
    if (size <= k_embed_max) {  // embedded: the bytes read now, hashed as read
      std::ifstream in(*file, std::ios::binary);
      bytes.resize(size_t(k_embed_max) + 1);
      in.read(bytes.data(), std::streamsize(bytes.size()));
      bytes.resize(size_t(in.gcount()));
      Sha256 h;
      h.update(bytes.data(), bytes.size());
      sha = h.hex();
      size = bytes.size();
    }
    r.append_attribute("sha256") = sha.c_str();
    r.append_attribute("size") = size;
    if (size <= k_embed_max) {
      auto it = embedded->find(sha);
      if (it == embedded->end()) it = embedded->emplace(sha, append_blob(bin, bytes)).first;
      r.append_attribute("offset") = it->second;
    } else {
      std::string why = store_file(*file, sha, size);
      if (why.empty()) r.append_attribute("store") = "cache";
      else r.append_attribute("store_error") = why.c_str();
    }
  }
}

ParamSet resolve_resources(pugi::xml_node n, ParamSet params, const std::vector<char>& bin) {
  const std::filesystem::path store = resource_store();
  for (pugi::xml_node r : n.children("resource")) {
    const std::string name = r.attribute("param").as_string(), path = r.attribute("path").as_string();
    const std::string what = std::string(n.attribute("type").as_string()) + " parameter '" + name + "' (file '" +
                             path + "')";
    if (!params.has(name) || !std::get_if<std::string>(&params.values().at(name)))
      throw Error("a <resource> names parameter '" + name + "', which is not a file parameter of the operation");
    if (r.attribute("unreadable"))
      throw Error(what + ": the file could not be read when the journal was written (" +
                  r.attribute("unreadable").as_string() + "); the journal cannot replay it");
    const std::string sha = r.attribute("sha256").as_string();
    if (!Sha256::is_hex_digest(sha))
      throw Error(what + ": sha256 '" + sha.substr(0, 80) + "' is not 64 lowercase hex digits");
    const uint64_t size = uint64_t(parse_integer(r.attribute("size").as_string(), 0, INT64_MAX, what + ": size"));
    const std::filesystem::path stored = store / (sha + safe_extension(path));
    std::error_code ec;
    auto content = [&](const std::filesystem::path& p, std::string* got) {
      uint64_t sz = 0;
      std::string error;
      return std::filesystem::is_regular_file(p, ec) && hash_file(p, got, &sz, &error);
    };
    std::string got;
    if (r.attribute("offset")) {
      if (size > k_embed_max)
        throw Error(what + ": an embedded file of " + std::to_string(size) + " bytes (at most " +
                    std::to_string(k_embed_max) + " are embedded)");
      std::vector<char> bytes;
      read_blob(bin, r.attribute("offset").as_ullong(), size_t(size), &bytes, what);
      Sha256 h;
      h.update(bytes.data(), bytes.size());
      if (h.hex() != sha) throw Error(what + ": the embedded copy does not have its recorded sha256 " + sha);
      if (!(content(stored, &got) && got == sha)) {
        std::filesystem::create_directories(store, ec);
        const std::filesystem::path tmp = temp_name(stored);
        {
          std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
          if (!bytes.empty()) out.write(bytes.data(), std::streamsize(bytes.size()));
          if (!out.flush()) {
            std::filesystem::remove(tmp, ec);
            throw Error(what + ": cannot write its embedded copy to " + stored.string());
          }
        }
        std::filesystem::rename(tmp, stored, ec);
        if (ec) {
          std::filesystem::remove(tmp, ec);
          throw Error(what + ": cannot write its embedded copy to " + stored.string());
        }
      }
      params.set(name, stored.string());
      continue;
    }
    if (content(stored, &got) && got == sha) {
      params.set(name, stored.string());
      continue;
    }
    const std::string stored_note = std::filesystem::exists(stored, ec) ? " (a copy there has other content)" : "";
    std::string at_path;
    if (content(path, &at_path) && at_path == sha) {
      params.set(name, path);
      continue;
    }
    std::string msg = what + ", sha256 " + sha + ", " + std::to_string(size) + " bytes: ";
    if (!at_path.empty())
      msg += "the file at its path has changed since the journal was written (its sha256 is now " + at_path +
             ") and the resource store has no copy: looked for " + stored.string() + stored_note;
    else
      msg += "missing: looked for " + stored.string() + stored_note + " and " + path;
    if (r.attribute("store_error"))
      msg += std::string("; it could not be stored when the journal was written: ") +
             r.attribute("store_error").as_string();
    throw Error(msg);
  }
  return params;
}

}  // namespace sg
