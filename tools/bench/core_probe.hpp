#pragma once
/// What a thread gets of its core, for reading benchmark figures on a shared machine.
///
/// On a shared virtual machine the physical core's other hardware thread may belong to
/// another tenant. When that thread is busy it takes issue slots from this one: code that
/// issues several instructions a cycle (the hard engine does) slows by up to a half within
/// seconds, while the clock, and any single dependent chain, stays put. That explains
/// much of the development machine's swings, not all: the probe sees the integer units
/// only, and the other thread also shares the L2 and the floating-point units
/// (docs/benchmarks.md, "Timing on this machine"). A low share explains a slow figure; a
/// full one does not certify a fast one.
///
/// Two timed loops of integer additions tell the two apart: one dependent chain runs one
/// addition a cycle whatever the other thread does (the clock); four independent chains
/// run four a cycle on a core to itself (any x86-64 core with four integer units) and
/// fewer when the other thread competes. About 0.3 ms. The additions add a register, not
/// an immediate: Intel's cores since Golden Cove fold chains of immediate additions in the
/// renamer, several a cycle (a Sapphire Rapids-class Xeon ran 21 GHz of them).

#include <chrono>
#include <cstdint>

namespace pdamp::bench {

struct CoreProbe {
  double clock_GHz;
  double share;  ///< the four chains' rate over four times the clock: about 1 on a core to itself
};

inline CoreProbe probe_core() {
  constexpr long rounds = 1L << 14, adds_per_round = 32;
  const auto seconds_since = [](std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  std::uint64_t a = 0, b = 0, c = 0, d = 0;
  const std::uint64_t one = 1;
  auto start = std::chrono::steady_clock::now();
  for (long k = 0; k < rounds; ++k) asm volatile(".rept 32\n\tadd %1, %0\n\t.endr" : "+r"(a) : "r"(one));
  const double one_chain_s = seconds_since(start);
  start = std::chrono::steady_clock::now();
  for (long k = 0; k < 4 * rounds; ++k) {  // four times the additions: as long, on a core to itself
    asm volatile(".rept 8\n\tadd %4, %0\n\tadd %4, %1\n\tadd %4, %2\n\tadd %4, %3\n\t.endr"
                 : "+r"(a), "+r"(b), "+r"(c), "+r"(d)
                 : "r"(one));
  }
  const double four_chains_s = seconds_since(start);
  return {static_cast<double>(rounds * adds_per_round) / one_chain_s * 1e-9, one_chain_s / four_chains_s};
}

}  // namespace pdamp::bench
