#include "pdamp/sim/stored_run.hpp"

#include <omp.h>
#include <sys/resource.h>

#include <charconv>
#include <chrono>
#include <memory>

#include "pdamp/errors.hpp"
#include "pdamp/model/placement.hpp"
#include "pdamp/model/scenario_loader.hpp"

namespace pdamp {
namespace {

/// Builds the run's engine from its bed and records what it started from; an exception
/// leaves the run to be stored as failed (or interrupted).
std::unique_ptr<Engine> start_engine(RunStore& store, std::int64_t run_id, const RunPlan& plan,
                                     const BedSource& bed_source) {
  const Scenario& scenario = *plan.scenario;
  const InitialBed& bed = bed_source();
  auto engine = make_engine(plan.engine, scenario, bed.particles);
  store.start_run(run_id, {engine->time_step_s() > 0 ? std::optional(engine->time_step_s()) : std::nullopt,
                           bed.state_id, solid_fraction(scenario.cavity, bed.particles), bed.shift});
  if (plan.engine.calibration && bed.particles.size() > 0) store.save_calibration(run_id, *plan.engine.calibration);
  return engine;
}

SnapshotRecord snapshot_record(const SnapshotWriter& writer, const SnapshotSettings& settings) {
  return {writer.files().folder.string(), writer.files().collection.string(), settings.interval_s, writer.frames()};
}

/// Makes the run's snapshot folder and records it in the store, before the bed is settled:
/// a run that fails later leaves its folder recorded.
std::optional<SnapshotWriter> start_snapshots(RunStore& store, std::int64_t run_id, const RunPlan& plan) {
  std::optional<SnapshotWriter> writer(std::in_place, *plan.snapshots, *plan.scenario, run_id);
  store.save_snapshots(run_id, snapshot_record(*writer, *plan.snapshots));
  return writer;
}

/// `control` with the run's frames written at each observation, after control's own.
RunControl with_snapshots(const RunControl& control, std::optional<SnapshotWriter>& snapshots) {
  RunControl with = control;
  if (snapshots) {
    with.at_observation = [&control, &snapshots](const Engine& e, const ObservationStep& step) {
      if (control.at_observation) control.at_observation(e, step);
      snapshots->at_observation(e, step);
    };
  }
  return with;
}

void store_engine_statistics(RunStore& store, std::int64_t run_id, const Engine& engine) {
  EngineStatistics statistics = engine.statistics();
  statistics.emplace_back("threads", omp_get_max_threads());
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  statistics.emplace_back("peak_memory_kB", usage.ru_maxrss);
  store.save_statistics(run_id, statistics);
}

/// Appends the engine's warnings to the outcome's message (and tells `warn`), and stores
/// its statistics.
void store_engine_results(RunStore& store, std::int64_t run_id, const Engine& engine, RunOutcome& outcome,
                          const std::function<void(const std::string&)>& warn) {
  for (const auto& warning : engine.warnings()) {
    if (warn) warn(warning);
    outcome.message += (outcome.message.empty() ? "warning: " : "; warning: ") + warning;
  }
  store_engine_statistics(store, run_id, engine);
}

/// A number as text that reads back as the same double.
std::string exact_text(double value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  return std::string(text, end);
}

}  // namespace

RunPlan plan_run(Model model, const Scenario& scenario, const std::optional<SnapshotSettings>& snapshots,
                 bool diagnose_events) {
  if (snapshots) check_snapshot_settings(*snapshots, scenario);
  return {prepare_engine(model, scenario, diagnose_events), &scenario, snapshots, {}};
}

StoredRun run_and_store(RunStore& store, const RunPlan& plan, const BedSource& bed, const RunControl& control,
                        const std::function<void(const std::string&)>& warn,
                        const std::function<void(std::int64_t run_id)>& started) {
  const Scenario& scenario = *plan.scenario;
  const auto wall_start = std::chrono::steady_clock::now();
  StoredRun result;
  result.run_id = store.begin_run({std::string(to_string(plan.engine.model)), scenario.name, scenario.canonical_text,
                                   scenario.particles.seed, scenario.particles.count, scenario.run.duration_s});
  if (started) started(result.run_id);
  std::unique_ptr<Engine> engine;
  std::optional<SnapshotWriter> snapshots;
  try {
    if (plan.snapshots) snapshots = start_snapshots(store, result.run_id, plan);
    engine = start_engine(store, result.run_id, plan, bed);
  } catch (const Interrupted& e) {
    result.outcome.status = RunStatus::interrupted;
    result.outcome.message = e.what();
  } catch (const std::exception& e) {
    result.outcome.status = RunStatus::failed;
    result.outcome.message = e.what();
  }
  if (engine) {
    {
      RunWriter writer(store, result.run_id);
      const RunControl run_control = with_snapshots(control, snapshots);
      result.outcome = plan.body ? plan.body(*engine, scenario, writer, run_control)
                                 : run_simulation(*engine, scenario, writer, run_control);
    }
    store_engine_results(store, result.run_id, *engine, result.outcome, warn);
  } else {
    result.outcome.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  }
  if (snapshots) store.save_snapshots(result.run_id, snapshot_record(*snapshots, *plan.snapshots));
  store.finish_run(result.run_id, result.outcome);
  return result;
}

StoredRun resume_and_store(RunStore& store, std::int64_t run_id, std::optional<double> until_s,
                           const RunControl& control, const std::function<void(const std::string&)>& warn,
                           const ResumedBody& body, const std::function<void()>& claimed) {
  const ResumableRun run = store.resumable_run(run_id, until_s);
  const Model model = parse_model(run.model);
  ScenarioOverrides overrides;
  if (until_s) overrides.push_back("run.duration_s=" + exact_text(*until_s));
  const Scenario scenario = parse_scenario(run.scenario_text, "resumed",
                                           "run " + std::to_string(run_id) + "'s scenario", overrides, "--until");
  const EngineSetup setup = prepare_engine(model, scenario);
  Particles bed = run.initial_state_id ? store.load_initial_particles(*run.initial_state_id) : Particles(0);
  if (run.bed_shift) bed = moved_with_host(std::move(bed), *run.bed_shift);
  // Restored before the store is touched: a checkpoint that does not fit changes nothing.
  CheckpointReader checkpoint(run.checkpoint.state);
  const std::optional<RunLoopState> loop = body ? std::nullopt : std::optional(read_run_loop_state(checkpoint));
  const RunBody resumed_body = body ? body(checkpoint) : RunBody{};
  const auto engine = restore_engine(setup, scenario, bed, checkpoint);
  // The run loop's snapshots go on in their folder from the checkpoint's observation.
  const std::optional<SnapshotRecord> recorded = loop ? store.snapshots(run_id) : std::nullopt;
  const SnapshotFiles files = recorded ? SnapshotFiles{recorded->folder, recorded->collection} : SnapshotFiles{};
  const std::int64_t checkpoint_step =
      loop ? loop->interval * observation_grid(scenario).steps_per_sample + loop->step : 0;
  if (recorded) check_resumable_snapshots(files, recorded->interval_s, scenario, run_id, checkpoint_step);
  store.claim_for_resume(run, scenario.run.duration_s, scenario.canonical_text);
  if (claimed) claimed();
  StoredRun result{run_id, {}};
  std::optional<SnapshotWriter> snapshots;
  try {
    if (recorded) snapshots.emplace(files, recorded->interval_s, scenario, checkpoint_step);
  } catch (const std::exception& e) {
    result.outcome = loop->outcome;
    result.outcome.status = RunStatus::failed;
    result.outcome.message = e.what();
  }
  if (!recorded || snapshots) {
    RunWriter writer(store, run_id);
    result.outcome = loop ? run_simulation(*engine, scenario, writer, with_snapshots(control, snapshots), &*loop)
                          : resumed_body(*engine, scenario, writer, control);
  }
  store_engine_results(store, run_id, *engine, result.outcome, warn);
  if (snapshots)
    store.save_snapshots(run_id,
                         {files.folder.string(), files.collection.string(), recorded->interval_s, snapshots->frames()});
  store.finish_run(run_id, result.outcome);
  return result;
}

}  // namespace pdamp
