#include "pdamp/sim/stored_run.hpp"

#include <omp.h>
#include <sys/resource.h>

#include <chrono>
#include <memory>

#include "pdamp/errors.hpp"
#include "pdamp/model/placement.hpp"
#include "pdamp/sim/calibration.hpp"

namespace pdamp {
namespace {

/// Builds the run's engine from its bed and records what it started from; an exception
/// leaves the run to be stored as failed (or interrupted).
std::unique_ptr<Engine> start_engine(RunStore& store, std::int64_t run_id, const RunPlan& plan,
                                     const BedSource& bed_source) {
  const Scenario& scenario = *plan.scenario;
  const InitialBed& bed = bed_source();
  auto engine = make_engine(plan.model, scenario, bed.particles, plan.calibration ? &*plan.calibration : nullptr,
                            plan.diagnose_events);
  store.start_run(run_id, {engine->time_step_s() > 0 ? std::optional(engine->time_step_s()) : std::nullopt,
                           bed.state_id, solid_fraction(scenario.cavity, bed.particles)});
  if (plan.calibration && bed.particles.size() > 0) store.save_calibration(run_id, *plan.calibration);
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

void store_engine_statistics(RunStore& store, std::int64_t run_id, const Engine& engine) {
  EngineStatistics statistics = engine.statistics();
  statistics.emplace_back("threads", omp_get_max_threads());
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  statistics.emplace_back("peak_memory_kB", usage.ru_maxrss);
  store.save_statistics(run_id, statistics);
}

}  // namespace

RunPlan plan_run(Model model, const Scenario& scenario, const std::optional<SnapshotSettings>& snapshots) {
  check_model_can_run(model, scenario);
  if (snapshots) check_snapshot_settings(*snapshots, scenario);
  RunPlan plan{model, &scenario, std::nullopt, snapshots};
  if (model == Model::hard && scenario.hard_restitution == HardRestitution::calibrated &&
      scenario.particles.count > 0) {
    try {
      plan.calibration = calibrate_restitution(scenario);
    } catch (const RuntimeFailure& e) {
      throw InputError(std::string("hard.restitution = calibrated: ") + e.what());
    }
  }
  return plan;
}

StoredRun run_and_store(RunStore& store, const RunPlan& plan, const BedSource& bed, const RunControl& control,
                        const std::function<void(const std::string&)>& warn,
                        const std::function<void(std::int64_t run_id)>& started) {
  const Scenario& scenario = *plan.scenario;
  const auto wall_start = std::chrono::steady_clock::now();
  StoredRun result;
  result.run_id = store.begin_run({std::string(to_string(plan.model)), scenario.name, scenario.canonical_text,
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
      RunControl with_snapshots = control;
      if (snapshots) {
        with_snapshots.at_observation = [&](const Engine& e, const ObservationStep& step) {
          if (control.at_observation) control.at_observation(e, step);
          snapshots->at_observation(e, step);
        };
      }
      result.outcome = run_simulation(*engine, scenario, writer, with_snapshots);
    }
    for (const auto& warning : engine->warnings()) {
      if (warn) warn(warning);
      result.outcome.message += (result.outcome.message.empty() ? "warning: " : "; warning: ") + warning;
    }
    store_engine_statistics(store, result.run_id, *engine);
  } else {
    result.outcome.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  }
  if (snapshots) store.save_snapshots(result.run_id, snapshot_record(*snapshots, *plan.snapshots));
  store.finish_run(result.run_id, result.outcome);
  return result;
}

}  // namespace pdamp
