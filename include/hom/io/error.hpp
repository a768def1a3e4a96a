#pragma once
/// @file error.hpp
/// Errors of the file readers and writers, and atomic file output.
///
/// Every I/O failure is an `IoError` (a std::runtime_error) with a one-line
/// message that names the file. Malformed input is a `ParseError`, whose
/// message is "FILE:LINE: what" (LINE counts from 1; in a binary section it is
/// the line the offending byte falls on, with the byte offset in the text).
///
/// Writers never leave a half-written file: they write FILE.tmp and rename it
/// to FILE only once everything is written (`write_atomically`).

#include <cstdio>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <system_error>

namespace hom::io {

class IoError : public std::runtime_error {
 public:
  explicit IoError(const std::string& what) : std::runtime_error(what) {}
};

class ParseError : public IoError {
 public:
  ParseError(std::string file, std::size_t line, const std::string& what)
      : IoError(file + ":" + std::to_string(line) + ": " + what), file_(std::move(file)), line_(line) {}
  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }

 private:
  std::string file_;
  std::size_t line_;
};

/// Runs `write(FILE*)` on PATH.tmp, then renames it to PATH. On any failure
/// (the callback throws, or a write error) the temporary is removed and an
/// IoError (or the callback's exception) propagates; PATH is untouched.
inline void write_atomically(const std::string& path, const std::function<void(std::FILE*)>& write) {
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw IoError(path + ": cannot open for writing (" + tmp + ")");
  try {
    write(f);
  } catch (...) {
    std::fclose(f);
    std::remove(tmp.c_str());
    throw;
  }
  const bool bad = std::ferror(f) != 0;
  if (std::fclose(f) != 0 || bad) {
    std::remove(tmp.c_str());
    throw IoError(path + ": write error");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw IoError(path + ": cannot rename " + tmp + " (" + ec.message() + ")");
  }
}

/// Writes a whole buffer, throwing IoError on a short write.
inline void write_all(std::FILE* f, const std::string& path, const char* data, std::size_t n) {
  if (n && std::fwrite(data, 1, n, f) != n) throw IoError(path + ": write error");
}

}  // namespace hom::io
