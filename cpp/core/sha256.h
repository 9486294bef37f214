// SHA-256 (FIPS 180-4), incremental: the content hash by which the change journal records the
// files it names (api/scene_journal.cpp) -- the same digest as Python's hashlib.sha256, so that
// both sides name a file's content alike. Computed by OpenSSL's libcrypto (core/sha256.cpp, the
// only file using its API): a maintained, tested implementation rather than one of our own.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

namespace sg {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  void update(const void* data, size_t n);
  /// The digest as 64 lowercase hex digits (the object is spent afterwards).
  std::string hex();

  /// True when `s` is a digest as hex() writes it (64 lowercase hex digits).
  static bool is_hex_digest(const std::string& s) {
    if (s.size() != 64) return false;
    for (char c : s)
      if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
    return true;
  }

 private:
  struct State;
  std::unique_ptr<State> m_state;
};

}  // namespace sg
