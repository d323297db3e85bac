#pragma once
/// One run of one model from a bed, stored as it goes: the run's row, its samples and
/// cycles, the calibration the hard model used, the engine's statistics, and how it ended.
/// `pdamp run` makes one; `pdamp compare` makes one per model from the same bed.

#include <cstdint>
#include <functional>
#include <string>

#include "pdamp/sim/engine_factory.hpp"
#include "pdamp/sim/initial_bed.hpp"
#include "pdamp/sim/run.hpp"
#include "pdamp/store/run_store.hpp"

namespace pdamp {

struct StoredRun {
  std::int64_t run_id = 0;
  RunOutcome outcome;
};

/// `warn` receives the engine's warnings (they are also appended to the run's message).
StoredRun run_and_store(RunStore& store, Model model, const Scenario& scenario, const InitialBed& bed,
                        const RunControl& control, const std::function<void(const std::string&)>& warn = {});

}  // namespace pdamp
