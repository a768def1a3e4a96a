#pragma once
/// @file json.hpp
/// A small JSON value for the machine-readable reports of DESIGN.md
/// ({"tool": ..., "version": ..., "cases": [...]}): ordered keys, and
/// non-finite numbers written as null (JSON has no infinity).

#include <cmath>
#include <iomanip>
#include <initializer_list>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace hom::io {

struct Json {
  using Array = std::vector<Json>;
  using Object = std::vector<std::pair<std::string, Json>>;
  std::variant<std::nullptr_t, bool, double, long long, std::string, Array, Object> value;

  Json() : value(nullptr) {}
  Json(bool b) : value(b) {}
  Json(double d) : value(d) {}
  Json(int i) : value(static_cast<long long>(i)) {}
  Json(long long i) : value(i) {}
  Json(const char* s) : value(std::string(s)) {}
  Json(std::string s) : value(std::move(s)) {}
  Json(std::string_view s) : value(std::string(s)) {}
  Json(Array a) : value(std::move(a)) {}
  Json(Object o) : value(std::move(o)) {}

  static Json array(std::initializer_list<Json> items = {}) { return Json(Array(items)); }
  static Json object() { return Json(Object{}); }

  Json& set(std::string key, Json v) {
    std::get<Object>(value).emplace_back(std::move(key), std::move(v));
    return *this;
  }
  void push(Json v) { std::get<Array>(value).push_back(std::move(v)); }

  void write(std::ostream& os, int indent = 0) const {
    const std::string pad(indent + 2, ' '), end(indent, ' ');
    std::visit(
        [&](const auto& v) {
          using T = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<T, std::nullptr_t>) {
            os << "null";
          } else if constexpr (std::is_same_v<T, bool>) {
            os << (v ? "true" : "false");
          } else if constexpr (std::is_same_v<T, double>) {
            if (std::isfinite(v))
              os << std::setprecision(15) << v;
            else
              os << "null";  // JSON has no infinity; the report's prose says where inf is meant
          } else if constexpr (std::is_same_v<T, long long>) {
            os << v;
          } else if constexpr (std::is_same_v<T, std::string>) {
            write_string(os, v);
          } else if constexpr (std::is_same_v<T, Array>) {
            if (v.empty()) {
              os << "[]";
              return;
            }
            os << "[\n";
            for (std::size_t i = 0; i < v.size(); ++i) {
              os << pad;
              v[i].write(os, indent + 2);
              os << (i + 1 < v.size() ? ",\n" : "\n");
            }
            os << end << "]";
          } else {
            if (v.empty()) {
              os << "{}";
              return;
            }
            os << "{\n";
            for (std::size_t i = 0; i < v.size(); ++i) {
              os << pad;
              write_string(os, v[i].first);
              os << ": ";
              v[i].second.write(os, indent + 2);
              os << (i + 1 < v.size() ? ",\n" : "\n");
            }
            os << end << "}";
          }
        },
        value);
  }

 private:
  static void write_string(std::ostream& os, const std::string& s) {
    os << '"';
    for (char c : s) {
      if (c == '"' || c == '\\')
        os << '\\' << c;
      else if (c == '\n')
        os << "\\n";
      else if (static_cast<unsigned char>(c) < 0x20) {
        const char* hex = "0123456789abcdef";
        os << "\\u00" << hex[(c >> 4) & 0xf] << hex[c & 0xf];
      } else
        os << c;
    }
    os << '"';
  }
};

}  // namespace hom::io
