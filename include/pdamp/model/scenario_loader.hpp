#pragma once
/// Scenario files: INI syntax (ini.hpp), `[section]` headers, one `key = value` per line,
/// `#` comments (at the start of a line or after a space; a '#' inside a value is refused).
/// Every key has a unit, a default and a validity range, listed by
/// `describe_scenario_keys()` (the CLI help prints it).

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

/// `section.key=value` strings from the command line (`--set`); they win over the file, and
/// where one key is given twice the later wins.
using ScenarioOverrides = std::vector<std::string>;

/// The most a scenario file may hold (bytes): a scenario is a few kB of text.
constexpr std::size_t max_scenario_file_bytes = 1 << 20;

/// Reads, overrides and validates a scenario. Throws InputError naming the key, the
/// value and what would be valid, for the first problem found. The file must be a
/// regular file of at most max_scenario_file_bytes.
Scenario load_scenario(const std::filesystem::path& file, const ScenarioOverrides& overrides = {});

/// The same from text already in memory (`origin` names it in error messages, and
/// `overrides_origin` names where the overrides came from).
Scenario parse_scenario(const std::string& text, const std::string& name, const std::string& origin,
                        const ScenarioOverrides& overrides = {}, const std::string& overrides_origin = "--set");

/// Every scenario key (section.key), in the order of the canonical text.
std::vector<std::string> scenario_key_names();

/// The key reference: one line per key with unit, default and meaning.
void describe_scenario_keys(std::ostream& out);

}  // namespace pdamp
