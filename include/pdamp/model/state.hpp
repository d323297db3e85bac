#pragma once
/// What an engine reports: the same types from both engines.

#include <cstdint>

#include "pdamp/model/energy_ledger.hpp"
#include "pdamp/model/host.hpp"
#include "pdamp/model/particles.hpp"

namespace pdamp {

struct EngineCounters {
  std::int64_t steps = 0;     ///< time steps taken (soft engine), cumulative
  std::int64_t events = 0;    ///< collisions processed (hard engine), cumulative
  std::int64_t contacts = 0;  ///< contacts open at this instant
};

/// A cheap look at an engine: host, energy ledger, counters. Taken many times per
/// host cycle for the cycle analysis, so it never copies the particles.
struct Observation {
  double t_s = 0.0;
  HostState host;
  EnergyLedger energy;
  EngineCounters counters;
};

/// The full state: an observation plus every particle. Another engine can start from it.
struct State {
  Observation observation;
  Particles particles;
};

}  // namespace pdamp
