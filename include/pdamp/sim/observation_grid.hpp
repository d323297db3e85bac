#pragma once
/// When the run loop observes the engine: the grid of observation steps within each sample
/// interval.

#include <cstdint>

#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

/// Where an observation falls on the run loop's grid of observation steps (ObservationGrid).
struct ObservationStep {
  std::int64_t index = 0;  ///< steps since t = 0: the engine is at index × step_s
  /// false for the run's last observation if the duration ends between two steps (the
  /// engine is then at the duration, before step `index`)
  bool on_grid = true;
};

/// How often the run loop observes the engine (s): ≥ 256 times per natural period of
/// the host (or of the excitation, if faster), and at every sample.
double observation_interval_s(const Scenario& scenario);

/// The times the run loop observes the engine: every sample interval Δ split into
/// `steps_per_sample` steps of `step_s` (≤ observation_interval_s), step j of sample
/// interval k at k Δ + j step_s, computed so that samples fall exactly on multiples of Δ.
struct ObservationGrid {
  long steps_per_sample;
  double step_s;
  double sample_interval_s;
  /// The time of observation step `index` (s), as the run loop advances the engine to it:
  /// the engines stop exactly there.
  double time_s(std::int64_t index) const {
    const std::int64_t sample = index / steps_per_sample, step = index % steps_per_sample;
    return static_cast<double>(sample) * sample_interval_s + static_cast<double>(step) * step_s;
  }
};
ObservationGrid observation_grid(const Scenario& scenario);

}  // namespace pdamp
