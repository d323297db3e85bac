#pragma once
/// One point of a frequency response: the engine driven cycle by cycle at the scenario's
/// excitation until the response is steady (analysis/frf_response.hpp), then over the
/// measured cycles, whose metrics it returns.

#include <chrono>
#include <functional>

#include "pdamp/analysis/frf_response.hpp"
#include "pdamp/analysis/recorder.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/sim/run.hpp"

namespace pdamp {

struct FrfPointOutcome {
  ResponseMetrics metrics;
  int cycles_run = 0;
  double wall_time_s = 0.0;
};

/// Advances `engine` (at its time t0, any state) to t0 + k T, T = 2π/ω, one cycle at a
/// time: until settled, or not settled by the cap; the metrics are over the n cycles after
/// settling, or the last n cycles up to the cap. `at_boundary` sees the engine at t0 and
/// at every cycle's end. The engine's stop request ends it with Interrupted.
FrfPointOutcome run_frf_point(Engine& engine, const Scenario& scenario, const SteadyStateCriterion& criterion,
                              const std::function<void(const Observation&)>& at_boundary = {});

/// What a frequency-response point's run found besides how it ended.
struct FrfRun {
  FrfPointOutcome point;
  State final_state;  ///< the engine at the end of the last cycle
};

/// A frequency-response point as a stored run (stored_run.hpp's RunPlan::body): the
/// point's cycles, one sample at each cycle boundary (t0 included), the control's stop and
/// progress; `result` receives the metrics and the final state if the run completes.
RunOutcome run_frf_simulation(Engine& engine, const Scenario& scenario, RunRecorder& recorder,
                              const RunControl& control, const SteadyStateCriterion& criterion, FrfRun& result);

}  // namespace pdamp
