#include "pdamp/sim/engine_factory.hpp"

#include <array>

#include "pdamp/errors.hpp"
#include "pdamp/hard/hard_engine.hpp"
#include "pdamp/model/host_only_engine.hpp"
#include "pdamp/sim/calibration.hpp"
#include "pdamp/sim/run_budget.hpp"
#include "pdamp/simd/simd_path.hpp"
#include "pdamp/soft/soft_engine.hpp"
#include "pdamp/soft/time_step.hpp"

namespace pdamp {
namespace {

std::string describe_soft(const Scenario& scenario) { return "time step " + soft::describe_time_step(scenario); }
std::string describe_hard(const Scenario&) { return "event-driven, no time step"; }

std::unique_ptr<Engine> make_soft(const EngineSetup&, const Scenario& scenario, const Particles& initial) {
  return soft::make_soft_engine(scenario, initial);
}
std::unique_ptr<Engine> make_hard(const EngineSetup& setup, const Scenario& scenario, const Particles& initial) {
  return hard::make_hard_engine(scenario, initial, setup.calibration ? &*setup.calibration : nullptr,
                                setup.diagnose_events);
}

constexpr std::array<EngineKind, 2> kinds{{
    {Model::soft, "soft", "time-stepped Hertz DEM", "[soft], [soft_wall]", describe_soft, make_soft},
    {Model::hard, "hard", "event-driven hard spheres", "[hard], [hard_wall]", describe_hard, make_hard},
}};

}  // namespace

std::span<const EngineKind> engine_kinds() { return kinds; }

const EngineKind& engine_kind(Model model) { return kinds[static_cast<std::size_t>(model)]; }

std::string_view to_string(Model model) { return engine_kind(model).name; }

Model parse_model(std::string_view text) {
  std::string valid;
  for (const EngineKind& kind : kinds) {
    if (text == kind.name) return kind.model;
    valid += std::string(valid.empty() ? "" : " or ") + "'" + std::string(kind.name) + "' (" +
             std::string(kind.description) + ")";
  }
  throw InputError("--model '" + std::string(text) + "': must be " + valid);
}

void set_instruction_set(std::string_view text, std::string_view option) {
  simd::set_default_simd_path(simd::parse_simd_path(text, option), option);
}

void check_model_can_run(Model model, const Scenario& scenario) {
  // The soft engine settles every bed, so its time step must work for either model.
  check_run_budget(model, scenario);
}

EngineSetup prepare_engine(Model model, const Scenario& scenario, bool diagnose_events) {
  check_model_can_run(model, scenario);
  EngineSetup setup{model, std::nullopt, diagnose_events};
  if (model == Model::hard && scenario.hard_restitution == HardRestitution::calibrated &&
      scenario.particles.count > 0) {
    try {
      setup.calibration = calibrate_restitution(scenario);
    } catch (const RuntimeFailure& e) {
      throw InputError(std::string("hard.restitution = calibrated: ") + e.what());
    }
  }
  return setup;
}

std::unique_ptr<Engine> make_engine(const EngineSetup& setup, const Scenario& scenario, const Particles& initial) {
  if (initial.size() == 0) return std::make_unique<HostOnlyEngine>(scenario);
  return engine_kind(setup.model).make(setup, scenario, initial);
}

std::unique_ptr<Engine> restore_engine(const EngineSetup& setup, const Scenario& scenario, const Particles& initial,
                                       CheckpointReader& checkpoint) {
  auto engine = make_engine(setup, scenario, initial);
  engine->restore(checkpoint);
  checkpoint.finish();
  return engine;
}

}  // namespace pdamp
