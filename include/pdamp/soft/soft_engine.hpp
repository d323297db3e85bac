#pragma once
/// The soft-sphere DEM engine, the reference model: the paper's Hertz law with tangential
/// history, velocity Verlet for particles, their rotations and the host, contacts found
/// exactly with a Verlet neighbour list on the shared cell grid (docs/soft-engine.md).
/// The engine's class and its parts are internal (src/soft); it is made here.

#include <memory>
#include <optional>

#include "pdamp/model/engine.hpp"
#include "pdamp/model/particles.hpp"
#include "pdamp/scenario/scenario.hpp"
#include "pdamp/simd/simd_path.hpp"

namespace pdamp::soft {

using simd::SimdPath;

struct SoftEngineOptions {
  /// Keep the host still at its initial displacement (the settling phase).
  bool hold_host = false;
  /// Drag −γ m v on every sphere and −γ I ω on its spin (1/s); only for settling, where
  /// spheres rolling on the floor would otherwise never stop (the law has no rolling
  /// resistance). Zero in every run.
  double settling_drag_1_s = 0.0;
  /// Neighbour-list skin as a fraction of the largest diameter.
  double skin_fraction = 0.2;
  /// Below this many spheres a step is too short to share between threads, which then
  /// cost more than they save (docs/benchmarks.md): the engine runs on one.
  int parallel_minimum_spheres = 3000;
  /// The instruction set of the kernels (default_simd_path() if not given); the results
  /// are the same bits on every path.
  std::optional<SimdPath> simd_path;
};

/// The soft engine for the scenario, starting from `initial`.
std::unique_ptr<Engine> make_soft_engine(const Scenario& scenario, const Particles& initial,
                                         SoftEngineOptions options = {});

}  // namespace pdamp::soft
