#pragma once
/// The instruction sets the engines' kernels are compiled for, one chosen at run time for
/// both engines (the default build stays portable to any x86-64): SSE2 with 2 lanes, AVX2
/// with 4, AVX-512 with 8. The soft engine's passes run on the chosen one; the hard
/// engine's neighbour screen, four lanes wide, runs on AVX2 where AVX2 or AVX-512 is chosen
/// and on SSE2 otherwise. Every lane performs the scalar code's IEEE operations in its
/// order, so all paths give the same bits.

#include <string_view>

namespace pdamp::simd {

enum class SimdPath { sse2, avx2, avx512 };

std::string_view to_string(SimdPath path);
/// Parses "sse2", "avx2" or "avx512"; throws InputError naming `what` otherwise.
SimdPath parse_simd_path(std::string_view text, std::string_view what);
/// Whether this build, this CPU and its operating system can run the path (an unoptimised
/// build runs sse2 only).
bool is_available(SimdPath path);
/// The widest path is_available says this build and CPU run.
SimdPath widest_simd_path();

/// The path engines take unless their options say otherwise: the widest, or what
/// set_default_simd_path chose for the process (as omp_set_num_threads does for threads).
SimdPath default_simd_path();
/// Throws InputError naming `what` (the option that asked for it), saying why and what is
/// valid, unless is_available(path).
void require_available(SimdPath path, std::string_view what);
/// Throws as require_available does.
void set_default_simd_path(SimdPath path, std::string_view what);

}  // namespace pdamp::simd
