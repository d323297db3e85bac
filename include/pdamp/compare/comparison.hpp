#pragma once
/// The metrics that compare a soft and a hard run of one scenario from one bed
/// (docs/comparison-and-results.md, "Metrics"): a pure function of the two runs' samples
/// and cycles, and the step that reads them from the store and stores the comparison.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "pdamp/scenario/scenario.hpp"
#include "pdamp/store/run_store.hpp"

namespace pdamp {

/// Fixed times (s) at which the energy dissipated by each mechanism is compared, besides
/// the end of the runs.
inline constexpr double comparison_times_s[] = {0.05, 0.1, 0.2, 0.5, 1.0};

/// The metrics of two runs' results (every field of ComparisonRecord but the scenario's
/// name, bed and hard restitution). Throws InputError for a run without samples.
ComparisonRecord compare_runs(const RunResults& soft, const RunResults& hard);

/// Compares the soft and the hard run of `scenario` from the bed `bed_state_id` and stores
/// the comparison (`pdamp compare`, a study point of both models); returns its id and what
/// was stored.
std::pair<std::int64_t, ComparisonRecord> store_comparison(RunStore& store, const Scenario& scenario,
                                                           std::optional<std::int64_t> bed_state_id,
                                                           std::int64_t soft_run_id, std::int64_t hard_run_id);

}  // namespace pdamp
