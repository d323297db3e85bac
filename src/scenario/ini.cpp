#include "pdamp/scenario/ini.hpp"

#include <algorithm>

#include "pdamp/errors.hpp"

namespace pdamp::ini {
namespace {

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// A line without its comment; a '#' directly after text is refused, never silently cut.
std::string_view strip_comment(std::string_view line, const std::string& where) {
  const auto hash = line.find('#');
  if (hash == std::string_view::npos) return line;
  if (hash > 0 && !is_blank(line[hash - 1])) {
    throw InputError(where + ": '" + printable(line) + "': '#' directly after text; " + no_hash_in_values +
                     " (a comment starts with '#' after a space)");
  }
  return line.substr(0, hash);
}

}  // namespace

const std::string no_hash_in_values =
    "a value cannot contain '#': in scenario syntax '#' starts a comment, and the scenario the store keeps must "
    "read back the same";

std::string_view trim(std::string_view text) {
  while (!text.empty() && is_blank(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_blank(text.back())) text.remove_suffix(1);
  return text;
}

std::string printable(std::string_view text) {
  std::string out;
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7f) {
      out += c;
    } else {
      constexpr const char* hex = "0123456789abcdef";
      out += {'\\', 'x', hex[byte >> 4], hex[byte & 15]};
    }
  }
  return out;
}

Document parse(std::string_view text, const std::string& origin) {
  constexpr std::string_view byte_order_mark = "\xEF\xBB\xBF";
  if (text.starts_with(byte_order_mark)) text.remove_prefix(byte_order_mark.size());
  if (const auto nul = text.find('\0'); nul != std::string_view::npos) {
    throw InputError(origin + ": a NUL byte at offset " + std::to_string(nul) + ": the file must be text");
  }
  Document document;
  std::string section;
  int number = 0;
  for (std::size_t start = 0; start < text.size();) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    std::string_view line = text.substr(start, end - start);
    start = end + 1;
    ++number;
    const std::string where = origin + ", line " + std::to_string(number);
    line = trim(strip_comment(line, where));
    if (line.empty()) continue;
    if (line.front() == '[' && line.back() == ']') {
      section = std::string(trim(line.substr(1, line.size() - 2)));
      document.sections.push_back({where, number, section});
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string_view::npos) {
      throw InputError(where + ": '" + printable(line) +
                       "' is not a 'key = value' line, a [section] header or a '#' comment");
    }
    document.entries.push_back(
        {where, number, section, std::string(trim(line.substr(0, eq))), std::string(trim(line.substr(eq + 1)))});
  }
  return document;
}

}  // namespace pdamp::ini
