#pragma once
/// Comparing two stores of one study bit for bit: every sample of each point's latest
/// runs, and every point metric (tests of studies run locally, with any --jobs, resumed,
/// or on a cluster).

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <utility>

#include "pdamp/store/sqlite.hpp"

namespace pdamp::test {

/// The runs of each point's latest attempt in store `alias`, by point and model.
inline std::string latest_runs(const std::string& alias) {
  return "(SELECT l.point, l.model, l.run_id FROM " + alias + ".study_point_runs l JOIN " + alias +
         ".study_points p ON p.study_id = l.study_id AND p.point = l.point AND p.attempt = l.attempt)";
}

/// How many rows of a table of runs (keyed by run_id and `key`) differ between the latest
/// attempts' runs of two stores of one study, bit for bit in `columns` or missing from
/// either, and how many there are. With `offset`, point P of `a` is compared with point
/// P - offset of `b`, and a's points up to `offset` are left out (a curve of a grid against
/// the same curve run alone).
inline std::pair<std::int64_t, std::int64_t> run_row_differences(const std::filesystem::path& a,
                                                                 const std::filesystem::path& b,
                                                                 const std::string& table, const std::string& key,
                                                                 std::initializer_list<const char*> columns,
                                                                 int offset = 0) {
  sqlite::Database d(a);
  d.exec("ATTACH '" + b.string() + "' AS b");
  std::string differs = "y.run_id IS NULL";
  for (const char* column : columns) differs += std::string(" OR x.") + column + " IS NOT y." + column;
  sqlite::Statement q(d, "SELECT coalesce(sum(" + differs + "), 0), count(*), (SELECT count(*) FROM " +
                             latest_runs("b") + " rb JOIN b." + table + " USING (run_id)) FROM " + latest_runs("main") +
                             " ra JOIN " + latest_runs("b") + " rb ON rb.point = ra.point - " + std::to_string(offset) +
                             " AND rb.model = ra.model JOIN main." + table + " x ON x.run_id = ra.run_id LEFT JOIN b." +
                             table + " y ON y.run_id = rb.run_id AND y." + key + " = x." + key + " WHERE ra.point > " +
                             std::to_string(offset));
  q.step();
  const std::int64_t missing_in_a = q.column_int(2) - q.column_int(1);
  return {q.column_int(0) + missing_in_a, q.column_int(1)};
}

/// How many samples of the latest attempts' runs differ between two stores of one study
/// (bit for bit, in every column, or missing from either), and how many there are
/// (`offset` as in run_row_differences).
inline std::pair<std::int64_t, std::int64_t> sample_differences(const std::filesystem::path& a,
                                                                const std::filesystem::path& b, int offset = 0) {
  return run_row_differences(
      a, b, "samples", "t_s",
      {"host_z_m", "host_v_m_s", "particle_translational_J", "particle_rotational_J", "host_kinetic_J",
       "spring_potential_J", "gravitational_potential_J", "contact_elastic_J", "excitation_work_J",
       "dissipated_impact_J", "dissipated_friction_J", "dissipated_viscous_J", "energy_balance_rel_err", "time_steps",
       "collisions", "contacts", "riding_spheres"},
      offset);
}

/// The same for the runs' cycles.
inline std::pair<std::int64_t, std::int64_t> cycle_differences(const std::filesystem::path& a,
                                                               const std::filesystem::path& b) {
  return run_row_differences(a, b, "cycles", "cycle",
                             {"t_start_s", "t_end_s", "amplitude_m", "freq_hz", "gamma", "psi", "psi_impact",
                              "psi_friction", "psi_viscous", "max_host_kinetic_J"});
}

/// The same for the runs' rows: all but their ids, times and wall times.
inline std::pair<std::int64_t, std::int64_t> run_differences(const std::filesystem::path& a,
                                                             const std::filesystem::path& b) {
  return run_row_differences(
      a, b, "runs", "model",
      {"scenario_name", "scenario_text", "seed", "n_particles", "duration_s", "dt_s", "pdamp_version", "status",
       "message", "sim_time_s", "initial_energy_J", "energy_balance_rel_err", "solid_fraction"});
}

/// How many point metrics differ between two stores of one study (all but the wall time).
inline std::int64_t metric_differences(const std::filesystem::path& a, const std::filesystem::path& b) {
  sqlite::Database d(a);
  d.exec("ATTACH '" + b.string() + "' AS b");
  std::string differs = "y.point IS NULL";
  for (const char* column : {"dissipated_impact_J", "dissipated_friction_J", "dissipated_viscous_J", "psi_peak",
                             "psi_peak_gamma", "final_amplitude_m", "cycles", "energy_balance_rel_err"}) {
    differs += std::string(" OR x.") + column + " IS NOT y." + column;
  }
  sqlite::Statement q(d, "SELECT sum(" + differs +
                             ") + abs(count(*) - (SELECT count(*) FROM b.study_point_metrics)) "
                             "FROM main.study_point_metrics x LEFT JOIN b.study_point_metrics y USING (point, model)");
  q.step();
  return q.column_int(0);
}

/// How many of the curve points' metrics in `table` (all but the wall time) differ between
/// two stores, bit for bit, or are missing from the second; -1 if the first has none
/// (`offset` as in run_row_differences).
inline std::int64_t curve_metric_differences(const std::filesystem::path& a, const std::filesystem::path& b,
                                             const std::string& table, std::initializer_list<const char*> columns,
                                             int offset = 0) {
  sqlite::Database d(a);
  d.exec("ATTACH '" + b.string() + "' AS b");
  std::string differs = "y.point IS NULL";
  for (const char* column : columns) differs += std::string(" OR x.") + column + " IS NOT y." + column;
  const std::string shift = std::to_string(offset);
  sqlite::Statement q(d, "SELECT coalesce(sum(" + differs + "), -1) FROM main." + table + " x LEFT JOIN b." + table +
                             " y ON y.point = x.point - " + shift + " WHERE x.point > " + shift);
  q.step();
  return q.column_int(0);
}

/// Every stored frequency-response metric but the wall time that differs (study_frf_metrics;
/// `offset` as in run_row_differences).
inline std::int64_t frf_metric_differences(const std::filesystem::path& a, const std::filesystem::path& b,
                                           int offset = 0) {
  return curve_metric_differences(
      a, b, "study_frf_metrics",
      {"settled", "cycles_to_steady", "cycles_run", "measured_cycles", "amplitude_m", "amplitude_spread_m", "phase_rad",
       "normalised_amplitude", "gamma", "impact_J_per_cycle", "friction_J_per_cycle", "viscous_J_per_cycle",
       "loss_factor", "apparent_mass_kg", "equivalent_damping_N_s_m", "particle_mass_kg"},
      offset);
}

/// Every stored characterisation metric but the wall time that differs (study_characterise_metrics).
inline std::int64_t characterise_metric_differences(const std::filesystem::path& a, const std::filesystem::path& b) {
  return curve_metric_differences(
      a, b, "study_characterise_metrics",
      {"settled", "cycles_to_steady", "cycles_run", "measured_cycles", "amplitude_m", "gamma", "apparent_mass_kg",
       "apparent_mass_spread_kg", "equivalent_damping_N_s_m", "equivalent_damping_spread_N_s_m", "impact_J_per_cycle",
       "friction_J_per_cycle", "loss_factor", "floor_contact_fraction", "lid_contact_fraction", "particle_mass_kg",
       "gravity_m_s2", "free_height_m"});
}

}  // namespace pdamp::test
