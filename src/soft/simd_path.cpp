#include "pdamp/soft/simd_path.hpp"

#include <atomic>
#include <string>

#include "pdamp/errors.hpp"

namespace pdamp::soft {
namespace {

std::atomic<int> chosen_default{-1};  ///< a SimdPath, or −1 for the widest

}  // namespace

std::string_view to_string(SimdPath path) {
  switch (path) {
    case SimdPath::sse2: return "sse2";
    case SimdPath::avx2: return "avx2";
    case SimdPath::avx512: break;
  }
  return "avx512";
}

SimdPath parse_simd_path(std::string_view text, std::string_view what) {
  for (const SimdPath path : {SimdPath::sse2, SimdPath::avx2, SimdPath::avx512}) {
    if (text == to_string(path)) return path;
  }
  throw InputError(std::string(what) + " '" + std::string(text) + "': must be sse2, avx2 or avx512");
}

bool is_available(SimdPath path) {
  // __builtin_cpu_supports also checks that the operating system saves the wide registers.
  switch (path) {
    case SimdPath::sse2: return true;
    case SimdPath::avx2: return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
    case SimdPath::avx512: break;
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

void set_default_simd_path(SimdPath path) {
  if (!is_available(path)) throw InputError("this CPU cannot run the " + std::string(to_string(path)) + " path");
  chosen_default.store(static_cast<int>(path));
}

}  // namespace pdamp::soft
