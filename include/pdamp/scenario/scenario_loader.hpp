#pragma once
/// Scenario files: Boost.program_options config syntax (INI sections), one key per
/// line, `#` comments. Every key has a unit, a default and a validity range, listed by
/// `describe_scenario_keys()` (the CLI help prints it).

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

/// `section.key=value` strings from the command line (`--set`); they win over the file.
using ScenarioOverrides = std::vector<std::string>;

/// Reads, overrides and validates a scenario. Throws InputError naming the key, the
/// value and what would be valid, for the first problem found.
Scenario load_scenario(const std::filesystem::path& file, const ScenarioOverrides& overrides = {});

/// The same from text already in memory (`origin` names it in error messages).
Scenario parse_scenario(const std::string& text, const std::string& name, const std::string& origin,
                        const ScenarioOverrides& overrides = {});

/// The key reference: one line per key with unit, default and meaning.
void describe_scenario_keys(std::ostream& out);

}  // namespace pdamp
