#pragma once
/// One run of one model from a bed, stored as it goes: the run's row, its samples and
/// cycles, the calibration the hard model used, the engine's statistics, and how it ended.
/// `pdamp run` makes one; `pdamp compare` makes one per model from the same bed.
///
/// What can be found from the scenario alone is checked before the store is touched
/// (plan_run). The run's row is written next, before the bed is settled, so that whatever
/// ends the run later (a failure, a signal) is stored with it.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "pdamp/sim/engine_factory.hpp"
#include "pdamp/sim/initial_bed.hpp"
#include "pdamp/sim/run.hpp"
#include "pdamp/sim/snapshots.hpp"
#include "pdamp/store/run_store.hpp"

namespace pdamp {

/// What drives a run's engine once it is built (or restored).
using RunBody = std::function<RunOutcome(Engine&, const Scenario&, RunRecorder&, const RunControl&)>;

/// A model checked to run a scenario, with what it needs that depends on the scenario alone.
struct RunPlan {
  EngineSetup engine;
  const Scenario* scenario;
  std::optional<SnapshotSettings> snapshots;  ///< checked against the scenario
  /// Empty for the run loop over the scenario's duration (run_simulation), or another
  /// driver (a frequency-response point's cycles).
  RunBody body;
};

/// The engine's setup (prepare_engine: the model can run `scenario`, calibrated if the
/// scenario asks) with these snapshots (check_snapshot_settings). Throws InputError for
/// any of them failing.
RunPlan plan_run(Model model, const Scenario& scenario, const std::optional<SnapshotSettings>& snapshots = {},
                 bool diagnose_events = false);

/// Gives the bed a run starts from, settling it or taking it from the store (the bed is
/// shared by the runs of a comparison). May throw, Interrupted included.
using BedSource = std::function<const InitialBed&()>;

struct StoredRun {
  std::int64_t run_id = 0;
  RunOutcome outcome;
};

/// Stores the run's row, gets its bed, runs it (writing its snapshots, recorded in the
/// store) and stores how it ended: failed with the message if the bed, the engine, the
/// snapshots or the run failed, interrupted if a signal stopped it.
/// `warn` receives the engine's warnings (they are also appended to the run's message);
/// `started` hears of the run's row as soon as it exists (a study links it to its point).
/// Throws only if the store itself fails.
StoredRun run_and_store(RunStore& store, const RunPlan& plan, const BedSource& bed, const RunControl& control,
                        const std::function<void(const std::string&)>& warn = {},
                        const std::function<void(std::int64_t run_id)>& started = {});

/// How a run driven by another body than the run loop goes on from its checkpoint: reads
/// the loop's part of it (before the engine's) and gives the body that drives the
/// restored engine from there.
using ResumedBody = std::function<RunBody(CheckpointReader& checkpoint)>;

/// Continues a stored run from its checkpoint (pdamp resume, docs/checkpoints.md) to its
/// end, or on to `until_s` (then the run's end and scenario say so), as run_and_store runs
/// one: the samples and cycles it had recorded after the checkpoint are dropped, and
/// what follows is recorded with the same bits as if the run had never stopped; so are
/// its snapshots (run loop only). `body` continues a run of another driver (empty: the run
/// loop); `claimed` hears that the run is taken over, before it goes on. Throws, changing
/// nothing, InputError for a run that cannot be resumed (RunStore::resumable_run) and
/// RuntimeFailure for a checkpoint that does not fit its engine or its driver.
StoredRun resume_and_store(RunStore& store, std::int64_t run_id, std::optional<double> until_s,
                           const RunControl& control, const std::function<void(const std::string&)>& warn = {},
                           const ResumedBody& body = {}, const std::function<void()>& claimed = {});

}  // namespace pdamp
