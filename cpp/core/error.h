// The exception type of synthgen. Bound to Python as synthgen.SynthgenError
// (a subclass of ValueError), so every bad input surfaces as a Python exception.
#pragma once

#include <stdexcept>
#include <string>

namespace sg {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

/// Error raised when a file cannot be read or parsed; the message names the file.
class FileError : public Error {
 public:
  FileError(const std::string& path, const std::string& reason)
      : Error(path + ": " + reason), m_path(path) {}
  const std::string& path() const { return m_path; }
  /// The same error with `context` ("material 3") in front of the message.
  FileError with_context(const std::string& context) const { return FileError(m_path, context + ": " + what(), 0); }

 private:
  FileError(const std::string& path, const std::string& message, int) : Error(message), m_path(path) {}

 private:
  std::string m_path;
};

}  // namespace sg
