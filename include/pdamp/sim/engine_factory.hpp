#pragma once
/// Chooses the engine for a model name.

#include <memory>
#include <string_view>

#include "pdamp/model/engine.hpp"
#include "pdamp/model/restitution.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

enum class Model { soft, hard };

std::string_view to_string(Model model);
/// Throws InputError for anything but "soft" or "hard".
Model parse_model(std::string_view text);

/// Checks that `model` can run the scenario (the soft engine's time
/// step, the run's budget: run_budget.hpp), before any work is done. Throws InputError
/// naming the offending key.
void check_model_can_run(Model model, const Scenario& scenario);

/// The engine of `model` for the scenario, starting from `initial` (a placement or a
/// settled bed) with the host in its initial condition. A scenario without particles
/// runs the host alone on its exact solution, whatever the model. The hard model takes
/// `calibration` when the scenario asks for calibrated restitution. Throws InputError for
/// a scenario the engine cannot run.
std::unique_ptr<Engine> make_engine(Model model, const Scenario& scenario, const Particles& initial,
                                    const RestitutionTable* calibration = nullptr);

}  // namespace pdamp
