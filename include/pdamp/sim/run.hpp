#pragma once
/// The run loop: advances an engine over the scenario's duration, feeds the cycle
/// analysis, records samples and cycles, and stops cleanly when asked.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include "pdamp/analysis/cycle_analyzer.hpp"
#include "pdamp/analysis/recorder.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/sim/observation_grid.hpp"
#include "pdamp/store/run_store.hpp"

namespace pdamp {

struct RunControl {
  const std::atomic<bool>* stop = nullptr;   ///< when it becomes true the run ends as interrupted
  std::function<void(double t_s)> progress;  ///< called about twice a second of wall time
  /// Called at every observation, t = 0 included, after it is recorded, with the engine as
  /// it is then (snapshots). An exception ends the run as failed with its message.
  std::function<void(const Engine& engine, const ObservationStep& step)> at_observation;
  /// Wall time between checkpoints (docs/checkpoints.md; 0: none). At the first
  /// observation on the grid after each interval, at a stop request and at the end, the
  /// run loop saves its own state and the engine's and hands them to the recorder with
  /// the results so far.
  std::chrono::nanoseconds checkpoint_interval{0};
  /// With checkpoints, how long the engine goes on after a stop request to reach the next
  /// observation, where the run checkpoints where it stopped; past it the run stops inside
  /// the engine and keeps its last checkpoint before.
  std::chrono::milliseconds stop_grace{300};
};

/// How the run ended, as the store keeps it, and what it recorded.
struct RunOutcome : RunEnd {
  int samples = 0;
  int cycles = 0;
};

/// Where the run loop stood at a checkpoint: the observation's place on the grid (step
/// `step` of sample interval `interval`: step 0 is the sample at its start), what it had
/// recorded and its cycle analysis.
struct RunLoopState {
  std::int64_t interval = 0, step = 0;
  RunOutcome outcome;  ///< so far; its wall time that of every process that ran it
  CycleAnalyzer cycles;
};

/// Runs `engine` from its current time to scenario.run.duration_s. An exception inside
/// the engine ends the run as failed with its message; what was recorded stays. With
/// `resume`, the engine is one restored from a checkpoint (restore_engine) and the loop
/// continues from where that checkpoint left it, recording what follows.
RunOutcome run_simulation(Engine& engine, const Scenario& scenario, RunRecorder& recorder,
                          const RunControl& control = {}, const RunLoopState* resume = nullptr);

/// The run loop's part of a checkpoint, which comes first: a checkpoint is read back by
/// read_run_loop_state, then restore_engine.
RunLoopState read_run_loop_state(CheckpointReader& in);

/// The cycle analysis of a run starting from `bed`: it needs the host's equilibrium with
/// the bed resting in it.
CycleAnalyzer make_cycle_analyzer(const Scenario& scenario, const Particles& bed);

}  // namespace pdamp
