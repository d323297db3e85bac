#pragma once
/// `pdamp rom`: the reduced-order model of a characterised damper on a single-degree-of-freedom
/// host (docs/rom.md).

#include <string>
#include <vector>

namespace pdamp {

/// Runs `pdamp rom ARGS...` and returns the exit code.
int rom_command(const std::vector<std::string>& args);

}  // namespace pdamp
