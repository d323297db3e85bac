#pragma once
/// What an engine reports: the same types from both engines.

#include <cstdint>
#include <optional>

#include "pdamp/model/energy_ledger.hpp"
#include "pdamp/model/host.hpp"
#include "pdamp/model/host_load.hpp"
#include "pdamp/model/particles.hpp"

namespace pdamp {

/// What an engine counts, each with one meaning; empty where the engine does not keep it.
struct EngineCounters {
  std::optional<std::int64_t> time_steps;      ///< time steps taken, cumulative (soft engine)
  std::optional<std::int64_t> collisions;      ///< collisions processed, cumulative (hard engine)
  std::optional<std::int64_t> contacts;        ///< contacts open at this instant (soft engine)
  std::optional<std::int64_t> riding_spheres;  ///< spheres riding the host at this instant (hard engine)
  bool operator==(const EngineCounters&) const = default;
};

/// A cheap look at an engine: host, energy ledger, the host's load integrals, counters.
/// Taken many times per host cycle for the cycle analysis, so it never copies the particles.
struct Observation {
  double t_s = 0.0;
  HostState host;
  EnergyLedger energy;
  HostLoadIntegrals host_load;  ///< cumulative since t = 0, integrated exactly by the engine
  EngineCounters counters;
  bool operator==(const Observation&) const = default;
};

/// The full state: an observation plus every particle. Another engine can start from it.
struct State {
  Observation observation;
  Particles particles;
};

/// The energy each sphere has dissipated since t = 0 (J), by mechanism, in the scenario's
/// order: a sphere–sphere contact's loss half to each sphere, a wall's (or the host's)
/// all to the sphere. Summed over the spheres, each equals the ledger's
/// dissipated_impact_J or dissipated_friction_J (up to rounding).
struct SphereDissipation {
  Eigen::VectorXd impact_J;
  Eigen::VectorXd friction_J;
};

}  // namespace pdamp
