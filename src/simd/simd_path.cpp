#include "pdamp/simd/simd_path.hpp"

#include <atomic>
#include <string>

#include "pdamp/errors.hpp"

namespace pdamp::simd {
namespace {

std::atomic<int> chosen_default{-1};  ///< a SimdPath, or −1 for the widest

constexpr SimdPath all_paths[] = {SimdPath::sse2, SimdPath::avx2, SimdPath::avx512};

// The wide kernels rely on `flatten` to compile everything they call for their instruction
// set. An unoptimised build inlines nothing, so their wide vectors would be passed to
// helpers compiled for the baseline, which crashes: such builds run SSE2 only.
#ifdef __OPTIMIZE__
constexpr bool wide_kernels_built = true;
#else
constexpr bool wide_kernels_built = false;
#endif

}  // namespace

std::string_view to_string(SimdPath path) {
  switch (path) {
    case SimdPath::sse2:
      return "sse2";
    case SimdPath::avx2:
      return "avx2";
    case SimdPath::avx512:
      break;
  }
  return "avx512";
}

SimdPath parse_simd_path(std::string_view text, std::string_view what) {
  for (const SimdPath path : all_paths) {
    if (text == to_string(path)) return path;
  }
  throw InputError(std::string(what) + " '" + std::string(text) + "': must be sse2, avx2 or avx512");
}

bool is_available(SimdPath path) {
  if (path != SimdPath::sse2 && !wide_kernels_built) return false;
  // __builtin_cpu_supports also checks that the operating system saves the wide registers.
  switch (path) {
    case SimdPath::sse2:
      return true;
    case SimdPath::avx2:
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
    case SimdPath::avx512:
      break;
  }
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("popcnt");
}

SimdPath widest_simd_path() {
  if (is_available(SimdPath::avx512)) return SimdPath::avx512;
  if (is_available(SimdPath::avx2)) return SimdPath::avx2;
  return SimdPath::sse2;
}

SimdPath default_simd_path() {
  const int chosen = chosen_default.load();
  return chosen < 0 ? widest_simd_path() : static_cast<SimdPath>(chosen);
}

void require_available(SimdPath path, std::string_view what) {
  if (is_available(path)) return;
  std::string message(what);
  message += " '";
  message += to_string(path);
  message += '\'';
  message += wide_kernels_built ? ": this CPU cannot run it" : ": an unoptimised build runs sse2 only";
  message += " (valid here:";
  for (const SimdPath other : all_paths) {
    if (!is_available(other)) continue;
    message += ' ';
    message += to_string(other);
  }
  message += ')';
  throw InputError(message);
}

void set_default_simd_path(SimdPath path, std::string_view what) {
  require_available(path, what);
  chosen_default.store(static_cast<int>(path));
}

}  // namespace pdamp::simd
