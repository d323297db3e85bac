#include "pdamp/version.hpp"

namespace pdamp {
const char* const version_string = PDAMP_VERSION;
}  // namespace pdamp
