#pragma once
/// @file cursor.hpp
/// A reading position in an in-memory text or binary file that knows its line
/// number, for "FILE:LINE: what" messages. Every read checks the bounds, and
/// numbers are parsed with std::from_chars (no locale, no exceptions).

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>

#include "hom/io/error.hpp"

namespace hom::io::detail {

class Cursor {
 public:
  Cursor(std::string_view buf, std::string path) : buf_(buf), path_(std::move(path)) {}

  const std::string& path() const { return path_; }
  std::size_t line() const { return line_; }
  std::size_t pos() const { return pos_; }
  std::size_t remaining() const { return buf_.size() - pos_; }

  [[noreturn]] void fail(const std::string& what) const { throw ParseError(path_, line_, what); }
  [[noreturn]] void fail_at(std::size_t line, const std::string& what) const { throw ParseError(path_, line, what); }

  void skip_space() {
    while (pos_ < buf_.size()) {
      const char c = buf_[pos_];
      if (c == '\n')
        ++line_;
      else if (c != ' ' && c != '\t' && c != '\r' && c != '\f' && c != '\v')
        break;
      ++pos_;
    }
  }

  bool at_end() {
    skip_space();
    return pos_ >= buf_.size();
  }

  /// The next whitespace-separated token; fails at the end of the file.
  std::string_view token(std::string_view context) {
    skip_space();
    if (pos_ >= buf_.size()) fail("unexpected end of file in " + std::string(context));
    const std::size_t start = pos_;
    while (pos_ < buf_.size() && !is_space(buf_[pos_])) ++pos_;
    return buf_.substr(start, pos_ - start);
  }

  template <class Int>
  Int integer(std::string_view context) {
    const auto t = token(context);
    Int v{};
    auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || ptr != t.data() + t.size())
      fail("expected an integer in " + std::string(context) + ", got '" + shorten(t) + "'");
    return v;
  }

  /// A finite floating-point number.
  double real(std::string_view context) {
    const auto t = token(context);
    double v = 0;
    auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || ptr != t.data() + t.size())
      fail("expected a number in " + std::string(context) + ", got '" + shorten(t) + "'");
    if (!std::isfinite(v)) fail("non-finite number '" + shorten(t) + "' in " + std::string(context));
    return v;
  }

  /// A "quoted string" (physical names); the quotes are removed.
  std::string quoted(std::string_view context) {
    skip_space();
    if (pos_ >= buf_.size() || buf_[pos_] != '"') fail("expected a quoted name in " + std::string(context));
    const std::size_t end = buf_.find('"', pos_ + 1);
    const std::size_t eol = buf_.find('\n', pos_ + 1);
    if (end == std::string_view::npos || (eol != std::string_view::npos && eol < end))
      fail("unterminated quoted name in " + std::string(context));
    std::string s(buf_.substr(pos_ + 1, end - pos_ - 1));
    pos_ = end + 1;
    return s;
  }

  void expect(std::string_view word, std::string_view context) {
    const auto t = token(context);
    if (t != word) fail("expected '" + std::string(word) + "' in " + std::string(context) + ", got '" + shorten(t) + "'");
  }

  /// After a section header, binary data starts right after its line end.
  void end_of_header_line(std::string_view context) {
    while (pos_ < buf_.size() && (buf_[pos_] == ' ' || buf_[pos_] == '\t' || buf_[pos_] == '\r')) ++pos_;
    if (pos_ >= buf_.size() || buf_[pos_] != '\n') fail("expected the end of the line before binary data in " + std::string(context));
    ++pos_;
    ++line_;
  }

  /// A raw little/native-endian value of a binary section.
  template <class T>
  T binary(std::string_view context) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (remaining() < sizeof(T)) fail("unexpected end of file in binary " + std::string(context));
    T v;
    std::memcpy(&v, buf_.data() + pos_, sizeof(T));
    line_ += std::count(buf_.data() + pos_, buf_.data() + pos_ + sizeof(T), '\n');
    pos_ += sizeof(T);
    return v;
  }

  double binary_real(std::string_view context) {
    const double v = binary<double>(context);
    if (!std::isfinite(v)) fail("non-finite number in binary " + std::string(context));
    return v;
  }

  /// Moves to just after the next occurrence of `word` (false if absent).
  bool skip_past(std::string_view word) {
    const std::size_t at = buf_.find(word, pos_);
    if (at == std::string_view::npos) return false;
    line_ += std::count(buf_.data() + pos_, buf_.data() + at + word.size(), '\n');
    pos_ = at + word.size();
    return true;
  }

  static std::string shorten(std::string_view t) {
    std::string s(t.substr(0, 40));
    for (char& c : s)
      if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
    if (t.size() > 40) s += "...";
    return s;
  }

 private:
  static bool is_space(char c) { return c == ' ' || c == '\n' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

  std::string_view buf_;
  std::string path_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
};

}  // namespace hom::io::detail
