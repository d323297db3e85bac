#include "pdamp/sim/engine_factory.hpp"

#include "pdamp/errors.hpp"
#include "pdamp/hard/hard_engine.hpp"
#include "pdamp/model/host_only_engine.hpp"
#include "pdamp/sim/run_budget.hpp"
#include "pdamp/soft/soft_engine.hpp"

namespace pdamp {

std::string_view to_string(Model model) { return model == Model::soft ? "soft" : "hard"; }

Model parse_model(std::string_view text) {
  if (text == "soft") return Model::soft;
  if (text == "hard") return Model::hard;
  throw InputError("--model '" + std::string(text) +
                   "': must be 'soft' (time-stepped Hertz DEM) or 'hard' (event-driven hard spheres)");
}

void check_model_can_run(Model model, const Scenario& scenario) {
  // The soft engine settles every bed, so its time step must work for either model.
  check_run_budget(model, scenario);
}

std::unique_ptr<Engine> make_engine(Model model, const Scenario& scenario, const Particles& initial,
                                    const RestitutionTable* calibration) {
  if (initial.size() == 0) return std::make_unique<HostOnlyEngine>(scenario);
  if (model == Model::soft) return std::make_unique<soft::SoftEngine>(scenario, initial);
  return std::make_unique<hard::HardEngine>(scenario, initial, calibration);
}

}  // namespace pdamp
