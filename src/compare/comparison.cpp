#include "pdamp/compare/comparison.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "pdamp/errors.hpp"

namespace pdamp {
namespace {

/// The last sample at or before t (or the run's last sample).
const Observation& observation_at(const RunResults& run, double t_s) {
  const auto after = std::upper_bound(run.samples.begin(), run.samples.end(), t_s * (1.0 + 1e-12),
                                      [](double t, const SampleRecord& sample) { return t < sample.observation.t_s; });
  if (after == run.samples.begin()) {
    throw InputError("run " + std::to_string(run.run_id) + " has no samples to compare" +
                     (run.samples.empty() ? "" : " at t = " + std::to_string(t_s) + " s"));
  }
  return (after - 1)->observation;
}

double mid_time_s(const CycleRecord& c) { return 0.5 * (c.t_start_s + c.t_end_s); }

/// Amplitude of a run's cycles at time t, interpolated between cycle mid-times.
std::optional<double> amplitude_at(const std::vector<CycleRecord>& cycles, double t_s) {
  if (cycles.empty() || t_s < mid_time_s(cycles.front()) || t_s > mid_time_s(cycles.back())) return std::nullopt;
  const auto after = std::lower_bound(cycles.begin(), cycles.end(), t_s,
                                      [](const CycleRecord& c, double t) { return mid_time_s(c) < t; });
  if (after == cycles.begin()) return after->amplitude_m;
  const auto before = after - 1;
  const double f = (t_s - mid_time_s(*before)) / (mid_time_s(*after) - mid_time_s(*before));
  return before->amplitude_m + f * (after->amplitude_m - before->amplitude_m);
}

std::optional<double> small_amplitude_frequency(const std::vector<CycleRecord>& cycles) {
  double sum = 0.0;
  int count = 0;
  for (const auto& c : cycles) {
    if (c.gamma && *c.gamma < 1.0) {
      sum += c.freq_hz;
      ++count;
    }
  }
  return count > 0 ? std::optional(sum / count) : std::nullopt;
}

std::optional<double> first_time_below_gamma_1(const std::vector<CycleRecord>& cycles) {
  for (const auto& c : cycles) {
    if (c.gamma && *c.gamma < 1.0) return c.t_start_s;
  }
  return std::nullopt;
}

/// ψ per Γ bin [2^k, 2^(k+1)): (sum, count) per model.
std::map<int, std::pair<double, int>> psi_by_gamma_bin(const std::vector<CycleRecord>& cycles) {
  std::map<int, std::pair<double, int>> bins;
  for (const auto& c : cycles) {
    if (!c.gamma || *c.gamma <= 0.0) continue;
    auto& [sum, count] = bins[static_cast<int>(std::floor(std::log2(*c.gamma)))];
    sum += c.psi;
    ++count;
  }
  return bins;
}

}  // namespace

ComparisonRecord compare_runs(const RunResults& soft_run, const RunResults& hard_run) {
  ComparisonRecord r;
  r.soft_run_id = soft_run.run_id;
  r.hard_run_id = hard_run.run_id;
  const auto &soft = soft_run.cycles, &hard = hard_run.cycles;

  if (!soft.empty()) {
    const double reference = soft.front().amplitude_m;
    double worst = 0.0, squares = 0.0;
    int compared = 0;
    for (const auto& c : soft) {
      const auto other = amplitude_at(hard, mid_time_s(c));
      if (!other) continue;
      const double difference = std::abs(*other - c.amplitude_m) / reference;
      worst = std::max(worst, difference);
      squares += difference * difference;
      ++compared;
    }
    if (compared > 0) {
      r.envelope_max_rel_diff = worst;
      r.envelope_rms_rel_diff = std::sqrt(squares / compared);
    }
  }
  r.small_amplitude_freq_soft_hz = small_amplitude_frequency(soft);
  r.small_amplitude_freq_hard_hz = small_amplitude_frequency(hard);
  r.gamma_below_1_soft_s = first_time_below_gamma_1(soft);
  r.gamma_below_1_hard_s = first_time_below_gamma_1(hard);

  const auto soft_bins = psi_by_gamma_bin(soft), hard_bins = psi_by_gamma_bin(hard);
  std::map<int, bool> keys;
  for (const auto& [k, v] : soft_bins) keys[k] = true;
  for (const auto& [k, v] : hard_bins) keys[k] = true;
  double differences = 0.0;
  int shared = 0;
  for (const auto& [k, unused] : keys) {
    ComparisonRecord::PsiBin bin{std::ldexp(1.0, k), std::ldexp(1.0, k + 1), std::nullopt, std::nullopt, 0, 0};
    if (const auto it = soft_bins.find(k); it != soft_bins.end()) {
      bin.psi_soft = it->second.first / it->second.second;
      bin.cycles_soft = it->second.second;
    }
    if (const auto it = hard_bins.find(k); it != hard_bins.end()) {
      bin.psi_hard = it->second.first / it->second.second;
      bin.cycles_hard = it->second.second;
    }
    if (bin.psi_soft && bin.psi_hard) {
      differences += std::abs(*bin.psi_hard - *bin.psi_soft);
      ++shared;
    }
    r.psi_bins.push_back(bin);
  }
  if (shared > 0) r.psi_mean_abs_diff = differences / shared;

  const Observation &soft_end = observation_at(soft_run, 1e300), &hard_end = observation_at(hard_run, 1e300);
  r.dissipated_soft_J = soft_end.energy.dissipated_J();
  r.dissipated_hard_J = hard_end.energy.dissipated_J();
  if (r.dissipated_soft_J > 0.0)
    r.dissipated_rel_diff = (r.dissipated_hard_J - r.dissipated_soft_J) / r.dissipated_soft_J;
  const double end_s = std::min(soft_end.t_s, hard_end.t_s);
  std::vector<double> times;
  for (const double t : comparison_times_s) {
    if (t <= end_s) times.push_back(t);
  }
  times.push_back(end_s);
  times.erase(std::unique(times.begin(), times.end()), times.end());
  for (const double t : times) {
    for (const auto& [model, run] : {std::pair{"soft", &soft_run}, std::pair{"hard", &hard_run}}) {
      const EnergyLedger& e = observation_at(*run, t).energy;
      r.energy.push_back({t, model, e.dissipated_impact_J, e.dissipated_friction_J, e.dissipated_viscous_J});
    }
  }
  r.wall_time_soft_s = soft_run.wall_time_s;
  r.wall_time_hard_s = hard_run.wall_time_s;
  if (r.wall_time_hard_s > 0.0) r.wall_time_ratio = r.wall_time_soft_s / r.wall_time_hard_s;
  r.soft_steps = soft_end.counters.time_steps.value_or(0);
  r.hard_events = hard_end.counters.collisions.value_or(0);
  return r;
}

std::pair<std::int64_t, ComparisonRecord> store_comparison(RunStore& store, const Scenario& scenario,
                                                           std::optional<std::int64_t> bed_state_id,
                                                           std::int64_t soft_run_id, std::int64_t hard_run_id) {
  ComparisonRecord comparison = compare_runs(store.results(soft_run_id), store.results(hard_run_id));
  comparison.scenario_name = scenario.name;
  comparison.initial_state_id = bed_state_id;
  comparison.hard_restitution = scenario.hard_restitution == HardRestitution::calibrated ? "calibrated" : "constant";
  const std::int64_t id = store.save_comparison(comparison);
  return {id, std::move(comparison)};
}

}  // namespace pdamp
