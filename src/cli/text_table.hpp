#pragma once
/// Text for the terminal: stored strings made safe to print, and tables whose columns
/// fit what they hold.

#include <cstddef>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace pdamp {

/// `text` with every control character (and every byte that is not UTF-8) written as an
/// escape: \n, \r, \t, or \xHH. Stored names and messages pass through it before they
/// reach a terminal.
std::string printable(std::string_view text);

/// Characters (UTF-8 code points) of printable text.
std::size_t display_width(std::string_view text);

/// `value` with `precision` significant digits; "-" for none.
std::string format_number(double value, int precision = 4);
std::string format_optional(const std::optional<double>& value, int precision = 4);

/// Columns separated by two spaces, each as wide as its widest cell (header included) up
/// to its limit; a longer cell is cut to the limit, ending in "…". Cells are made
/// printable.
class TextTable {
 public:
  struct Column {
    std::string header;
    bool right_aligned = false;
    std::size_t max_width = 1000;
  };
  explicit TextTable(std::vector<Column> columns);
  void add_row(const std::vector<std::string>& cells);
  void print(std::ostream& out) const;

 private:
  std::vector<Column> columns_;
  std::vector<std::vector<std::string>> rows_;
};

}  // namespace pdamp
