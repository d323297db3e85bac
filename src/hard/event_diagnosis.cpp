#include "hard/event_diagnosis.hpp"

#include <array>
#include <cmath>

#include "pdamp/model/hertz_contact.hpp"

namespace pdamp::hard {

namespace {

constexpr const char* kind_names[] = {"sphere_sphere", "side_wall", "cap", "rider"};
constexpr const char* interval_names[] = {"dt_same_instant", "dt_below_0.01tc", "dt_0.01_0.1tc",  "dt_0.1_1tc",
                                          "dt_1_10tc",       "dt_10_100tc",     "dt_above_100tc", "dt_first"};
constexpr const char* speed_names[] = {"v_below_1e-4", "v_1e-4_1e-3", "v_1e-3_1e-2",
                                       "v_1e-2_1e-1",  "v_1e-1_1",    "v_above_1"};

}  // namespace

EventDiagnosis::EventDiagnosis(const Scenario& scenario)
    : EventDiagnosis(scenario.soft_particle.kn_N_m1_5, scenario.soft_wall.kn_N_m1_5) {}

EventDiagnosis::Interval EventDiagnosis::interval_of(double since_previous_s, double contact_time_s) {
  if (std::isinf(since_previous_s)) return first;
  if (since_previous_s == 0.0) return same_instant;
  const double ratio = since_previous_s / contact_time_s;
  if (ratio < 0.01) return below_0_01;
  if (ratio < 0.1) return below_0_1;
  if (ratio < 1.0) return below_1;
  if (ratio < 10.0) return below_10;
  if (ratio < 100.0) return below_100;
  return at_least_100;
}

std::size_t EventDiagnosis::speed_bin_of(double approach_m_s) {
  constexpr std::array<double, speed_bins - 1> lower_edges_m_s{1e-4, 1e-3, 1e-2, 1e-1, 1.0};
  std::size_t bin = 0;
  while (bin < lower_edges_m_s.size() && approach_m_s >= lower_edges_m_s[bin]) ++bin;
  return bin;
}

bool EventDiagnosis::count_interval(Counts& counts, double since_previous_s, double contact_time_s) {
  ++counts.intervals[interval_of(since_previous_s, contact_time_s)];
  return since_previous_s < contact_time_s;
}

void EventDiagnosis::note(Kind kind, double t_s, double approach_m_s, double effective_mass_kg, double previous_s,
                          double partner_previous_s) {
  Counts& counts = counts_[kind];
  const double kn = kind == side_wall || kind == cap ? wall_kn_N_m1_5_ : sphere_kn_N_m1_5_;
  const double contact_time_s = hertz_contact_time_s(effective_mass_kg, kn, approach_m_s);
  const bool fast = count_interval(counts, t_s - previous_s, contact_time_s);
  const bool partner_fast =
      !std::isnan(partner_previous_s) && count_interval(counts, t_s - partner_previous_s, contact_time_s);
  if (fast || partner_fast) ++counts.within_contact_time;
  ++counts.speeds[speed_bin_of(approach_m_s)];
}

EngineStatistics EventDiagnosis::named() const {
  EngineStatistics named;
  for (std::size_t k = 0; k < kind_count; ++k) {
    const std::string prefix = std::string("diagnosis_") + kind_names[k] + "_";
    const Counts& c = counts_[k];
    for (std::size_t b = 0; b < interval_count; ++b) named.emplace_back(prefix + interval_names[b], c.intervals[b]);
    named.emplace_back(prefix + "within_tc", c.within_contact_time);
    for (std::size_t b = 0; b < speed_bins; ++b) named.emplace_back(prefix + speed_names[b], c.speeds[b]);
  }
  return named;
}

}  // namespace pdamp::hard
