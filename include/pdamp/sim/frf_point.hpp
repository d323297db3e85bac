#pragma once
/// One point of a frequency response: the engine driven cycle by cycle at the scenario's
/// excitation until the response is steady (analysis/frf_response.hpp), then over the
/// measured cycles, whose metrics it returns.

#include <chrono>

#include "pdamp/analysis/frf_response.hpp"
#include "pdamp/model/engine.hpp"

namespace pdamp {

struct FrfPointOutcome {
  ResponseMetrics metrics;
  int cycles_run = 0;
  double wall_time_s = 0.0;
};

/// Advances `engine` (at its time t0, any state) to t0 + k T, T = 2π/ω, one cycle at a
/// time: until settled, or not settled by the cap; the metrics are over the n cycles after
/// settling, or the last n cycles up to the cap. The engine's stop request ends it with
/// Interrupted.
FrfPointOutcome run_frf_point(Engine& engine, const Scenario& scenario, const SteadyStateCriterion& criterion);

}  // namespace pdamp
