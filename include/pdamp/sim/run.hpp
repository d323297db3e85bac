#pragma once
/// The run loop: advances an engine over the scenario's duration, feeds the cycle
/// analysis, records samples and cycles, and stops cleanly when asked.

#include <atomic>
#include <functional>
#include <string>
#include <string_view>

#include "pdamp/analysis/cycle_analyzer.hpp"
#include "pdamp/analysis/recorder.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/store/run_store.hpp"

namespace pdamp {

struct RunControl {
  const std::atomic<bool>* stop = nullptr;   ///< when it becomes true the run ends as interrupted
  std::function<void(double t_s)> progress;  ///< called about twice a second of wall time
};

/// How the run ended, as the store keeps it, and what it recorded.
struct RunOutcome : RunEnd {
  int samples = 0;
  int cycles = 0;
};

/// Runs `engine` from its current time to scenario.run.duration_s. An exception inside
/// the engine ends the run as failed with its message; what was recorded stays.
RunOutcome run_simulation(Engine& engine, const Scenario& scenario, RunRecorder& recorder,
                          const RunControl& control = {});

/// How often the run loop observes the engine (s): ≥ 256 times per natural period of
/// the host (or of the excitation, if faster), and at every sample.
double observation_interval_s(const Scenario& scenario);

/// The cycle analysis of a run starting from `bed`: it needs the host's equilibrium with
/// the bed resting in it.
CycleAnalyzer make_cycle_analyzer(const Scenario& scenario, const Particles& bed);

}  // namespace pdamp
