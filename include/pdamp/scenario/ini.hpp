#pragma once
/// The syntax of pdamp's input files, scenario files and study files alike: `[section]`
/// headers, `key = value` lines, `#` comments, blank lines. A '#' starts a comment at the
/// start of a line or after white space; directly after text it is refused, so that no
/// value ever holds a '#' (the texts the store keeps must read back the same). White space
/// is blanks, tabs, CR, VT and FF. A UTF-8 byte-order mark at the start is skipped; a NUL
/// byte is refused. Files are read with read_input_file (input_file.hpp).

#include <string>
#include <string_view>
#include <vector>

namespace pdamp::ini {

/// One `[section]` header.
struct Section {
  std::string where;  ///< "origin, line N", for messages
  int line = 0;
  std::string name;  ///< without the brackets and white space around it
};

/// One `key = value` line.
struct Entry {
  std::string where;  ///< "origin, line N", for messages
  int line = 0;
  std::string section;     ///< the header above it, "" before any
  std::string key, value;  ///< without white space around them
};

struct Document {
  std::vector<Section> sections;  ///< in file order
  std::vector<Entry> entries;     ///< in file order
};

/// Parses INI text; `origin` names it in messages. Throws InputError, naming the line, for
/// a line that is neither a header, a `key = value` line, a comment nor blank.
Document parse(std::string_view text, const std::string& origin);

/// `text` without white space around it.
std::string_view trim(std::string_view text);

/// Text for a message, with every byte outside printable ASCII written \xNN: nothing in
/// it is invisible (a byte-order mark, a zero-width space, a control character).
std::string printable(std::string_view text);

/// Why no value may hold a '#'.
extern const std::string no_hash_in_values;

}  // namespace pdamp::ini
