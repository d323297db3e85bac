#pragma once
/// The metrics that compare a soft and a hard run of one scenario from one bed
/// (docs/comparison-and-results.md, "Metrics"), computed from what the store holds of the
/// two runs.

#include <cstdint>
#include <string>

#include "pdamp/store/run_store.hpp"

namespace pdamp {

/// Fixed times (s) at which the energy dissipated by each mechanism is compared, besides
/// the end of the runs.
inline constexpr double comparison_times_s[] = {0.05, 0.1, 0.2, 0.5, 1.0};

ComparisonRecord compare_stored_runs(RunStore& store, std::int64_t soft_run_id, std::int64_t hard_run_id);

}  // namespace pdamp
