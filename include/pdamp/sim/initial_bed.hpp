#pragma once
/// The bed both engines start from: the random placement settled under gravity with the
/// host held still (soft/settling.hpp). A settled bed is stored with the settings that
/// determine it (its settle key); any later run of either model with the same settings
/// starts from exactly that stored bed instead of settling again.

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "pdamp/model/particles.hpp"
#include "pdamp/scenario/scenario.hpp"
#include "pdamp/store/run_store.hpp"

namespace pdamp {

struct InitialBed {
  Particles particles;
  std::optional<std::int64_t> state_id;  ///< in the store; empty for a bed without particles
  bool reused = false;                   ///< taken from the store rather than stored now (also if settled here too)
  double settle_time_s = 0.0;
  /// `particles` are state_id's moved rigidly by this (moved_with_host), which the run
  /// records instead of storing them again.
  std::optional<HostState> shift{};
};

/// The spheres moved rigidly with the host by `shift`: z and vz by its z and v; x, y, the
/// other velocities and the spins as they were.
Particles moved_with_host(Particles spheres, const HostState& shift);

/// Every setting that determines the settled bed, as text: the cavity, gravity, particle
/// and soft-contact sections, the host's held position, the time step and the rule.
std::string settle_key(const Scenario& scenario);

InitialBed prepare_initial_bed(const Scenario& scenario, RunStore& store, const std::atomic<bool>* stop = nullptr,
                               const std::function<void(double t_s, double kinetic_J)>& progress = {});

}  // namespace pdamp
