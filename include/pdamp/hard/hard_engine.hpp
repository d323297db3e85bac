#pragma once
/// The event-driven hard-sphere engine (docs/hard-engine.md): spheres on exact parabolas,
/// Walton's impulse at each collision, the host's motion in closed form between events.
/// The engine's class and its parts are internal (src/hard); it is made here.

#include <memory>

#include "pdamp/model/engine.hpp"
#include "pdamp/model/particles.hpp"
#include "pdamp/model/restitution.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp::hard {

/// The hard engine for the scenario, starting from `initial`. With a `calibration`, e_n
/// and β0 follow the soft law's e_n(v), β0(v) at each impact speed (hard.restitution =
/// calibrated); otherwise they are the scenario's constants. With `diagnose_events`, it
/// counts where its collisions come from into its statistics (the results are the same
/// bits).
std::unique_ptr<Engine> make_hard_engine(const Scenario& scenario, const Particles& initial,
                                         const RestitutionTable* calibration = nullptr, bool diagnose_events = false);

}  // namespace pdamp::hard
