#include "pdamp/store/run_store.hpp"

#include <ctime>

#include "pdamp/errors.hpp"
#include "pdamp/version.hpp"
#include "schema.hpp"

namespace pdamp {
namespace {

std::string utc_now_iso8601() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto millis = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[40];
  const std::size_t n = std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc);
  return std::string(text, n) + "." + std::to_string(1000 + millis).substr(1) + "Z";
}

int user_version(sqlite::Database& db) {
  sqlite::Statement query(db, "PRAGMA user_version");
  query.step();
  return static_cast<int>(query.column_int(0));
}

constexpr std::string_view summary_columns =
    "SELECT run_id, model, scenario_name, status, n_particles, duration_s, sim_time_s, wall_time_s, "
    "energy_balance_rel_err, n_samples, n_cycles, dissipated_impact_J, dissipated_friction_J, "
    "dissipated_viscous_J, started_at, message FROM run_summary";

RunSummary read_summary(const sqlite::Statement& row) {
  RunSummary s;
  s.run_id = row.column_int(0);
  s.model = row.column_text(1);
  s.scenario_name = row.column_text(2);
  s.status = row.column_text(3);
  s.n_particles = static_cast<int>(row.column_int(4));
  s.duration_s = row.column_double(5);
  s.sim_time_s = row.column_double(6);
  s.wall_time_s = row.column_optional_double(7);
  s.energy_balance_rel_err = row.column_optional_double(8);
  s.n_samples = row.column_int(9);
  s.n_cycles = row.column_int(10);
  s.dissipated_impact_J = row.column_optional_double(11);
  s.dissipated_friction_J = row.column_optional_double(12);
  s.dissipated_viscous_J = row.column_optional_double(13);
  s.started_at = row.column_text(14);
  s.message = row.column_text(15);
  return s;
}

}  // namespace

std::string_view to_string(RunStatus status) {
  switch (status) {
    case RunStatus::running:
      return "running";
    case RunStatus::completed:
      return "completed";
    case RunStatus::failed:
      return "failed";
    case RunStatus::interrupted:
      break;
  }
  return "interrupted";
}

RunStore::RunStore(const std::filesystem::path& file) : db_(file) {
  try {
    db_.exec("PRAGMA journal_mode = WAL");
  } catch (const RuntimeFailure& e) {
    throw InputError("'" + file.string() + "' is not a pdamp run store (" + e.what() + ")");
  }
  db_.exec("PRAGMA synchronous = NORMAL");  // WAL + NORMAL: a killed process loses nothing committed
  migrate();
}

int RunStore::schema_version() { return static_cast<int>(schema::migrations().size()); }

void RunStore::migrate() {
  const int latest = schema_version();
  if (user_version(db_) == latest) return;
  sqlite::Transaction transaction(db_);
  const int version = user_version(db_);  // re-read under the write lock: another process may have migrated
  if (version > latest) {
    throw InputError("database '" + db_.file().string() + "' has schema version " + std::to_string(version) +
                     ", newer than this pdamp's " + std::to_string(latest) + "; use a newer pdamp or another --db");
  }
  if (version == 0) {
    sqlite::Statement tables(db_, "SELECT count(*) FROM sqlite_schema");
    tables.step();
    if (tables.column_int(0) > 0) {
      throw InputError("database '" + db_.file().string() +
                       "' already holds tables that pdamp did not create; give another --db");
    }
  }
  for (int v = version; v < latest; ++v) db_.exec(schema::migrations()[static_cast<std::size_t>(v)]);
  db_.exec("PRAGMA user_version = " + std::to_string(latest));
  transaction.commit();
}

std::int64_t RunStore::begin_run(const NewRun& run) {
  sqlite::Statement insert(db_,
                           "INSERT INTO runs (model, scenario_name, scenario_text, seed, n_particles, duration_s, "
                           "dt_s, pdamp_version, status, started_at, initial_state_id, solid_fraction) "
                           "VALUES (?, ?, ?, ?, ?, ?, ?, ?, 'running', ?, ?, ?)");
  insert.bind(1, run.model)
      .bind(2, run.scenario_name)
      .bind(3, run.scenario_text)
      .bind(4, static_cast<std::int64_t>(run.seed))
      .bind(5, run.n_particles)
      .bind(6, run.duration_s)
      .bind(7, run.dt_s)
      .bind(8, std::string_view(version_string))
      .bind(9, utc_now_iso8601());
  if (run.initial_state_id) insert.bind(10, *run.initial_state_id);
  insert.bind(11, run.solid_fraction);
  insert.run();
  return db_.last_insert_rowid();
}

std::optional<StoredInitialState> RunStore::find_initial_state(const std::string& settle_key) {
  sqlite::Statement query(db_, "SELECT state_id, settle_time_s FROM initial_states WHERE settle_key = ?");
  query.bind(1, settle_key);
  if (!query.step()) return std::nullopt;
  const std::int64_t id = query.column_int(0);
  return StoredInitialState{id, load_initial_particles(id), query.column_double(1)};
}

std::int64_t RunStore::save_initial_state(const std::string& settle_key, const Particles& p, double settle_time_s,
                                          double kinetic_J, double wall_time_s) {
  sqlite::Transaction transaction(db_);
  // Another process may have settled the same bed meanwhile: the first one stays.
  sqlite::Statement existing(db_, "SELECT state_id FROM initial_states WHERE settle_key = ?");
  existing.bind(1, settle_key);
  if (existing.step()) return existing.column_int(0);
  sqlite::Statement state(db_,
                          "INSERT INTO initial_states (settle_key, n_particles, settle_time_s, kinetic_J, wall_time_s, "
                          "created_at) VALUES (?, ?, ?, ?, ?, ?)");
  state.bind(1, settle_key)
      .bind(2, static_cast<std::int64_t>(p.size()))
      .bind(3, settle_time_s)
      .bind(4, kinetic_J)
      .bind(5, wall_time_s)
      .bind(6, utc_now_iso8601());
  state.run();
  const std::int64_t id = db_.last_insert_rowid();
  sqlite::Statement particle(db_, "INSERT INTO initial_particles VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    particle.bind(1, id).bind(2, static_cast<std::int64_t>(i));
    for (int c = 0; c < 3; ++c) {
      particle.bind(3 + c, p.position_m(c, i))
          .bind(6 + c, p.velocity_m_s(c, i))
          .bind(9 + c, p.angular_velocity_rad_s(c, i));
    }
    particle.bind(12, p.radius_m[i]).bind(13, p.mass_kg[i]);
    particle.run();
  }
  transaction.commit();
  return id;
}

Particles RunStore::load_initial_particles(std::int64_t state_id) {
  sqlite::Statement count(db_, "SELECT n_particles FROM initial_states WHERE state_id = ?");
  count.bind(1, state_id);
  if (!count.step()) throw InputError("initial state " + std::to_string(state_id) + " is not in the store");
  Particles p(count.column_int(0));
  sqlite::Statement rows(db_, "SELECT * FROM initial_particles WHERE state_id = ? ORDER BY particle");
  rows.bind(1, state_id);
  Eigen::Index i = 0;
  for (; rows.step() && i < p.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      p.position_m(c, i) = rows.column_double(2 + c);
      p.velocity_m_s(c, i) = rows.column_double(5 + c);
      p.angular_velocity_rad_s(c, i) = rows.column_double(8 + c);
    }
    p.radius_m[i] = rows.column_double(11);
    p.mass_kg[i] = rows.column_double(12);
  }
  if (i != p.size()) throw RuntimeFailure("initial state " + std::to_string(state_id) + " is incomplete in the store");
  return p;
}

void RunStore::finish_run(std::int64_t run_id, const RunEnd& end) {
  sqlite::Statement update(db_,
                           "UPDATE runs SET status = ?, message = ?, sim_time_s = ?, wall_time_s = ?, "
                           "initial_energy_J = ?, energy_balance_rel_err = ?, ended_at = ? WHERE run_id = ?");
  update.bind(1, to_string(end.status))
      .bind(2, end.message)
      .bind(3, end.sim_time_s)
      .bind(4, end.wall_time_s)
      .bind(5, end.initial_energy_J)
      .bind(6, end.energy_balance_rel_err)
      .bind(7, utc_now_iso8601())
      .bind(8, run_id);
  update.run();
}

void RunStore::save_statistics(std::int64_t run_id, const EngineStatistics& statistics) {
  sqlite::Transaction transaction(db_);
  sqlite::Statement upsert(db_, "INSERT OR REPLACE INTO run_statistics (run_id, name, value) VALUES (?, ?, ?)");
  for (const auto& [name, value] : statistics) upsert.bind(1, run_id).bind(2, name).bind(3, value).run();
  transaction.commit();
}

void RunStore::save_calibration(std::int64_t run_id, const RestitutionTable& table) {
  sqlite::Transaction transaction(db_);
  sqlite::Statement insert(
      db_, "INSERT INTO calibrations (run_id, contact, impact_speed_m_s, en, beta0) VALUES (?, ?, ?, ?, ?)");
  for (const auto& [contact, curve] :
       {std::pair{"sphere_sphere", &table.sphere_sphere}, std::pair{"sphere_wall", &table.sphere_wall}}) {
    for (std::size_t k = 0; k < curve->impact_speed_m_s.size(); ++k) {
      insert.bind(1, run_id)
          .bind(2, std::string_view(contact))
          .bind(3, curve->impact_speed_m_s[k])
          .bind(4, curve->en[k])
          .bind(5, curve->beta0[k])
          .run();
    }
  }
  transaction.commit();
}

EngineStatistics RunStore::statistics(std::int64_t run_id) {
  sqlite::Statement query(db_, "SELECT name, value FROM run_statistics WHERE run_id = ? ORDER BY name");
  query.bind(1, run_id);
  EngineStatistics result;
  while (query.step()) result.emplace_back(query.column_text(0), query.column_int(1));
  return result;
}

std::int64_t RunStore::save_comparison(const ComparisonRecord& c) {
  sqlite::Transaction transaction(db_);
  sqlite::Statement row(db_,
                        "INSERT INTO comparisons (scenario_name, soft_run_id, hard_run_id, initial_state_id, "
                        "hard_restitution, created_at, envelope_max_rel_diff, envelope_rms_rel_diff, "
                        "small_amplitude_freq_soft_hz, small_amplitude_freq_hard_hz, gamma_below_1_soft_s, "
                        "gamma_below_1_hard_s, psi_mean_abs_diff, dissipated_soft_J, dissipated_hard_J, "
                        "dissipated_rel_diff, wall_time_soft_s, wall_time_hard_s, wall_time_ratio, soft_steps, "
                        "hard_events) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  row.bind(1, c.scenario_name).bind(2, c.soft_run_id).bind(3, c.hard_run_id);
  if (c.initial_state_id) row.bind(4, *c.initial_state_id);
  row.bind(5, c.hard_restitution)
      .bind(6, utc_now_iso8601())
      .bind(7, c.envelope_max_rel_diff)
      .bind(8, c.envelope_rms_rel_diff)
      .bind(9, c.small_amplitude_freq_soft_hz)
      .bind(10, c.small_amplitude_freq_hard_hz)
      .bind(11, c.gamma_below_1_soft_s)
      .bind(12, c.gamma_below_1_hard_s)
      .bind(13, c.psi_mean_abs_diff)
      .bind(14, c.dissipated_soft_J)
      .bind(15, c.dissipated_hard_J)
      .bind(16, c.dissipated_rel_diff)
      .bind(17, c.wall_time_soft_s)
      .bind(18, c.wall_time_hard_s)
      .bind(19, c.wall_time_ratio)
      .bind(20, c.soft_steps)
      .bind(21, c.hard_events);
  row.run();
  const std::int64_t id = db_.last_insert_rowid();
  sqlite::Statement bin(db_,
                        "INSERT INTO comparison_psi_bins (comparison_id, gamma_low, gamma_high, psi_soft, psi_hard, "
                        "cycles_soft, cycles_hard) VALUES (?, ?, ?, ?, ?, ?, ?)");
  for (const auto& b : c.psi_bins) {
    bin.bind(1, id).bind(2, b.gamma_low).bind(3, b.gamma_high).bind(4, b.psi_soft).bind(5, b.psi_hard);
    bin.bind(6, b.cycles_soft).bind(7, b.cycles_hard).run();
  }
  sqlite::Statement energy(db_,
                           "INSERT INTO comparison_energy (comparison_id, t_s, model, impact_J, friction_J, viscous_J) "
                           "VALUES (?, ?, ?, ?, ?, ?)");
  for (const auto& e : c.energy) {
    energy.bind(1, id).bind(2, e.t_s).bind(3, e.model).bind(4, e.impact_J).bind(5, e.friction_J).bind(6, e.viscous_J);
    energy.run();
  }
  transaction.commit();
  return id;
}

std::vector<RunSummary> RunStore::list_runs() {
  sqlite::Statement query(db_, std::string(summary_columns) + " ORDER BY run_id");
  std::vector<RunSummary> runs;
  while (query.step()) runs.push_back(read_summary(query));
  return runs;
}

std::optional<RunSummary> RunStore::summary(std::int64_t run_id) {
  sqlite::Statement query(db_, std::string(summary_columns) + " WHERE run_id = ?");
  query.bind(1, run_id);
  if (!query.step()) return std::nullopt;
  return read_summary(query);
}

RunWriter::RunWriter(RunStore& store, std::int64_t run_id, std::chrono::milliseconds commit_interval)
    : store_(&store),
      run_id_(run_id),
      commit_interval_(commit_interval),
      insert_sample_(store.database(),
                     "INSERT INTO samples (run_id, t_s, host_z_m, host_v_m_s, particle_translational_J, "
                     "particle_rotational_J, host_kinetic_J, spring_potential_J, gravitational_potential_J, "
                     "contact_elastic_J, excitation_work_J, dissipated_impact_J, dissipated_friction_J, "
                     "dissipated_viscous_J, energy_balance_rel_err, contacts, events, steps) "
                     "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)"),
      insert_cycle_(store.database(),
                    "INSERT INTO cycles (run_id, cycle, t_start_s, t_end_s, amplitude_m, freq_hz, gamma, psi, "
                    "psi_impact, psi_friction, psi_viscous, max_host_kinetic_J) "
                    "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)") {}

RunWriter::~RunWriter() {
  try {
    flush();
  } catch (...) {
    // Destructors must not throw; an explicit flush() reports the error.
  }
}

void RunWriter::begin_batch() {
  if (in_batch_) return;
  store_->database().exec("BEGIN IMMEDIATE");
  in_batch_ = true;
  batch_started_ = std::chrono::steady_clock::now();
}

void RunWriter::commit_if_due() {
  if (std::chrono::steady_clock::now() - batch_started_ >= commit_interval_) flush();
}

void RunWriter::record_sample(const Observation& o, double energy_balance_rel_err) {
  begin_batch();
  const EnergyLedger& e = o.energy;
  insert_sample_.bind(1, run_id_)
      .bind(2, o.t_s)
      .bind(3, o.host.z_m)
      .bind(4, o.host.v_m_s)
      .bind(5, e.particle_translational_J)
      .bind(6, e.particle_rotational_J)
      .bind(7, e.host_kinetic_J)
      .bind(8, e.spring_potential_J)
      .bind(9, e.gravitational_potential_J)
      .bind(10, e.contact_elastic_J)
      .bind(11, e.excitation_work_J)
      .bind(12, e.dissipated_impact_J)
      .bind(13, e.dissipated_friction_J)
      .bind(14, e.dissipated_viscous_J)
      .bind(15, energy_balance_rel_err)
      .bind(16, o.counters.contacts)
      .bind(17, o.counters.events)
      .bind(18, o.counters.steps);
  insert_sample_.run();
  commit_if_due();
}

void RunWriter::record_cycle(const CycleRecord& c) {
  begin_batch();
  insert_cycle_.bind(1, run_id_)
      .bind(2, c.cycle)
      .bind(3, c.t_start_s)
      .bind(4, c.t_end_s)
      .bind(5, c.amplitude_m)
      .bind(6, c.freq_hz)
      .bind(7, c.gamma)
      .bind(8, c.psi)
      .bind(9, c.psi_impact)
      .bind(10, c.psi_friction)
      .bind(11, c.psi_viscous)
      .bind(12, c.max_host_kinetic_J);
  insert_cycle_.run();
  commit_if_due();
}

void RunWriter::flush() {
  if (!in_batch_) return;
  in_batch_ = false;
  store_->database().exec("COMMIT");
}

}  // namespace pdamp
