#pragma once

namespace pdamp {
/// pdamp's version (CMake project version), stored with every run.
extern const char* const version_string;
}  // namespace pdamp
