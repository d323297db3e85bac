#pragma once
/// Points driven to a steady state cycle by cycle: a frequency-response point (the host
/// driven at the scenario's excitation, analysis/frf_response.hpp) and a characterisation
/// point (the container's motion prescribed, analysis/damper_characterisation.hpp). Both
/// advance the engine one excitation period at a time until the watched first harmonic is
/// steady (or not by the cap), then over the measured cycles, and store one sample per
/// cycle boundary.

#include <chrono>
#include <functional>
#include <vector>

#include "pdamp/analysis/damper_characterisation.hpp"
#include "pdamp/analysis/frf_response.hpp"
#include "pdamp/analysis/recorder.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/sim/run.hpp"

namespace pdamp {

/// The cycles a point ran: the boundaries of its measured cycles and how it got there.
struct SteadyCycles {
  std::vector<Observation> measured;  ///< n + 1 observations at whole cycles
  bool settled = false;
  int cycles_to_steady = 0;  ///< cycles before the measured ones
  int cycles_run = 0;
  double wall_time_s = 0.0;
};

/// Per cycle, the instants (of contact_instants_per_cycle) at which a sphere touched the
/// floor and the lid: a characterisation point's.
struct WallTouches {
  int floor = 0, lid = 0;
};

/// What a point run cycle by cycle has seen so far: the observations at t0 and at the end
/// of each cycle, and each cycle's wall touches where the point counts them. With the
/// engine at its last boundary, they are all a checkpoint needs of the point's loop: the
/// steady-state detection and the measured cycles follow from them.
struct CycleLog {
  std::vector<Observation> boundaries;
  std::vector<WallTouches> touches;
};

struct CycleHooks {
  /// Sees the engine at t0 and at every cycle's end.
  std::function<void(const Observation&)> at_boundary;
  /// Advances the engine through one cycle to `t_end_s` (default: advance_to): where a
  /// point looks inside its cycles.
  std::function<void(Engine& engine, double t_end_s)> advance_cycle;
};

/// Advances `engine` (at its time t0, any state) to t0 + k T, T = 2π/ω, one cycle at a
/// time: until `watch`'s first harmonic is settled, or not settled by the cap; the measured
/// cycles are the n after settling, or the last n up to the cap. The engine's stop request
/// ends it with Interrupted. Each boundary is appended to `log` before the hook sees it; a
/// `log` that holds boundaries already is a point resumed at its last one (the engine
/// restored there): its cycles are taken from the log, not run again.
SteadyCycles run_to_steady_state(Engine& engine, double omega_rad_s, const SteadyStateCriterion& criterion,
                                 SteadyWatch watch, CycleLog& log, const CycleHooks& hooks = {});

struct FrfPointOutcome {
  ResponseMetrics metrics;
  int cycles_run = 0;
  double wall_time_s = 0.0;
};

/// A frequency-response point: run_to_steady_state on the host's displacement at the
/// scenario's excitation, and its response metrics.
FrfPointOutcome run_frf_point(Engine& engine, const Scenario& scenario, const SteadyStateCriterion& criterion,
                              const std::function<void(const Observation&)>& at_boundary = {}, CycleLog* log = nullptr);

/// What a frequency-response point's run found besides how it ended.
struct FrfRun {
  FrfPointOutcome point;
  State final_state;  ///< the engine at the end of the last cycle
};

/// Where a point run cycle by cycle stood at a checkpoint: what it had recorded and its
/// cycles so far.
struct CycleLoopState {
  RunOutcome outcome;  ///< so far; its wall time that of every process that ran it
  CycleLog log;
};

/// A frequency-response point as a stored run (stored_run.hpp's RunPlan::body): the
/// point's cycles, one sample at each cycle boundary (t0 included), the control's stop and
/// progress; `result` receives the metrics and the final state if the run completes.
/// Checkpoints at a boundary after each of the control's intervals and at a stop request
/// (which then ends the run there). With `resume`, the engine is one restored from such a
/// checkpoint and the point goes on from it.
RunOutcome run_frf_simulation(Engine& engine, const Scenario& scenario, RunRecorder& recorder,
                              const RunControl& control, const SteadyStateCriterion& criterion, FrfRun& result,
                              const CycleLoopState* resume = nullptr);

/// Instants per cycle at which a characterisation point looks for spheres touching the
/// floor and the lid.
inline constexpr int contact_instants_per_cycle = 64;

struct CharacterisationPointOutcome {
  CharacterisationMetrics metrics;
  int cycles_run = 0;
  double wall_time_s = 0.0;
};

/// The period of a cycle-by-cycle point's drive (force, base or prescribed motion), 2π/ω:
/// the time between its cycle boundaries.
double cycle_period_s(const Scenario& scenario);

/// A characterisation point (excitation.mode = prescribed): run_to_steady_state on the
/// particles' force, each cycle advanced in contact_instants_per_cycle steps to find the
/// spheres touching the floor and the lid, and its metrics. Throws InputError for another
/// excitation mode.
CharacterisationPointOutcome run_characterisation_point(Engine& engine, const Scenario& scenario,
                                                        const SteadyStateCriterion& criterion,
                                                        const std::function<void(const Observation&)>& at_boundary = {},
                                                        CycleLog* log = nullptr);

struct CharacterisationRun {
  CharacterisationPointOutcome point;
  State final_state;  ///< the engine at the end of the last cycle
};

/// A characterisation point as a stored run, as run_frf_simulation.
RunOutcome run_characterisation_simulation(Engine& engine, const Scenario& scenario, RunRecorder& recorder,
                                           const RunControl& control, const SteadyStateCriterion& criterion,
                                           CharacterisationRun& result, const CycleLoopState* resume = nullptr);

/// The loop's part of a cycle-by-cycle point's checkpoint, which comes first (then
/// restore_engine), as read_run_loop_state for the run loop.
CycleLoopState read_cycle_loop_state(CheckpointReader& in);

}  // namespace pdamp
