#include "pdamp/store/study_store.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <sstream>
#include <utility>

#include "pdamp/errors.hpp"
#include "pdamp/version.hpp"

namespace pdamp {
namespace {

/// The time as run_store.cpp writes it: ISO 8601, UTC, milliseconds.
constexpr std::string_view now_sql = "strftime('%Y-%m-%dT%H:%M:%fZ', 'now')";

std::string with_now(std::string_view before, std::string_view after) {
  return std::string(before) + std::string(now_sql) + std::string(after);
}

/// The value as a number if it is exactly one finite number.
std::optional<double> single_number(const std::string& value) {
  std::istringstream in(value);
  std::string word, extra;
  if (!(in >> word) || (in >> extra)) return std::nullopt;
  double x = 0.0;
  const char* end = word.data() + word.size();
  if (auto [ptr, ec] = std::from_chars(word.data(), end, x); ec != std::errc() || ptr != end || !std::isfinite(x)) {
    return std::nullopt;
  }
  return x;
}

constexpr std::string_view study_columns =
    "SELECT study_id, name, models, study_file, study_text, scenario_file, scenario_text, pdamp_version, "
    "created_at, n_points FROM studies";

StudyRecord read_study(const sqlite::Statement& q) {
  return {q.column_int(0),  q.column_text(1), q.column_text(2), q.column_text(3), q.column_text(4),
          q.column_text(5), q.column_text(6), q.column_text(7), q.column_text(8), static_cast<int>(q.column_int(9))};
}

constexpr std::string_view summary_columns =
    "SELECT study_id, name, models, created_at, n_points, completed, failed, interrupted, running, pending "
    "FROM study_summary";

StudySummary read_summary(const sqlite::Statement& q) {
  StudySummary s;
  s.study_id = q.column_int(0);
  s.name = q.column_text(1);
  s.models = q.column_text(2);
  s.created_at = q.column_text(3);
  int* counts[] = {&s.n_points, &s.completed, &s.failed, &s.interrupted, &s.running, &s.pending};
  for (int c = 0; c < 6; ++c) *counts[c] = static_cast<int>(q.column_int(4 + c));
  return s;
}

constexpr std::string_view point_columns =
    "SELECT point, section, status, attempt, message, lease_host, lease_pid, lease_start FROM study_points";

StudyPointState read_point(const sqlite::Statement& q) {
  StudyPointState p{static_cast<int>(q.column_int(0)), q.column_text(1), parse_point_status(q.column_text(2)),
                    static_cast<int>(q.column_int(3)), q.column_text(4), std::nullopt};
  if (!q.is_null(6)) p.lease = ProcessLease{q.column_text(5), q.column_int(6), q.column_int(7)};
  return p;
}

/// The first row of a query with one parameter, read by `read`.
template <typename Key, typename Read>
auto first_row(sqlite::Database& db, const std::string& sql, Key key, Read read)
    -> std::optional<decltype(read(std::declval<const sqlite::Statement&>()))> {
  sqlite::Statement q(db, sql);
  q.bind(1, key);
  if (!q.step()) return std::nullopt;
  return read(q);
}

}  // namespace

namespace {

constexpr std::array<std::pair<PointStatus, std::string_view>, 5> point_statuses{
    {{PointStatus::pending, "pending"},
     {PointStatus::running, "running"},
     {PointStatus::completed, "completed"},
     {PointStatus::failed, "failed"},
     {PointStatus::interrupted, "interrupted"}}};

}  // namespace

std::string_view to_string(PointStatus status) {
  for (const auto& [value, name] : point_statuses) {
    if (value == status) return name;
  }
  throw RuntimeFailure("a study point status out of range");
}

PointStatus parse_point_status(std::string_view text) {
  for (const auto& [value, name] : point_statuses) {
    if (name == text) return value;
  }
  throw RuntimeFailure("unknown study point status '" + std::string(text) + "' in the store");
}

std::int64_t StudyStore::create_study(const NewStudy& s, const std::vector<NewStudyPoint>& points) {
  return sqlite::write_transaction(db(), [&] {
    sqlite::Statement insert(db(), with_now("INSERT INTO studies (name, models, n_points, study_file, study_text, "
                                            "scenario_file, scenario_text, pdamp_version, created_at) "
                                            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ",
                                            ")"));
    insert.bind(1, s.name)
        .bind(2, s.models)
        .bind(3, static_cast<std::int64_t>(points.size()))
        .bind(4, s.study_file)
        .bind(5, s.study_text)
        .bind(6, s.scenario_file)
        .bind(7, s.scenario_text)
        .bind(8, std::string_view(version_string));
    insert.run();
    const std::int64_t id = db().last_insert_rowid();
    insert_points(id, points);
    return id;
  });
}

void StudyStore::copy_study(const StudyRecord& s) {
  sqlite::write_transaction(db(), [&] {
    sqlite::Statement insert(db(),
                             "INSERT INTO studies (study_id, name, models, n_points, study_file, study_text, "
                             "scenario_file, scenario_text, pdamp_version, created_at) "
                             "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    insert.bind(1, s.study_id).bind(2, s.name).bind(3, s.models).bind(4, s.n_points).bind(5, s.study_file);
    insert.bind(6, s.study_text).bind(7, s.scenario_file).bind(8, s.scenario_text).bind(9, s.pdamp_version);
    insert.bind(10, s.created_at).run();
  });
}

void StudyStore::add_points(std::int64_t study_id, const std::vector<NewStudyPoint>& points) {
  sqlite::write_transaction(db(), [&] { insert_points(study_id, points); });
}

void StudyStore::insert_points(std::int64_t study_id, const std::vector<NewStudyPoint>& points) {
  sqlite::Statement point(db(), "INSERT INTO study_points (study_id, point, section) VALUES (?, ?, ?)");
  sqlite::Statement frf(db(),
                        "INSERT INTO study_frf_points (study_id, point, curve, model, direction, host_alone, mode, "
                        "level, frequency_hz, step, previous_point, grid) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  sqlite::Statement value(
      db(), "INSERT INTO study_point_values (study_id, point, key, value, number) VALUES (?, ?, ?, ?, ?)");
  sqlite::Statement characterise(
      db(),
      "INSERT INTO study_characterise_points (study_id, point, curve, model, empty, amplitude_m, gamma_given, "
      "frequency_hz, step, previous_point) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  for (const auto& p : points) {
    point.bind(1, study_id).bind(2, p.point).bind(3, p.section).run();
    for (const auto& [key, text] : p.values) {
      value.bind(1, study_id).bind(2, p.point).bind(3, key).bind(4, text).bind(5, single_number(text)).run();
    }
    if (const auto& c = p.characterise) {
      characterise.bind(1, study_id).bind(2, p.point).bind(3, c->curve).bind(4, c->model);
      characterise.bind(5, static_cast<std::int64_t>(c->empty)).bind(6, c->amplitude_m).bind(7, c->gamma_given);
      characterise.bind(8, c->frequency_hz).bind(9, c->step);
      characterise.bind(10, c->previous_point > 0 ? std::optional<std::int64_t>(c->previous_point) : std::nullopt);
      characterise.run();
    }
    if (!p.frf) continue;
    const FrfPointRow& f = *p.frf;
    frf.bind(1, study_id).bind(2, p.point).bind(3, f.curve).bind(4, f.model).bind(5, f.direction);
    frf.bind(6, static_cast<std::int64_t>(f.host_alone)).bind(7, f.mode).bind(8, f.level).bind(9, f.frequency_hz);
    frf.bind(10, f.step).bind(11, f.previous_point > 0 ? std::optional<std::int64_t>(f.previous_point) : std::nullopt);
    frf.bind(12, f.grid).run();
  }
}

std::optional<StudyRecord> StudyStore::find_study(std::string_view name) {
  return first_row(db(), std::string(study_columns) + " WHERE name = ?", name, read_study);
}

std::optional<StudyRecord> StudyStore::study(std::int64_t study_id) {
  return first_row(db(), std::string(study_columns) + " WHERE study_id = ?", study_id, read_study);
}

std::vector<StudyRecord> StudyStore::studies() {
  sqlite::Statement q(db(), std::string(study_columns) + " ORDER BY study_id");
  std::vector<StudyRecord> records;
  while (q.step()) records.push_back(read_study(q));
  return records;
}

std::int64_t StudyStore::next_study_id() {
  sqlite::Statement next(db(), "SELECT coalesce(max(seq), 0) + 1 FROM sqlite_sequence WHERE name = 'studies'");
  next.step();
  return next.column_int(0);
}

std::vector<StudySummary> StudyStore::list_studies() {
  sqlite::Statement q(db(), std::string(summary_columns) + " ORDER BY study_id");
  std::vector<StudySummary> studies;
  while (q.step()) studies.push_back(read_summary(q));
  return studies;
}

std::optional<StudySummary> StudyStore::summary(std::int64_t study_id) {
  return first_row(db(), std::string(summary_columns) + " WHERE study_id = ?", study_id, read_summary);
}

std::vector<StudyPointState> StudyStore::points(std::int64_t study_id) {
  sqlite::Statement q(db(), std::string(point_columns) + " WHERE study_id = ? ORDER BY point");
  q.bind(1, study_id);
  std::vector<StudyPointState> points;
  while (q.step()) points.push_back(read_point(q));
  return points;
}

std::optional<StudyPointState> StudyStore::point(std::int64_t study_id, int point) {
  sqlite::Statement q(db(), std::string(point_columns) + " WHERE study_id = ? AND point = ?");
  q.bind(1, study_id).bind(2, point);
  if (!q.step()) return std::nullopt;
  return read_point(q);
}

std::vector<PointMetrics> StudyStore::metrics(std::int64_t study_id) {
  sqlite::Statement q(db(),
                      "SELECT m.point, m.model, m.run_id, m.dissipated_impact_J, m.dissipated_friction_J, "
                      "m.dissipated_viscous_J, m.psi_peak, m.psi_peak_gamma, m.final_amplitude_m, m.cycles, "
                      "m.energy_balance_rel_err, m.wall_time_s, a.dissipated_rel_diff, a.envelope_max_rel_diff "
                      "FROM study_point_metrics m LEFT JOIN study_agreement a "
                      "ON a.study_id = m.study_id AND a.point = m.point "
                      "WHERE m.study_id = ? ORDER BY m.point, m.model DESC");
  q.bind(1, study_id);
  std::vector<PointMetrics> rows;
  while (q.step()) {
    PointMetrics m;
    m.point = static_cast<int>(q.column_int(0));
    m.model = q.column_text(1);
    m.run_id = q.column_int(2);
    m.dissipated_impact_J = q.column_double(3);
    m.dissipated_friction_J = q.column_double(4);
    m.dissipated_viscous_J = q.column_double(5);
    m.psi_peak = q.column_optional_double(6);
    m.psi_peak_gamma = q.column_optional_double(7);
    m.final_amplitude_m = q.column_optional_double(8);
    m.cycles = q.column_int(9);
    m.energy_balance_rel_err = q.column_double(10);
    m.wall_time_s = q.column_double(11);
    m.dissipated_rel_diff = q.column_optional_double(12);
    m.envelope_max_rel_diff = q.column_optional_double(13);
    rows.push_back(std::move(m));
  }
  return rows;
}

std::optional<int> StudyStore::claim_point(std::int64_t study_id, int point, const ProcessLease& lease) {
  return sqlite::write_transaction(db(), [&]() -> std::optional<int> {
    sqlite::Statement claim(db(), with_now("UPDATE study_points SET status = 'running', attempt = attempt + 1, "
                                           "message = '', lease_host = ?, lease_pid = ?, lease_start = ?, "
                                           "ended_at = NULL, comparison_id = NULL, started_at = ",
                                           " WHERE study_id = ? AND point = ? "
                                           "AND status IN ('pending', 'failed', 'interrupted') RETURNING attempt"));
    claim.bind(1, lease.host).bind(2, lease.pid).bind(3, lease.start_ticks).bind(4, study_id).bind(5, point);
    if (!claim.step()) return std::nullopt;
    const int attempt = static_cast<int>(claim.column_int(0));
    claim.reset();
    // A redone point's earlier metrics and final state belong to runs of an earlier attempt.
    for (const char* table :
         {"study_point_metrics", "study_frf_metrics", "study_characterise_metrics", "study_point_states"}) {
      sqlite::Statement old(db(), std::string("DELETE FROM ") + table + " WHERE study_id = ? AND point = ?");
      old.bind(1, study_id).bind(2, point).run();
    }
    return attempt;
  });
}

void StudyStore::link_run(std::int64_t study_id, int point, int attempt, std::string_view model, std::int64_t run_id) {
  sqlite::write_transaction(db(), [&] {
    sqlite::Statement link(
        db(), "INSERT INTO study_point_runs (study_id, point, attempt, model, run_id) VALUES (?, ?, ?, ?, ?)");
    link.bind(1, study_id).bind(2, point).bind(3, attempt).bind(4, model).bind(5, run_id).run();
  });
}

std::optional<std::int64_t> StudyStore::earlier_run(std::int64_t study_id, int point, int attempt,
                                                    std::string_view model) {
  sqlite::Statement q(db(),
                      "SELECT run_id FROM study_point_runs WHERE study_id = ? AND point = ? AND attempt < ? AND "
                      "model = ? ORDER BY attempt DESC LIMIT 1");
  q.bind(1, study_id).bind(2, point).bind(3, attempt).bind(4, model);
  if (!q.step()) return std::nullopt;
  return q.column_int(0);
}

std::optional<CurvePointRun> StudyStore::curve_point_of_run(std::int64_t run_id) {
  sqlite::Statement q(db(),
                      "SELECT l.study_id, l.point, CASE WHEN f.point IS NOT NULL THEN 'frf' ELSE 'characterise' END "
                      "FROM study_point_runs l "
                      "LEFT JOIN study_frf_points f ON f.study_id = l.study_id AND f.point = l.point "
                      "LEFT JOIN study_characterise_points c ON c.study_id = l.study_id AND c.point = l.point "
                      "WHERE l.run_id = ? AND (f.point IS NOT NULL OR c.point IS NOT NULL)");
  q.bind(1, run_id);
  if (!q.step()) return std::nullopt;
  return CurvePointRun{q.column_int(0), static_cast<int>(q.column_int(1)), q.column_text(2)};
}

void StudyStore::move_run(std::int64_t study_id, int point, int attempt, std::int64_t run_id) {
  sqlite::write_transaction(db(), [&] {
    sqlite::Statement move(db(),
                           "UPDATE study_point_runs SET attempt = ? WHERE study_id = ? AND point = ? AND run_id = ?");
    move.bind(1, attempt).bind(2, study_id).bind(3, point).bind(4, run_id).run();
  });
}

void StudyStore::complete_point(std::int64_t study_id, int point, int attempt, const std::vector<std::int64_t>& run_ids,
                                std::optional<std::int64_t> comparison_id) {
  sqlite::write_transaction(db(), [&] {
    sqlite::Statement metrics(
        db(),
        "INSERT INTO study_point_metrics (study_id, point, model, run_id, dissipated_impact_J, dissipated_friction_J, "
        "dissipated_viscous_J, psi_peak, psi_peak_gamma, final_amplitude_m, cycles, energy_balance_rel_err, "
        "wall_time_s) "
        "SELECT ?1, ?2, r.model, r.run_id, last.dissipated_impact_J, last.dissipated_friction_J, "
        "last.dissipated_viscous_J, peak.psi, peak.gamma, last_cycle.amplitude_m, "
        "(SELECT count(*) FROM cycles WHERE run_id = r.run_id), r.energy_balance_rel_err, r.wall_time_s "
        "FROM runs r "
        "JOIN samples last ON last.run_id = r.run_id "
        "AND last.t_s = (SELECT max(t_s) FROM samples WHERE run_id = r.run_id) "
        "LEFT JOIN cycles peak ON peak.run_id = r.run_id "
        "AND peak.cycle = (SELECT cycle FROM cycles WHERE run_id = r.run_id ORDER BY psi DESC, cycle LIMIT 1) "
        "LEFT JOIN cycles last_cycle ON last_cycle.run_id = r.run_id "
        "AND last_cycle.cycle = (SELECT max(cycle) FROM cycles WHERE run_id = r.run_id) "
        "WHERE r.run_id = ?3 AND r.status = 'completed'");
    for (const std::int64_t run_id : run_ids) {
      metrics.bind(1, study_id).bind(2, point).bind(3, run_id);
      metrics.run();
      if (db().changes() != 1) {
        throw RuntimeFailure("study " + std::to_string(study_id) + " point " + std::to_string(point) + ": run " +
                             std::to_string(run_id) + " is not a completed run with samples");
      }
    }
    sqlite::Statement done(db(), with_now("UPDATE study_points SET status = 'completed', message = '', "
                                          "lease_host = NULL, lease_pid = NULL, lease_start = NULL, comparison_id = ?, "
                                          "ended_at = ",
                                          " WHERE study_id = ? AND point = ? AND attempt = ? AND status = 'running'"));
    if (comparison_id) {
      done.bind(1, *comparison_id);
    } else {
      done.bind_null(1);
    }
    done.bind(2, study_id).bind(3, point).bind(4, attempt).run();
    if (db().changes() != 1) {
      throw RuntimeFailure("study " + std::to_string(study_id) + " point " + std::to_string(point) + " attempt " +
                           std::to_string(attempt) + " is no longer running here; its results are not counted");
    }
  });
}

std::int64_t StudyStore::store_end_and_complete(std::int64_t study_id, int point, int attempt, const std::string& label,
                                                const FrfEndState& end, const Particles& end_spheres, double kinetic_J,
                                                double wall_time_s) {
  const std::int64_t state_id =
      insert_initial_state(db(), label, end_spheres, end.t_s, kinetic_J, wall_time_s).state_id;
  sqlite::Statement state(db(),
                          "INSERT INTO study_point_states (study_id, point, run_id, state_id, t_s, host_z_m, "
                          "host_v_m_s) VALUES (?, ?, ?, ?, ?, ?, ?)");
  state.bind(1, study_id).bind(2, point).bind(3, end.run_id).bind(4, state_id).bind(5, end.t_s);
  state.bind(6, end.host.z_m).bind(7, end.host.v_m_s).run();
  sqlite::Statement done(db(), with_now("UPDATE study_points SET status = 'completed', message = '', "
                                        "lease_host = NULL, lease_pid = NULL, lease_start = NULL, ended_at = ",
                                        " WHERE study_id = ? AND point = ? AND attempt = ? AND status = 'running'"));
  done.bind(1, study_id).bind(2, point).bind(3, attempt).run();
  if (db().changes() != 1) {
    throw RuntimeFailure("study " + std::to_string(study_id) + " point " + std::to_string(point) + " attempt " +
                         std::to_string(attempt) + " is no longer running here; its results are not counted");
  }
  // The run's last checkpoint (most of a point's bytes) has served: the curve goes on from
  // the end state just stored, and a completed point is never continued.
  sqlite::Statement forget(db(), "DELETE FROM run_checkpoints WHERE run_id = ?");
  forget.bind(1, end.run_id).run();
  return state_id;
}

std::int64_t StudyStore::complete_frf_point(std::int64_t study_id, int point, int attempt, const FrfPointResult& r,
                                            const Particles& end_spheres, double kinetic_J) {
  return sqlite::write_transaction(db(), [&] {
    const ResponseMetrics& m = r.metrics;
    sqlite::Statement metrics(
        db(),
        "INSERT INTO study_frf_metrics (study_id, point, run_id, settled, cycles_to_steady, cycles_run, "
        "measured_cycles, amplitude_m, amplitude_spread_m, phase_rad, normalised_amplitude, gamma, "
        "impact_J_per_cycle, friction_J_per_cycle, viscous_J_per_cycle, loss_factor, apparent_mass_kg, "
        "equivalent_damping_N_s_m, particle_mass_kg, wall_time_s) "
        "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    metrics.bind(1, study_id).bind(2, point).bind(3, r.run_id).bind(4, static_cast<std::int64_t>(m.settled));
    metrics.bind(5, m.cycles_to_steady).bind(6, r.cycles_run).bind(7, m.measured_cycles);
    const std::optional<double> values[] = {m.amplitude_m,
                                            m.amplitude_spread_m,
                                            m.phase_rad,
                                            m.normalised_amplitude,
                                            m.gamma,
                                            m.impact_J_per_cycle,
                                            m.friction_J_per_cycle,
                                            m.viscous_J_per_cycle,
                                            m.loss_factor,
                                            m.apparent_mass_kg,
                                            m.equivalent_damping_N_s_m,
                                            r.particle_mass_kg,
                                            r.wall_time_s};
    for (int k = 0; k < 13; ++k) metrics.bind(8 + k, values[k]);
    metrics.run();
    return store_end_and_complete(study_id, point, attempt,
                                  "frequency-response point end: run " + std::to_string(r.run_id), r.end, end_spheres,
                                  kinetic_J, r.wall_time_s);
  });
}

std::int64_t StudyStore::complete_characterise_point(std::int64_t study_id, int point, int attempt,
                                                     const CharacterisePointResult& r, const Particles& end_spheres,
                                                     double kinetic_J) {
  return sqlite::write_transaction(db(), [&] {
    const CharacterisationMetrics& m = r.metrics;
    sqlite::Statement metrics(
        db(),
        "INSERT INTO study_characterise_metrics (study_id, point, run_id, settled, cycles_to_steady, cycles_run, "
        "measured_cycles, amplitude_m, gamma, apparent_mass_kg, apparent_mass_spread_kg, equivalent_damping_N_s_m, "
        "equivalent_damping_spread_N_s_m, impact_J_per_cycle, friction_J_per_cycle, loss_factor, "
        "floor_contact_fraction, lid_contact_fraction, particle_mass_kg, gravity_m_s2, free_height_m, wall_time_s) "
        "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    metrics.bind(1, study_id).bind(2, point).bind(3, r.run_id).bind(4, static_cast<std::int64_t>(m.settled));
    metrics.bind(5, m.cycles_to_steady).bind(6, r.cycles_run).bind(7, m.measured_cycles);
    const std::optional<double> values[] = {m.amplitude_m,
                                            m.gamma,
                                            m.apparent_mass_kg,
                                            m.apparent_mass_spread_kg,
                                            m.equivalent_damping_N_s_m,
                                            m.equivalent_damping_spread_N_s_m,
                                            m.impact_J_per_cycle,
                                            m.friction_J_per_cycle,
                                            m.loss_factor,
                                            m.floor_contact_fraction,
                                            m.lid_contact_fraction,
                                            r.particle_mass_kg,
                                            r.gravity_m_s2,
                                            r.free_height_m,
                                            r.wall_time_s};
    for (int k = 0; k < 15; ++k) metrics.bind(8 + k, values[k]);
    metrics.run();
    return store_end_and_complete(study_id, point, attempt,
                                  "characterisation point end: run " + std::to_string(r.run_id), r.end, end_spheres,
                                  kinetic_J, r.wall_time_s);
  });
}

std::map<int, int> StudyStore::previous_points(std::int64_t study_id) {
  sqlite::Statement q(db(),
                      "SELECT point, previous_point FROM study_frf_points WHERE study_id = ?1 AND previous_point "
                      "IS NOT NULL UNION ALL SELECT point, previous_point FROM study_characterise_points "
                      "WHERE study_id = ?1 AND previous_point IS NOT NULL");
  q.bind(1, study_id);
  std::map<int, int> previous;
  while (q.step()) previous[static_cast<int>(q.column_int(0))] = static_cast<int>(q.column_int(1));
  return previous;
}

std::vector<int> StudyStore::curve_from(std::int64_t study_id, int first) {
  std::map<int, int> next;
  for (const auto& [point, previous] : previous_points(study_id)) next[previous] = point;
  std::vector<int> points{first};
  for (auto it = next.find(first); it != next.end(); it = next.find(it->second)) points.push_back(it->second);
  return points;
}

std::optional<FrfEndState> StudyStore::end_state(std::int64_t study_id, int point) {
  sqlite::Statement q(db(),
                      "SELECT s.run_id, s.state_id, s.t_s, s.host_z_m, s.host_v_m_s FROM study_point_states s "
                      "JOIN study_points p ON p.study_id = s.study_id AND p.point = s.point "
                      "WHERE s.study_id = ? AND s.point = ? AND p.status = 'completed'");
  q.bind(1, study_id).bind(2, point);
  if (!q.step()) return std::nullopt;
  return FrfEndState{q.column_int(0), q.column_int(1), q.column_double(2), {q.column_double(3), q.column_double(4)}};
}

namespace {

/// A frequency-response point's stored metrics (study_frf_metrics' columns, also the
/// study_frf view's), selected in this order from column `first` of `q` on.
constexpr std::string_view frf_metric_columns =
    "run_id, settled, cycles_to_steady, cycles_run, measured_cycles, amplitude_m, amplitude_spread_m, phase_rad, "
    "normalised_amplitude, impact_J_per_cycle, friction_J_per_cycle, viscous_J_per_cycle, loss_factor, "
    "apparent_mass_kg, equivalent_damping_N_s_m, particle_mass_kg, wall_time_s, gamma";

FrfPointResult read_frf_metrics(const sqlite::Statement& q, int first) {
  FrfPointResult m;
  m.run_id = q.column_int(first);
  m.metrics.settled = q.column_int(first + 1) != 0;
  m.metrics.cycles_to_steady = static_cast<int>(q.column_int(first + 2));
  m.cycles_run = static_cast<int>(q.column_int(first + 3));
  m.metrics.measured_cycles = static_cast<int>(q.column_int(first + 4));
  double* values[] = {&m.metrics.amplitude_m,
                      &m.metrics.amplitude_spread_m,
                      &m.metrics.phase_rad,
                      &m.metrics.normalised_amplitude,
                      &m.metrics.impact_J_per_cycle,
                      &m.metrics.friction_J_per_cycle,
                      &m.metrics.viscous_J_per_cycle,
                      &m.metrics.loss_factor,
                      &m.metrics.apparent_mass_kg,
                      &m.metrics.equivalent_damping_N_s_m,
                      &m.particle_mass_kg,
                      &m.wall_time_s};
  for (int k = 0; k < 12; ++k) *values[k] = q.column_double(first + 5 + k);
  m.metrics.gamma = q.column_optional_double(first + 17);  // NULL without gravity
  return m;
}

}  // namespace

std::vector<FrfPointRecord> StudyStore::frf_points(std::int64_t study_id) {
  sqlite::Statement q(db(),
                      "SELECT point, status, curve, model, direction, host_alone, mode, level, frequency_hz, step, "
                      "coalesce(previous_point, 0), grid, " +
                          std::string(frf_metric_columns) + " FROM study_frf WHERE study_id = ? ORDER BY point");
  q.bind(1, study_id);
  std::vector<FrfPointRecord> rows;
  while (q.step()) {
    FrfPointRecord r;
    r.point = static_cast<int>(q.column_int(0));
    r.status = q.column_text(1);
    r.place = {static_cast<int>(q.column_int(2)),
               q.column_text(3),
               q.column_text(4),
               q.column_int(5) != 0,
               q.column_text(6),
               q.column_double(7),
               q.column_double(8),
               static_cast<int>(q.column_int(9)),
               static_cast<int>(q.column_int(10)),
               q.column_text(11)};
    if (!q.is_null(12)) r.result = read_frf_metrics(q, 12);
    rows.push_back(std::move(r));
  }
  return rows;
}

std::optional<FrfPointResult> StudyStore::frf_metrics(std::int64_t study_id, int point) {
  sqlite::Statement q(
      db(), "SELECT " + std::string(frf_metric_columns) + " FROM study_frf_metrics WHERE study_id = ? AND point = ?");
  q.bind(1, study_id).bind(2, point);
  if (!q.step()) return std::nullopt;
  return read_frf_metrics(q, 0);
}

std::vector<CharacterisePointRecord> StudyStore::characterise_points(std::int64_t study_id) {
  sqlite::Statement q(db(),
                      "SELECT point, status, curve, model, empty, amplitude_m, gamma_given, frequency_hz, step, "
                      "coalesce(previous_point, 0), run_id, settled, cycles_to_steady, cycles_run, measured_cycles, "
                      "apparent_mass_kg, apparent_mass_spread_kg, equivalent_damping_N_s_m, "
                      "equivalent_damping_spread_N_s_m, impact_J_per_cycle, friction_J_per_cycle, loss_factor, "
                      "floor_contact_fraction, lid_contact_fraction, particle_mass_kg, gravity_m_s2, free_height_m, "
                      "wall_time_s, measured_amplitude_m, gamma FROM study_characterisation WHERE study_id = ? "
                      "ORDER BY point");
  q.bind(1, study_id);
  std::vector<CharacterisePointRecord> rows;
  while (q.step()) {
    CharacterisePointRecord r;
    r.point = static_cast<int>(q.column_int(0));
    r.status = q.column_text(1);
    r.place = {static_cast<int>(q.column_int(2)),
               q.column_text(3),
               q.column_int(4) != 0,
               q.column_double(5),
               q.column_optional_double(6),
               q.column_double(7),
               static_cast<int>(q.column_int(8)),
               static_cast<int>(q.column_int(9))};
    if (!q.is_null(10)) {
      CharacterisePointResult m;
      m.run_id = q.column_int(10);
      m.metrics.settled = q.column_int(11) != 0;
      m.metrics.cycles_to_steady = static_cast<int>(q.column_int(12));
      m.cycles_run = static_cast<int>(q.column_int(13));
      m.metrics.measured_cycles = static_cast<int>(q.column_int(14));
      double* values[] = {&m.metrics.apparent_mass_kg,
                          &m.metrics.apparent_mass_spread_kg,
                          &m.metrics.equivalent_damping_N_s_m,
                          &m.metrics.equivalent_damping_spread_N_s_m,
                          &m.metrics.impact_J_per_cycle,
                          &m.metrics.friction_J_per_cycle,
                          &m.metrics.loss_factor,
                          &m.metrics.floor_contact_fraction,
                          &m.metrics.lid_contact_fraction,
                          &m.particle_mass_kg,
                          &m.gravity_m_s2,
                          &m.free_height_m,
                          &m.wall_time_s,
                          &m.metrics.amplitude_m};
      for (int k = 0; k < 14; ++k) *values[k] = q.column_double(15 + k);
      m.metrics.gamma = q.column_optional_double(29);  // NULL without gravity
      r.result = m;
    }
    rows.push_back(std::move(r));
  }
  return rows;
}

void StudyStore::end_point(std::int64_t study_id, int point, int attempt, PointStatus status,
                           const std::string& message) {
  sqlite::write_transaction(db(), [&] {
    sqlite::Statement end(db(), with_now("UPDATE study_points SET status = ?, message = ?, lease_host = NULL, "
                                         "lease_pid = NULL, lease_start = NULL, ended_at = ",
                                         " WHERE study_id = ? AND point = ? AND attempt = ? AND status = 'running'"));
    end.bind(1, to_string(status)).bind(2, message).bind(3, study_id).bind(4, point).bind(5, attempt).run();
  });
}

bool StudyStore::abandon_point(std::int64_t study_id, int point, const ProcessLease& lease, PointStatus status,
                               const std::string& message) {
  return sqlite::write_transaction(db(), [&] {
    sqlite::Statement end(db(),
                          with_now("UPDATE study_points SET status = ?1, message = ?2, "
                                   "lease_host = NULL, lease_pid = NULL, lease_start = NULL, ended_at = ",
                                   " WHERE study_id = ?3 AND point = ?4 AND status = 'running' "
                                   "AND lease_host = ?5 AND lease_pid = ?6 AND lease_start = ?7 RETURNING attempt"));
    end.bind(1, to_string(status)).bind(2, message).bind(3, study_id).bind(4, point).bind(5, lease.host);
    end.bind(6, lease.pid).bind(7, lease.start_ticks);
    if (!end.step()) return false;
    const std::int64_t attempt = end.column_int(0);
    end.reset();
    sqlite::Statement runs(db(), with_now("UPDATE runs SET status = ?1, message = ?2, ended_at = ",
                                          " WHERE status = 'running' AND run_id IN (SELECT run_id FROM "
                                          "study_point_runs WHERE study_id = ?3 AND point = ?4 AND attempt = ?5)"));
    runs.bind(1, to_string(status)).bind(2, message).bind(3, study_id).bind(4, point).bind(5, attempt).run();
    return true;
  });
}

void StudyStore::record_job(std::int64_t study_id, const StudyJob& job,
                            const std::vector<std::pair<std::int64_t, int>>& tasks) {
  sqlite::write_transaction(db(), [&] {
    sqlite::Statement row(db(), with_now("INSERT INTO study_jobs (study_id, job_id, script_file, shard_folder, "
                                         "submitted_at) VALUES (?, ?, ?, ?, ",
                                         ")"));
    row.bind(1, study_id).bind(2, job.job_id).bind(3, job.script_file).bind(4, job.shard_folder).run();
    sqlite::Statement task(db(), "INSERT INTO study_tasks (study_id, job_id, task, point) VALUES (?, ?, ?, ?)");
    for (const auto& [index, point] : tasks)
      task.bind(1, study_id).bind(2, job.job_id).bind(3, index).bind(4, point).run();
  });
}

std::vector<StudyJob> StudyStore::jobs(std::int64_t study_id) {
  sqlite::Statement q(db(),
                      "SELECT job_id, submitted_at, script_file, shard_folder FROM study_jobs WHERE study_id = ? "
                      "ORDER BY job_id");
  q.bind(1, study_id);
  std::vector<StudyJob> jobs;
  while (q.step()) jobs.push_back({q.column_int(0), q.column_text(1), q.column_text(2), q.column_text(3)});
  return jobs;
}

std::vector<StudyTask> StudyStore::tasks(std::int64_t study_id) {
  sqlite::Statement q(db(),
                      "SELECT job_id, task, point, coalesce(host, ''), coalesce(started_at, ''), "
                      "coalesce(ended_at, ''), message, coalesce(shard_file, ''), coalesce(collected_at, ''), outcome "
                      "FROM study_tasks WHERE study_id = ? ORDER BY job_id, task");
  q.bind(1, study_id);
  std::vector<StudyTask> tasks;
  while (q.step()) {
    StudyTask t{q.column_int(0),  q.column_int(1),  static_cast<int>(q.column_int(2)),
                q.column_text(3), q.column_text(4), q.column_text(5),
                q.column_text(6), q.column_text(7), q.column_text(8),
                std::nullopt};
    if (!q.is_null(9)) t.outcome = parse_point_status(q.column_text(9));
    tasks.push_back(std::move(t));
  }
  return tasks;
}

void StudyStore::begin_task(std::int64_t study_id, const StudyTask& task) {
  sqlite::write_transaction(db(), [&] {
    sqlite::Statement row(db(), with_now("INSERT INTO study_tasks (study_id, job_id, task, point, host, started_at) "
                                         "VALUES (?, ?, ?, ?, ?, ",
                                         ")"));
    row.bind(1, study_id).bind(2, task.job_id).bind(3, task.task).bind(4, task.point).bind(5, task.host).run();
  });
}

void StudyStore::end_task(std::int64_t study_id, std::int64_t job_id, std::int64_t task, PointStatus outcome,
                          const std::string& message) {
  sqlite::write_transaction(db(), [&] {
    sqlite::Statement row(db(), with_now("UPDATE study_tasks SET outcome = ?, message = ?, ended_at = ",
                                         " WHERE study_id = ? AND job_id = ? AND task = ?"));
    row.bind(1, to_string(outcome)).bind(2, message).bind(3, study_id).bind(4, job_id).bind(5, task).run();
  });
}

}  // namespace pdamp
