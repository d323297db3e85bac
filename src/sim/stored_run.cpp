#include "pdamp/sim/stored_run.hpp"

#include <omp.h>
#include <sys/resource.h>

#include <optional>

#include "pdamp/model/placement.hpp"
#include "pdamp/sim/calibration.hpp"

namespace pdamp {

StoredRun run_and_store(RunStore& store, Model model, const Scenario& scenario, const InitialBed& bed,
                        const RunControl& control, const std::function<void(const std::string&)>& warn) {
  std::optional<RestitutionTable> calibration;
  if (model == Model::hard && scenario.hard_restitution == HardRestitution::calibrated && bed.particles.size() > 0) {
    calibration = calibrate_restitution(scenario);
  }
  auto engine = make_engine(model, scenario, bed.particles, calibration ? &*calibration : nullptr);
  StoredRun result;
  result.run_id = store.begin_run({std::string(to_string(model)), scenario.name, scenario.canonical_text,
                                   scenario.particles.seed, scenario.particles.count, scenario.run.duration_s,
                                   engine->time_step_s() > 0 ? std::optional(engine->time_step_s()) : std::nullopt,
                                   bed.state_id, solid_fraction(scenario.cavity, bed.particles)});
  if (calibration) store.save_calibration(result.run_id, *calibration);
  {
    RunWriter writer(store, result.run_id);
    result.outcome = run_simulation(*engine, scenario, writer, control);
  }
  for (const auto& warning : engine->warnings()) {
    if (warn) warn(warning);
    result.outcome.message += (result.outcome.message.empty() ? "warning: " : "; warning: ") + warning;
  }
  EngineStatistics statistics = engine->statistics();
  statistics.emplace_back("threads", omp_get_max_threads());
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  statistics.emplace_back("peak_memory_kB", usage.ru_maxrss);
  store.save_statistics(result.run_id, statistics);
  store.finish_run(result.run_id, result.outcome);
  return result;
}

}  // namespace pdamp
