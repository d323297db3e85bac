#pragma once
/// What a run may take, checked before anything runs against the scenario's bounds
/// (RunSettings: run.max_steps, run.max_samples): the samples it stores, the run loop's
/// observations, and the soft engine's time steps, the run's (soft model) and settling's
/// (either model with spheres, up to soft::settling_time_limit_s of simulated time).
/// Settling and observing are checked for either model, so that a scenario `pdamp check`
/// passes never stalls in them. The hard engine's events cannot be foreseen: it stops at
/// run.max_events itself.

#include "pdamp/scenario/scenario.hpp"
#include "pdamp/sim/engine_factory.hpp"

namespace pdamp {

/// Throws InputError naming the bound a run of `model` would exceed, what it would need
/// and what sets it.
void check_run_budget(Model model, const Scenario& scenario);

}  // namespace pdamp
