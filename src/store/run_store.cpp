#include "pdamp/store/run_store.hpp"

#include <ctime>
#include <set>

#include "pdamp/errors.hpp"
#include "pdamp/version.hpp"
#include "schema.hpp"
#include "store_file.hpp"

namespace pdamp {
namespace {

using Kind = store_file::Examined::Kind;

/// Rows a RunWriter keeps before writing them, however soon: bounds its memory (~200 B a
/// sample) and the length of its transactions.
constexpr std::size_t max_buffered_rows = 16384;

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

/// Foreign keys off for the lifetime of this guard (outside any transaction: the setting
/// cannot change inside one).
class ForeignKeysOff {
 public:
  explicit ForeignKeysOff(sqlite::Database& db) : db_(db) { db_.exec("PRAGMA foreign_keys = OFF"); }
  ~ForeignKeysOff() {
    try {
      db_.exec("PRAGMA foreign_keys = ON");
    } catch (...) {
      // Only fails if the connection is broken, which its next use reports.
    }
  }
  ForeignKeysOff(const ForeignKeysOff&) = delete;
  ForeignKeysOff& operator=(const ForeignKeysOff&) = delete;

 private:
  sqlite::Database& db_;
};

constexpr std::string_view summary_columns =
    "SELECT v.run_id, v.model, v.scenario_name, v.status, v.n_particles, v.duration_s, v.sim_time_s, v.wall_time_s, "
    "v.energy_balance_rel_err, v.n_samples, v.n_cycles, v.dissipated_impact_J, v.dissipated_friction_J, "
    "v.dissipated_viscous_J, v.started_at, v.message, r.lease_host, r.lease_pid, r.lease_start "
    "FROM run_summary v JOIN runs r ON r.run_id = v.run_id";

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
  if (s.status == "running" && !row.is_null(16)) {
    s.lease = ProcessLease{row.column_text(16), row.column_int(17), row.column_int(18)};
    if (!lease_is_alive(*s.lease)) s.status = "dead";
  }
  return s;
}

// A sample's and a cycle's columns after run_id, in the order insert_ and read_ bind them.
constexpr std::string_view sample_columns =
    "t_s, host_z_m, host_v_m_s, particle_translational_J, particle_rotational_J, host_kinetic_J, "
    "spring_potential_J, gravitational_potential_J, contact_elastic_J, excitation_work_J, dissipated_impact_J, "
    "dissipated_friction_J, dissipated_viscous_J, energy_balance_rel_err, time_steps, collisions, contacts, "
    "riding_spheres";
constexpr std::string_view cycle_columns =
    "cycle, t_start_s, t_end_s, amplitude_m, freq_hz, gamma, psi, psi_impact, psi_friction, psi_viscous, "
    "max_host_kinetic_J";

void insert_sample(sqlite::Statement& insert, std::int64_t run_id, const SampleRecord& sample) {
  const Observation& o = sample.observation;
  const EnergyLedger& e = o.energy;
  insert.bind(1, run_id)
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
      .bind(15, sample.energy_balance_rel_err)
      .bind(16, o.counters.time_steps)
      .bind(17, o.counters.collisions)
      .bind(18, o.counters.contacts)
      .bind(19, o.counters.riding_spheres);
  insert.run();
}

void insert_cycle(sqlite::Statement& insert, std::int64_t run_id, const CycleRecord& c) {
  insert.bind(1, run_id)
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
  insert.run();
}

SampleRecord read_sample(const sqlite::Statement& row) {
  SampleRecord sample;
  Observation& o = sample.observation;
  EnergyLedger& e = o.energy;
  o.t_s = row.column_double(0);
  o.host = {row.column_double(1), row.column_double(2)};
  e.particle_translational_J = row.column_double(3);
  e.particle_rotational_J = row.column_double(4);
  e.host_kinetic_J = row.column_double(5);
  e.spring_potential_J = row.column_double(6);
  e.gravitational_potential_J = row.column_double(7);
  e.contact_elastic_J = row.column_double(8);
  e.excitation_work_J = row.column_double(9);
  e.dissipated_impact_J = row.column_double(10);
  e.dissipated_friction_J = row.column_double(11);
  e.dissipated_viscous_J = row.column_double(12);
  sample.energy_balance_rel_err = row.column_double(13);
  o.counters.time_steps = row.column_optional_int(14);
  o.counters.collisions = row.column_optional_int(15);
  o.counters.contacts = row.column_optional_int(16);
  o.counters.riding_spheres = row.column_optional_int(17);
  return sample;
}

CycleRecord read_cycle(const sqlite::Statement& row) {
  return CycleRecord{static_cast<int>(row.column_int(0)),
                     row.column_double(1),
                     row.column_double(2),
                     row.column_double(3),
                     row.column_double(4),
                     row.column_optional_double(5),
                     row.column_double(6),
                     row.column_double(7),
                     row.column_double(8),
                     row.column_double(9),
                     row.column_double(10)};
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

RunStore::RunStore(const std::filesystem::path& file, StoreAccess access, const StoreOptions& options) {
  const int latest = schema_version();
  store_file::Examined examined = store_file::examine(file, options, latest);
  if (access != StoreAccess::write && examined.kind == Kind::missing) {
    throw InputError("database '" + file.string() + "' does not exist (give the file a run was stored in with --db)");
  }
  if (access != StoreAccess::write && examined.kind == Kind::empty) {
    throw InputError("database '" + file.string() + "' is empty: no run was ever stored in it");
  }
  if (access == StoreAccess::read && examined.version == latest) {
    db_ = std::move(examined.reader);
    return;
  }
  examined.reader.reset();
  try {
    db_ = std::make_unique<sqlite::Database>(file, sqlite::Access::read_write, options.busy_limit);
    if (db_->read_only()) {
      throw sqlite::NotWritable("the store '" + file.string() +
                                "' can only be read: its file is not writable by this user; give a writable --db");
    }
    if (options.single_process) db_->exec("PRAGMA locking_mode = EXCLUSIVE");
    sqlite::retry_while_busy(*db_, [this] { db_->exec("PRAGMA journal_mode = WAL"); });
    db_->exec("PRAGMA synchronous = NORMAL");  // WAL + NORMAL: a killed process loses nothing committed
    migrate();
    store_file::check_schema(*db_);  // also one another process created or migrated since examined
  } catch (const sqlite::NotWritable& e) {
    if (examined.kind == Kind::store && examined.version < latest) {
      throw InputError("database '" + file.string() + "' has schema version " + std::to_string(examined.version) +
                       ", older than this pdamp's " + std::to_string(latest) +
                       ", and cannot be migrated without writing to it: " + e.what());
    }
    throw InputError(e.what());
  }
}

int RunStore::schema_version() { return static_cast<int>(schema::migrations().size()); }

void RunStore::migrate() {
  const int latest = schema_version();
  if (user_version(*db_) == latest) return;
  // A migration that rebuilds a table must not cascade deletes into the rows referring to it.
  const ForeignKeysOff foreign_keys_off(*db_);
  sqlite::write_transaction(*db_, [&] {
    const int version = user_version(*db_);  // re-read under the write lock: another process may have migrated
    if (version > latest) store_file::refuse_newer(db_->file(), version, latest);
    if (version == 0) {
      sqlite::Statement tables(*db_, "SELECT count(*) FROM sqlite_schema");
      tables.step();
      if (tables.column_int(0) > 0) {
        throw InputError("database '" + db_->file().string() +
                         "' already holds tables that pdamp did not create; give another --db");
      }
    }
    for (int v = version; v < latest; ++v) db_->exec(schema::migrations()[static_cast<std::size_t>(v)]);
    db_->exec("PRAGMA user_version = " + std::to_string(latest));
  });
}

std::int64_t RunStore::begin_run(const NewRun& run) {
  return sqlite::write_transaction(*db_, [&] {
    sqlite::Statement insert(*db_,
                             "INSERT INTO runs (model, scenario_name, scenario_text, seed, n_particles, duration_s, "
                             "pdamp_version, status, started_at, lease_host, lease_pid, lease_start) "
                             "VALUES (?, ?, ?, ?, ?, ?, ?, 'running', ?, ?, ?, ?)");
    const ProcessLease lease = this_process_lease();
    insert.bind(1, run.model)
        .bind(2, run.scenario_name)
        .bind(3, run.scenario_text)
        .bind(4, static_cast<std::int64_t>(run.seed))
        .bind(5, run.n_particles)
        .bind(6, run.duration_s)
        .bind(7, std::string_view(version_string))
        .bind(8, utc_now_iso8601())
        .bind(9, lease.host)
        .bind(10, lease.pid)
        .bind(11, lease.start_ticks);
    insert.run();
    return db_->last_insert_rowid();
  });
}

void RunStore::require_run(std::int64_t run_id) {
  sqlite::Statement query(*db_, "SELECT 1 FROM runs WHERE run_id = ?");
  query.bind(1, run_id);
  if (query.step()) return;
  throw RuntimeFailure("run " + std::to_string(run_id) + " is no longer in the store '" + db_->file().string() +
                       "': another process deleted it while it ran (pdamp delete --force); what it computed since "
                       "its last write is not stored");
}

void RunStore::start_run(std::int64_t run_id, const RunStart& start) {
  sqlite::write_transaction(*db_, [&] {
    require_run(run_id);
    sqlite::Statement update(*db_,
                             "UPDATE runs SET dt_s = ?, initial_state_id = ?, bed_shift_z_m = ?, bed_shift_v_m_s = ?, "
                             "solid_fraction = ? WHERE run_id = ?");
    const auto& shift = start.bed_shift;
    update.bind(1, start.dt_s)
        .bind(2, start.initial_state_id)
        .bind(3, shift ? std::optional(shift->z_m) : std::nullopt)
        .bind(4, shift ? std::optional(shift->v_m_s) : std::nullopt)
        .bind(5, start.solid_fraction)
        .bind(6, run_id);
    update.run();
  });
}

void RunStore::append_results(std::int64_t run_id, std::span<const SampleRecord> samples,
                              std::span<const CycleRecord> cycles, const RunCheckpoint* checkpoint) {
  sqlite::write_transaction(*db_, [&] {
    require_run(run_id);
    sqlite::Statement sample(*db_, "INSERT INTO samples (run_id, " + std::string(sample_columns) +
                                       ") VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    for (const SampleRecord& s : samples) insert_sample(sample, run_id, s);
    sqlite::Statement cycle(*db_, "INSERT INTO cycles (run_id, " + std::string(cycle_columns) +
                                      ") VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    for (const CycleRecord& c : cycles) insert_cycle(cycle, run_id, c);
    if (checkpoint) replace_checkpoint(run_id, *checkpoint);
  });
}

std::optional<StoredInitialState> RunStore::find_initial_state(const std::string& settle_key) {
  sqlite::Statement query(*db_, "SELECT state_id, settle_time_s FROM initial_states WHERE settle_key = ?");
  query.bind(1, settle_key);
  if (!query.step()) return std::nullopt;
  const std::int64_t id = query.column_int(0);
  return StoredInitialState{id, load_initial_particles(id), query.column_double(1)};
}

SavedInitialState insert_initial_state(sqlite::Database& db, const std::string& settle_key, const Particles& p,
                                       double settle_time_s, double kinetic_J, double wall_time_s) {
  // Another process may have settled the same bed meanwhile: the first one stays.
  sqlite::Statement existing(db, "SELECT state_id FROM initial_states WHERE settle_key = ?");
  existing.bind(1, settle_key);
  if (existing.step()) return {existing.column_int(0), false};
  sqlite::Statement state(db,
                          "INSERT INTO initial_states (settle_key, n_particles, settle_time_s, kinetic_J, "
                          "wall_time_s, created_at) VALUES (?, ?, ?, ?, ?, ?)");
  state.bind(1, settle_key)
      .bind(2, static_cast<std::int64_t>(p.size()))
      .bind(3, settle_time_s)
      .bind(4, kinetic_J)
      .bind(5, wall_time_s)
      .bind(6, utc_now_iso8601());
  state.run();
  const std::int64_t id = db.last_insert_rowid();
  sqlite::Statement particle(db, "INSERT INTO initial_particles VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
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
  return {id, true};
}

SavedInitialState RunStore::save_initial_state(const std::string& settle_key, const Particles& p, double settle_time_s,
                                               double kinetic_J, double wall_time_s) {
  return sqlite::write_transaction(
      *db_, [&] { return insert_initial_state(*db_, settle_key, p, settle_time_s, kinetic_J, wall_time_s); });
}

Particles RunStore::load_initial_particles(std::int64_t state_id) {
  sqlite::Statement count(*db_, "SELECT n_particles FROM initial_states WHERE state_id = ?");
  count.bind(1, state_id);
  if (!count.step()) throw InputError("initial state " + std::to_string(state_id) + " is not in the store");
  Particles p(count.column_int(0));
  sqlite::Statement rows(*db_, "SELECT * FROM initial_particles WHERE state_id = ? ORDER BY particle");
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
  sqlite::write_transaction(*db_, [&] {
    require_run(run_id);
    sqlite::Statement update(*db_,
                             "UPDATE runs SET status = ?, message = ?, sim_time_s = ?, wall_time_s = ?, "
                             "initial_energy_J = ?, energy_balance_rel_err = ?, ended_at = ?, lease_host = NULL, "
                             "lease_pid = NULL, lease_start = NULL WHERE run_id = ?");
    update.bind(1, to_string(end.status))
        .bind(2, end.message)
        .bind(3, end.sim_time_s)
        .bind(4, end.wall_time_s)
        .bind(5, end.initial_energy_J)
        .bind(6, end.energy_balance_rel_err)
        .bind(7, utc_now_iso8601())
        .bind(8, run_id);
    update.run();
  });
}

void RunStore::save_statistics(std::int64_t run_id, const EngineStatistics& statistics) {
  sqlite::write_transaction(*db_, [&] {
    require_run(run_id);
    sqlite::Statement upsert(*db_, "INSERT OR REPLACE INTO run_statistics (run_id, name, value) VALUES (?, ?, ?)");
    for (const auto& [name, value] : statistics) upsert.bind(1, run_id).bind(2, name).bind(3, value).run();
  });
}

void RunStore::save_calibration(std::int64_t run_id, const RestitutionTable& table) {
  sqlite::write_transaction(*db_, [&] {
    require_run(run_id);
    sqlite::Statement insert(
        *db_, "INSERT INTO calibrations (run_id, contact, impact_speed_m_s, en, beta0) VALUES (?, ?, ?, ?, ?)");
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
  });
}

EngineStatistics RunStore::statistics(std::int64_t run_id) {
  sqlite::Statement query(*db_, "SELECT name, value FROM run_statistics WHERE run_id = ? ORDER BY name");
  query.bind(1, run_id);
  EngineStatistics result;
  while (query.step()) result.emplace_back(query.column_text(0), query.column_int(1));
  return result;
}

void RunStore::save_comparison_runs(std::int64_t soft_run_id, std::optional<std::int64_t> hard_run_id) {
  sqlite::write_transaction(*db_, [&] {
    sqlite::Statement row(*db_,
                          "INSERT INTO comparison_runs (soft_run_id, hard_run_id) VALUES (?, ?) "
                          "ON CONFLICT (soft_run_id) DO UPDATE SET hard_run_id = excluded.hard_run_id");
    row.bind(1, soft_run_id).bind(2, hard_run_id).run();
  });
}

std::optional<ComparisonRuns> RunStore::comparison_runs(std::int64_t run_id) {
  sqlite::Statement q(*db_,
                      "SELECT c.soft_run_id, c.hard_run_id, r.scenario_name, r.scenario_text, r.initial_state_id "
                      "FROM comparison_runs c JOIN runs r ON r.run_id = c.soft_run_id "
                      "WHERE c.soft_run_id = ?1 OR c.hard_run_id = ?1");
  q.bind(1, run_id);
  if (!q.step()) return std::nullopt;
  ComparisonRuns runs;
  runs.soft_run_id = q.column_int(0);
  if (!q.is_null(1)) runs.hard_run_id = q.column_int(1);
  runs.scenario_name = q.column_text(2);
  runs.scenario_text = q.column_text(3);
  if (!q.is_null(4)) runs.initial_state_id = q.column_int(4);
  return runs;
}

std::int64_t RunStore::save_comparison(const ComparisonRecord& c) {
  return sqlite::write_transaction(*db_, [&] {
    sqlite::Statement row(*db_,
                          "INSERT INTO comparisons (scenario_name, soft_run_id, hard_run_id, initial_state_id, "
                          "hard_restitution, created_at, envelope_max_rel_diff, envelope_rms_rel_diff, "
                          "small_amplitude_freq_soft_hz, small_amplitude_freq_hard_hz, gamma_below_1_soft_s, "
                          "gamma_below_1_hard_s, psi_mean_abs_diff, dissipated_soft_J, dissipated_hard_J, "
                          "dissipated_rel_diff, wall_time_soft_s, wall_time_hard_s, wall_time_ratio, soft_steps, "
                          "hard_events) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    row.bind(1, c.scenario_name).bind(2, c.soft_run_id).bind(3, c.hard_run_id).bind(4, c.initial_state_id);
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
    const std::int64_t id = db_->last_insert_rowid();
    sqlite::Statement under_way(*db_, "DELETE FROM comparison_runs WHERE soft_run_id = ?");
    under_way.bind(1, c.soft_run_id).run();
    sqlite::Statement bin(*db_,
                          "INSERT INTO comparison_psi_bins (comparison_id, gamma_low, gamma_high, psi_soft, psi_hard, "
                          "cycles_soft, cycles_hard) VALUES (?, ?, ?, ?, ?, ?, ?)");
    for (const auto& b : c.psi_bins) {
      bin.bind(1, id).bind(2, b.gamma_low).bind(3, b.gamma_high).bind(4, b.psi_soft).bind(5, b.psi_hard);
      bin.bind(6, b.cycles_soft).bind(7, b.cycles_hard).run();
    }
    sqlite::Statement energy(
        *db_,
        "INSERT INTO comparison_energy (comparison_id, t_s, model, impact_J, friction_J, viscous_J) "
        "VALUES (?, ?, ?, ?, ?, ?)");
    for (const auto& e : c.energy) {
      energy.bind(1, id).bind(2, e.t_s).bind(3, e.model).bind(4, e.impact_J).bind(5, e.friction_J);
      energy.bind(6, e.viscous_J).run();
    }
    return id;
  });
}

void RunStore::save_snapshots(std::int64_t run_id, const SnapshotRecord& s) {
  sqlite::write_transaction(*db_, [&] {
    require_run(run_id);
    sqlite::Statement upsert(*db_,
                             "INSERT OR REPLACE INTO run_snapshots (run_id, folder, collection, interval_s, frames) "
                             "VALUES (?, ?, ?, ?, ?)");
    upsert.bind(1, run_id).bind(2, s.folder).bind(3, s.collection).bind(4, s.interval_s).bind(5, s.frames).run();
  });
}

RunResults RunStore::results(std::int64_t run_id) {
  const auto run = summary(run_id);
  if (!run) throw InputError("run " + std::to_string(run_id) + " is not in '" + db_->file().string() + "'");
  RunResults results{run_id, {}, {}, run->wall_time_s.value_or(0.0)};
  sqlite::Statement samples(*db_,
                            "SELECT " + std::string(sample_columns) + " FROM samples WHERE run_id = ? ORDER BY t_s");
  samples.bind(1, run_id);
  while (samples.step()) results.samples.push_back(read_sample(samples));
  sqlite::Statement cycles(*db_,
                           "SELECT " + std::string(cycle_columns) + " FROM cycles WHERE run_id = ? ORDER BY cycle");
  cycles.bind(1, run_id);
  while (cycles.step()) results.cycles.push_back(read_cycle(cycles));
  return results;
}

const std::filesystem::path& RunStore::file() const { return db_->file(); }

void RunStore::make_self_contained() { db_->exec("PRAGMA journal_mode = DELETE"); }

std::optional<SnapshotRecord> RunStore::snapshots(std::int64_t run_id) {
  sqlite::Statement query(*db_, "SELECT folder, collection, interval_s, frames FROM run_snapshots WHERE run_id = ?");
  query.bind(1, run_id);
  if (!query.step()) return std::nullopt;
  return SnapshotRecord{query.column_text(0), query.column_text(1), query.column_double(2), query.column_int(3)};
}

std::vector<RunSummary> RunStore::list_runs() {
  sqlite::Statement query(*db_, std::string(summary_columns) + " ORDER BY v.run_id");
  std::vector<RunSummary> runs;
  while (query.step()) runs.push_back(read_summary(query));
  return runs;
}

std::optional<RunSummary> RunStore::summary(std::int64_t run_id) {
  sqlite::Statement query(*db_, std::string(summary_columns) + " WHERE v.run_id = ?");
  query.bind(1, run_id);
  if (!query.step()) return std::nullopt;
  return read_summary(query);
}

std::optional<CycleOverview> RunStore::cycle_overview(std::int64_t run_id) {
  sqlite::Statement query(*db_,
                          "SELECT (SELECT freq_hz FROM cycles WHERE run_id = ?1 ORDER BY cycle LIMIT 1), "
                          "(SELECT freq_hz FROM cycles WHERE run_id = ?1 ORDER BY cycle DESC LIMIT 1), "
                          "psi, gamma, cycle FROM cycles WHERE run_id = ?1 ORDER BY psi DESC LIMIT 1");
  query.bind(1, run_id);
  if (!query.step()) return std::nullopt;
  return CycleOverview{query.column_double(0), query.column_double(1), query.column_double(2),
                       query.column_optional_double(3), query.column_int(4)};
}

std::vector<DeletedRun> RunStore::delete_runs(std::span<const std::int64_t> run_ids, bool including_running) {
  const std::set<std::int64_t> ids(run_ids.begin(), run_ids.end());
  return sqlite::write_transaction(*db_, [&] {
    std::vector<DeletedRun> deleted;
    sqlite::Statement comparisons(*db_, "SELECT count(*) FROM comparisons WHERE soft_run_id = ?1 OR hard_run_id = ?1");
    for (const std::int64_t id : ids) {
      auto run = summary(id);
      if (!run) {
        throw InputError("run " + std::to_string(id) + " is not in '" + db_->file().string() +
                         "' (see pdamp runs); nothing was deleted");
      }
      if (run->status == "running" && !including_running) {
        const std::string where =
            run->lease ? " in process " + std::to_string(run->lease->pid) + " on " + run->lease->host : "";
        throw InputError("run " + std::to_string(id) + " is running" + where +
                         " (a run whose process is gone shows as dead and is deleted without --force); nothing was "
                         "deleted. --force deletes it anyway (a run still going then fails)");
      }
      comparisons.bind(1, id);
      comparisons.step();
      deleted.push_back({std::move(*run), comparisons.column_int(0)});
      comparisons.reset();
    }
    // The foreign keys cascade to samples, cycles, statistics, calibrations and comparisons.
    sqlite::Statement remove(*db_, "DELETE FROM runs WHERE run_id = ?");
    for (const std::int64_t id : ids) remove.bind(1, id).run();
    return deleted;
  });
}

RunWriter::RunWriter(RunStore& store, std::int64_t run_id, std::chrono::milliseconds commit_interval)
    : store_(&store),
      run_id_(run_id),
      commit_interval_(commit_interval),
      last_flush_(std::chrono::steady_clock::now()) {}

RunWriter::~RunWriter() {
  try {
    flush();
  } catch (...) {
    // Destructors must not throw; an explicit flush() reports the error.
  }
}

void RunWriter::record_sample(const Observation& sample, double energy_balance_rel_err) {
  samples_.push_back({sample, energy_balance_rel_err});
  flush_if_due();
}

void RunWriter::record_cycle(const CycleRecord& cycle) {
  cycles_.push_back(cycle);
  flush_if_due();
}

void RunWriter::flush_if_due() {
  if (std::chrono::steady_clock::now() - last_flush_ >= commit_interval_ ||
      samples_.size() + cycles_.size() >= max_buffered_rows) {
    flush();
  }
}

void RunWriter::flush() {
  last_flush_ = std::chrono::steady_clock::now();
  if (samples_.empty() && cycles_.empty()) return;
  write(nullptr);
}

void RunWriter::flush_with_checkpoint(const RunCheckpoint& checkpoint) {
  last_flush_ = std::chrono::steady_clock::now();
  write(&checkpoint);
}

void RunWriter::write(const RunCheckpoint* checkpoint) {
  store_->append_results(run_id_, samples_, cycles_, checkpoint);
  samples_.clear();
  cycles_.clear();
}

}  // namespace pdamp
