#include "pdamp/sim/engine_factory.hpp"

#include "pdamp/errors.hpp"
#include "pdamp/model/host_only_engine.hpp"
#include "pdamp/soft/soft_engine.hpp"
#include "pdamp/soft/time_step.hpp"

namespace pdamp {

std::string_view to_string(Model model) { return model == Model::soft ? "soft" : "hard"; }

Model parse_model(std::string_view text) {
  if (text == "soft") return Model::soft;
  if (text == "hard") return Model::hard;
  throw InputError("--model '" + std::string(text) +
                   "': must be 'soft' (time-stepped Hertz DEM) or 'hard' (event-driven hard spheres)");
}

namespace {

[[noreturn]] void hard_engine_missing() {
  throw InputError("the hard engine is not built yet: only particles.count = 0 (the host alone) runs for now");
}

}  // namespace

void check_model_can_run(Model model, const Scenario& scenario) {
  if (scenario.particles.count == 0) return;
  // The soft engine settles every bed, so its time step must work for either model.
  soft::choose_time_step_s(scenario);
  if (model == Model::hard) hard_engine_missing();
}

std::unique_ptr<Engine> make_engine(Model model, const Scenario& scenario, const Particles& initial,
                                    const RestitutionTable* calibration) {
  (void)calibration;  // taken by the hard engine
  if (initial.size() == 0) return std::make_unique<HostOnlyEngine>(scenario);
  if (model == Model::soft) return std::make_unique<soft::SoftEngine>(scenario, initial);
  hard_engine_missing();
}

}  // namespace pdamp
