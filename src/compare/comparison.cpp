#include "pdamp/compare/comparison.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "pdamp/errors.hpp"

namespace pdamp {
namespace {

struct Cycle {
  double t_mid_s, amplitude_m, freq_hz, psi;
  std::optional<double> gamma;
  double t_start_s;
};

std::vector<Cycle> load_cycles(RunStore& store, std::int64_t run_id) {
  sqlite::Statement q(store.database(),
                      "SELECT t_start_s, t_end_s, amplitude_m, freq_hz, gamma, psi FROM cycles WHERE run_id = ? "
                      "ORDER BY cycle");
  q.bind(1, run_id);
  std::vector<Cycle> cycles;
  while (q.step()) {
    cycles.push_back({0.5 * (q.column_double(0) + q.column_double(1)), q.column_double(2), q.column_double(3),
                      q.column_double(5), q.column_optional_double(4), q.column_double(0)});
  }
  return cycles;
}

struct Dissipation {
  double t_s = 0.0, impact_J = 0.0, friction_J = 0.0, viscous_J = 0.0;
  std::int64_t steps = 0, events = 0;
  double total_J() const { return impact_J + friction_J + viscous_J; }
};

/// The last sample at or before t (or the run's last sample).
Dissipation dissipation_at(RunStore& store, std::int64_t run_id, double t_s) {
  sqlite::Statement q(store.database(),
                      "SELECT t_s, dissipated_impact_J, dissipated_friction_J, dissipated_viscous_J, steps, events "
                      "FROM samples WHERE run_id = ? AND t_s <= ? ORDER BY t_s DESC LIMIT 1");
  q.bind(1, run_id).bind(2, t_s * (1.0 + 1e-12));
  if (!q.step()) throw InputError("run " + std::to_string(run_id) + " has no samples to compare");
  return {q.column_double(0), q.column_double(1), q.column_double(2),
          q.column_double(3), q.column_int(4),    q.column_int(5)};
}

double wall_time(RunStore& store, std::int64_t run_id) {
  const auto s = store.summary(run_id);
  if (!s) throw InputError("run " + std::to_string(run_id) + " is not in the store");
  return s->wall_time_s.value_or(0.0);
}

/// Amplitude of a run's cycles at time t, interpolated between cycle mid-times.
std::optional<double> amplitude_at(const std::vector<Cycle>& cycles, double t_s) {
  if (cycles.empty() || t_s < cycles.front().t_mid_s || t_s > cycles.back().t_mid_s) return std::nullopt;
  const auto after =
      std::lower_bound(cycles.begin(), cycles.end(), t_s, [](const Cycle& c, double t) { return c.t_mid_s < t; });
  if (after == cycles.begin()) return after->amplitude_m;
  const auto before = after - 1;
  const double f = (t_s - before->t_mid_s) / (after->t_mid_s - before->t_mid_s);
  return before->amplitude_m + f * (after->amplitude_m - before->amplitude_m);
}

std::optional<double> small_amplitude_frequency(const std::vector<Cycle>& cycles) {
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

std::optional<double> first_time_below_gamma_1(const std::vector<Cycle>& cycles) {
  for (const auto& c : cycles) {
    if (c.gamma && *c.gamma < 1.0) return c.t_start_s;
  }
  return std::nullopt;
}

/// ψ per Γ bin [2^k, 2^(k+1)): (sum, count) per model.
std::map<int, std::pair<double, int>> psi_by_gamma_bin(const std::vector<Cycle>& cycles) {
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

ComparisonRecord compare_stored_runs(RunStore& store, std::int64_t soft_run_id, std::int64_t hard_run_id) {
  ComparisonRecord r;
  r.soft_run_id = soft_run_id;
  r.hard_run_id = hard_run_id;
  const auto soft = load_cycles(store, soft_run_id), hard = load_cycles(store, hard_run_id);

  if (!soft.empty()) {
    const double reference = soft.front().amplitude_m;
    double worst = 0.0, squares = 0.0;
    int compared = 0;
    for (const auto& c : soft) {
      const auto other = amplitude_at(hard, c.t_mid_s);
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

  const Dissipation soft_end = dissipation_at(store, soft_run_id, 1e300),
                    hard_end = dissipation_at(store, hard_run_id, 1e300);
  r.dissipated_soft_J = soft_end.total_J();
  r.dissipated_hard_J = hard_end.total_J();
  if (r.dissipated_soft_J > 0.0)
    r.dissipated_rel_diff = (r.dissipated_hard_J - r.dissipated_soft_J) / r.dissipated_soft_J;
  std::vector<double> times;
  for (const double t : comparison_times_s) {
    if (t <= std::min(soft_end.t_s, hard_end.t_s)) times.push_back(t);
  }
  times.push_back(std::min(soft_end.t_s, hard_end.t_s));
  times.erase(std::unique(times.begin(), times.end()), times.end());
  for (const double t : times) {
    for (const auto& [model, id] : {std::pair{"soft", soft_run_id}, std::pair{"hard", hard_run_id}}) {
      const Dissipation d = dissipation_at(store, id, t);
      r.energy.push_back({t, model, d.impact_J, d.friction_J, d.viscous_J});
    }
  }
  r.wall_time_soft_s = wall_time(store, soft_run_id);
  r.wall_time_hard_s = wall_time(store, hard_run_id);
  if (r.wall_time_hard_s > 0.0) r.wall_time_ratio = r.wall_time_soft_s / r.wall_time_hard_s;
  r.soft_steps = soft_end.steps;
  r.hard_events = hard_end.events;
  return r;
}

std::pair<std::int64_t, ComparisonRecord> store_comparison(RunStore& store, const Scenario& scenario,
                                                           std::optional<std::int64_t> bed_state_id,
                                                           std::int64_t soft_run_id, std::int64_t hard_run_id) {
  ComparisonRecord comparison = compare_stored_runs(store, soft_run_id, hard_run_id);
  comparison.scenario_name = scenario.name;
  comparison.initial_state_id = bed_state_id;
  comparison.hard_restitution = scenario.hard_restitution == HardRestitution::calibrated ? "calibrated" : "constant";
  const std::int64_t id = store.save_comparison(comparison);
  return {id, std::move(comparison)};
}

}  // namespace pdamp
