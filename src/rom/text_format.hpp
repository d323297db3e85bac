#pragma once
/// Number and string formatting shared by the rom layer's CSV and JSON writers.

#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>

namespace pdamp::rom::text {

/// The shortest text that reads back to the same double.
inline std::string number(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

/// A JSON string literal.
inline std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned>(c));
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

/// A JSON number, or null for a value JSON cannot hold.
inline std::string json_number(double value) { return std::isfinite(value) ? number(value) : "null"; }

}  // namespace pdamp::rom::text
