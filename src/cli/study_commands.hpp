#pragma once
/// `pdamp study ...`: parameter studies.

#include <string>
#include <vector>

namespace pdamp {

/// Runs `pdamp study SUBCOMMAND ARGS...` and returns the exit code.
int study_command(const std::vector<std::string>& args);

}  // namespace pdamp
