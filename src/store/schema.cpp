/// The SQL schema of the run store, as an ordered list of migrations. Never edit a
/// migration that has shipped: add a new one. Column names carry their units.
#include "schema.hpp"

#include <array>
#include <string>

namespace pdamp::schema {
namespace {

constexpr std::string_view v1_runs_samples_cycles = R"sql(
CREATE TABLE runs (
  run_id                  INTEGER PRIMARY KEY,
  model                   TEXT NOT NULL CHECK (model IN ('soft', 'hard')),
  scenario_name           TEXT NOT NULL,
  scenario_text           TEXT NOT NULL,            -- every key with its resolved value
  seed                    INTEGER NOT NULL,         -- uint64 stored as its int64 bit pattern
  n_particles             INTEGER NOT NULL CHECK (n_particles >= 0),
  duration_s              REAL NOT NULL,            -- requested simulated time
  dt_s                    REAL,                     -- time step (time-stepped engines)
  pdamp_version           TEXT NOT NULL,
  status                  TEXT NOT NULL CHECK (status IN ('running', 'completed', 'failed', 'interrupted')),
  message                 TEXT NOT NULL DEFAULT '',
  started_at              TEXT NOT NULL,            -- ISO 8601, UTC
  ended_at                TEXT,
  wall_time_s             REAL,
  sim_time_s              REAL NOT NULL DEFAULT 0,  -- simulated time reached
  initial_energy_J        REAL,
  energy_balance_rel_err  REAL                      -- max over the run of |E0 + W - E - D| / (|E0| + |W|)
) STRICT;

CREATE TABLE samples (
  run_id                     INTEGER NOT NULL REFERENCES runs (run_id) ON DELETE CASCADE,
  t_s                        REAL NOT NULL,
  host_z_m                   REAL NOT NULL,
  host_v_m_s                 REAL NOT NULL,
  particle_translational_J   REAL NOT NULL,
  particle_rotational_J      REAL NOT NULL,
  host_kinetic_J             REAL NOT NULL,
  spring_potential_J         REAL NOT NULL,
  gravitational_potential_J  REAL NOT NULL,
  contact_elastic_J          REAL NOT NULL,
  excitation_work_J          REAL NOT NULL,
  dissipated_impact_J        REAL NOT NULL,
  dissipated_friction_J      REAL NOT NULL,
  dissipated_viscous_J       REAL NOT NULL,
  energy_balance_rel_err     REAL NOT NULL,
  contacts                   INTEGER NOT NULL,
  events                     INTEGER NOT NULL,
  steps                      INTEGER NOT NULL,
  PRIMARY KEY (run_id, t_s)
) STRICT, WITHOUT ROWID;

CREATE TABLE cycles (
  run_id              INTEGER NOT NULL REFERENCES runs (run_id) ON DELETE CASCADE,
  cycle               INTEGER NOT NULL,
  t_start_s           REAL NOT NULL,
  t_end_s             REAL NOT NULL,
  amplitude_m         REAL NOT NULL,
  freq_hz             REAL NOT NULL,
  gamma               REAL,           -- A (2 pi f)^2 / |g_z|; NULL without vertical gravity
  psi                 REAL NOT NULL,  -- dissipated in the cycle / max host kinetic energy in it
  psi_impact          REAL NOT NULL,
  psi_friction        REAL NOT NULL,
  psi_viscous         REAL NOT NULL,
  max_host_kinetic_J  REAL NOT NULL,
  PRIMARY KEY (run_id, cycle)
) STRICT, WITHOUT ROWID;

CREATE VIEW run_summary AS
SELECT r.run_id, r.model, r.scenario_name, r.status, r.n_particles, r.duration_s, r.sim_time_s,
       r.wall_time_s, r.energy_balance_rel_err,
       (SELECT count(*) FROM samples s WHERE s.run_id = r.run_id) AS n_samples,
       (SELECT count(*) FROM cycles c WHERE c.run_id = r.run_id) AS n_cycles,
       last.dissipated_impact_J, last.dissipated_friction_J, last.dissipated_viscous_J,
       r.started_at, r.message
FROM runs r
LEFT JOIN samples last ON last.run_id = r.run_id
  AND last.t_s = (SELECT max(t_s) FROM samples m WHERE m.run_id = r.run_id);
)sql";

constexpr std::string_view v2_run_statistics = R"sql(
CREATE TABLE run_statistics (
  run_id  INTEGER NOT NULL REFERENCES runs (run_id) ON DELETE CASCADE,
  name    TEXT NOT NULL,     -- e.g. events_sphere_sphere, neighbour_rebuilds
  value   INTEGER NOT NULL,
  PRIMARY KEY (run_id, name)
) STRICT, WITHOUT ROWID;
)sql";

constexpr std::string_view v3_initial_states = R"sql(
CREATE TABLE initial_states (
  state_id       INTEGER PRIMARY KEY,
  settle_key     TEXT NOT NULL UNIQUE,  -- every setting that determines the bed
  n_particles    INTEGER NOT NULL,
  settle_time_s  REAL NOT NULL,         -- simulated settling time
  kinetic_J      REAL NOT NULL,         -- particle kinetic energy when declared at rest
  wall_time_s    REAL NOT NULL,
  created_at     TEXT NOT NULL
) STRICT;

CREATE TABLE initial_particles (
  state_id   INTEGER NOT NULL REFERENCES initial_states (state_id) ON DELETE CASCADE,
  particle   INTEGER NOT NULL,
  x_m        REAL NOT NULL,
  y_m        REAL NOT NULL,
  z_m        REAL NOT NULL,
  vx_m_s     REAL NOT NULL,
  vy_m_s     REAL NOT NULL,
  vz_m_s     REAL NOT NULL,
  wx_rad_s   REAL NOT NULL,
  wy_rad_s   REAL NOT NULL,
  wz_rad_s   REAL NOT NULL,
  radius_m   REAL NOT NULL,
  mass_kg    REAL NOT NULL,
  PRIMARY KEY (state_id, particle)
) STRICT, WITHOUT ROWID;

ALTER TABLE runs ADD COLUMN initial_state_id INTEGER REFERENCES initial_states (state_id);
)sql";

constexpr std::string_view v4_comparisons = R"sql(
CREATE TABLE calibrations (
  run_id            INTEGER NOT NULL REFERENCES runs (run_id) ON DELETE CASCADE,
  contact           TEXT NOT NULL CHECK (contact IN ('sphere_sphere', 'sphere_wall')),
  impact_speed_m_s  REAL NOT NULL,
  en                REAL NOT NULL,  -- normal restitution of an isolated soft collision
  beta0             REAL NOT NULL,  -- tangential restitution of a sticking oblique one
  PRIMARY KEY (run_id, contact, impact_speed_m_s)
) STRICT, WITHOUT ROWID;

CREATE TABLE comparisons (
  comparison_id                 INTEGER PRIMARY KEY,
  scenario_name                 TEXT NOT NULL,
  soft_run_id                   INTEGER NOT NULL REFERENCES runs (run_id) ON DELETE CASCADE,
  hard_run_id                   INTEGER NOT NULL REFERENCES runs (run_id) ON DELETE CASCADE,
  initial_state_id              INTEGER REFERENCES initial_states (state_id),
  hard_restitution              TEXT NOT NULL,
  created_at                    TEXT NOT NULL,
  envelope_max_rel_diff         REAL,  -- max over t of |A_hard(t) - A_soft(t)| / A_soft(0)
  envelope_rms_rel_diff         REAL,  -- rms of the same over the soft run's cycles
  small_amplitude_freq_soft_hz  REAL,  -- mean cycle frequency once Gamma < 1
  small_amplitude_freq_hard_hz  REAL,
  gamma_below_1_soft_s          REAL,  -- start of the first cycle with Gamma < 1
  gamma_below_1_hard_s          REAL,
  psi_mean_abs_diff             REAL,  -- mean |psi_hard - psi_soft| over Gamma bins both models fill
  dissipated_soft_J             REAL,  -- impact + friction + viscous at the end
  dissipated_hard_J             REAL,
  dissipated_rel_diff           REAL,  -- (hard - soft) / soft
  wall_time_soft_s              REAL,
  wall_time_hard_s              REAL,
  wall_time_ratio               REAL,  -- soft / hard
  soft_steps                    INTEGER,
  hard_events                   INTEGER
) STRICT;

CREATE TABLE comparison_psi_bins (
  comparison_id  INTEGER NOT NULL REFERENCES comparisons (comparison_id) ON DELETE CASCADE,
  gamma_low      REAL NOT NULL,  -- bins [2^k, 2^(k+1))
  gamma_high     REAL NOT NULL,
  psi_soft       REAL,           -- mean psi of the cycles in the bin; NULL if none
  psi_hard       REAL,
  cycles_soft    INTEGER NOT NULL,
  cycles_hard    INTEGER NOT NULL,
  PRIMARY KEY (comparison_id, gamma_low)
) STRICT, WITHOUT ROWID;

CREATE TABLE comparison_energy (
  comparison_id  INTEGER NOT NULL REFERENCES comparisons (comparison_id) ON DELETE CASCADE,
  t_s            REAL NOT NULL,
  model          TEXT NOT NULL CHECK (model IN ('soft', 'hard')),
  impact_J       REAL NOT NULL,
  friction_J     REAL NOT NULL,
  viscous_J      REAL NOT NULL,
  PRIMARY KEY (comparison_id, t_s, model)
) STRICT, WITHOUT ROWID;

CREATE VIEW damping_curve AS
SELECT c.run_id, r.model, r.scenario_name, c.cycle, c.t_start_s, c.amplitude_m, c.freq_hz, c.gamma,
       c.psi, c.psi_impact, c.psi_friction, c.psi_viscous
FROM cycles c JOIN runs r USING (run_id);

CREATE VIEW energy_partition AS
SELECT r.run_id, r.model, r.scenario_name, r.n_particles, s.t_s,
       s.dissipated_impact_J AS impact_J, s.dissipated_friction_J AS friction_J, s.dissipated_viscous_J AS viscous_J,
       s.dissipated_impact_J + s.dissipated_friction_J + s.dissipated_viscous_J AS total_J,
       s.dissipated_impact_J / nullif(s.dissipated_impact_J + s.dissipated_friction_J + s.dissipated_viscous_J, 0) AS impact_share,
       s.dissipated_friction_J / nullif(s.dissipated_impact_J + s.dissipated_friction_J + s.dissipated_viscous_J, 0) AS friction_share,
       s.dissipated_viscous_J / nullif(s.dissipated_impact_J + s.dissipated_friction_J + s.dissipated_viscous_J, 0) AS viscous_share
FROM runs r JOIN samples s ON s.run_id = r.run_id
 AND s.t_s = (SELECT max(t_s) FROM samples m WHERE m.run_id = r.run_id);

CREATE VIEW comparison_summary AS
SELECT c.comparison_id, c.scenario_name, c.hard_restitution, c.soft_run_id, c.hard_run_id,
       c.envelope_max_rel_diff, c.small_amplitude_freq_soft_hz, c.small_amplitude_freq_hard_hz,
       c.gamma_below_1_soft_s, c.gamma_below_1_hard_s, c.psi_mean_abs_diff,
       c.dissipated_soft_J, c.dissipated_hard_J, c.dissipated_rel_diff,
       c.wall_time_soft_s, c.wall_time_hard_s, c.wall_time_ratio, c.soft_steps, c.hard_events,
       (SELECT max(psi) FROM cycles WHERE run_id = c.soft_run_id) AS psi_peak_soft,
       (SELECT max(psi) FROM cycles WHERE run_id = c.hard_run_id) AS psi_peak_hard
FROM comparisons c;
)sql";

/// The fill of each run (the paper's packing studies): spheres' volume over the hole's.
constexpr std::string_view v5_solid_fraction = R"sql(
ALTER TABLE runs ADD COLUMN solid_fraction REAL CHECK (solid_fraction >= 0);

DROP VIEW energy_partition;
CREATE VIEW energy_partition AS
SELECT r.run_id, r.model, r.scenario_name, r.n_particles, r.solid_fraction, s.t_s,
       s.dissipated_impact_J AS impact_J, s.dissipated_friction_J AS friction_J, s.dissipated_viscous_J AS viscous_J,
       s.dissipated_impact_J + s.dissipated_friction_J + s.dissipated_viscous_J AS total_J,
       s.dissipated_impact_J / nullif(s.dissipated_impact_J + s.dissipated_friction_J + s.dissipated_viscous_J, 0) AS impact_share,
       s.dissipated_friction_J / nullif(s.dissipated_impact_J + s.dissipated_friction_J + s.dissipated_viscous_J, 0) AS friction_share,
       s.dissipated_viscous_J / nullif(s.dissipated_impact_J + s.dissipated_friction_J + s.dissipated_viscous_J, 0) AS viscous_share
FROM runs r JOIN samples s ON s.run_id = r.run_id
 AND s.t_s = (SELECT max(t_s) FROM samples m WHERE m.run_id = r.run_id);
)sql";

/// A run_id is never used twice, also after the newest run is deleted (AUTOINCREMENT:
/// the table is rebuilt, with foreign keys off, RunStore::migrate). The first id after
/// the migration comes after every id that any row still refers to: a run deleted by
/// hand with foreign keys off leaves its samples behind. The file is marked as a pdamp
/// store (application_id 'pdam'). The views that read runs resolve to the new table by
/// name (legacy_alter_table: the rename leaves them as they are).
constexpr std::string_view v6_run_ids_never_reused = R"sql(
PRAGMA application_id = 1885626733;
PRAGMA legacy_alter_table = ON;

CREATE TABLE runs_v6 (
  run_id                  INTEGER PRIMARY KEY AUTOINCREMENT,
  model                   TEXT NOT NULL CHECK (model IN ('soft', 'hard')),
  scenario_name           TEXT NOT NULL,
  scenario_text           TEXT NOT NULL,            -- every key with its resolved value
  seed                    INTEGER NOT NULL,         -- uint64 stored as its int64 bit pattern
  n_particles             INTEGER NOT NULL CHECK (n_particles >= 0),
  duration_s              REAL NOT NULL,            -- requested simulated time
  dt_s                    REAL,                     -- time step (time-stepped engines)
  pdamp_version           TEXT NOT NULL,
  status                  TEXT NOT NULL CHECK (status IN ('running', 'completed', 'failed', 'interrupted')),
  message                 TEXT NOT NULL DEFAULT '',
  started_at              TEXT NOT NULL,            -- ISO 8601, UTC
  ended_at                TEXT,
  wall_time_s             REAL,
  sim_time_s              REAL NOT NULL DEFAULT 0,  -- simulated time reached
  initial_energy_J        REAL,
  energy_balance_rel_err  REAL,                     -- max over the run of |E0 + W - E - D| / (|E0| + |W|)
  initial_state_id        INTEGER REFERENCES initial_states (state_id),
  solid_fraction          REAL CHECK (solid_fraction >= 0)  -- the spheres' volume over the hole's
) STRICT;
INSERT INTO runs_v6 SELECT run_id, model, scenario_name, scenario_text, seed, n_particles, duration_s, dt_s,
  pdamp_version, status, message, started_at, ended_at, wall_time_s, sim_time_s, initial_energy_J,
  energy_balance_rel_err, initial_state_id, solid_fraction FROM runs;
DROP TABLE runs;
ALTER TABLE runs_v6 RENAME TO runs;
PRAGMA legacy_alter_table = OFF;

DELETE FROM sqlite_sequence WHERE name IN ('runs', 'runs_v6');
INSERT INTO sqlite_sequence (name, seq)
SELECT 'runs', coalesce(max(id), 0) FROM (
  SELECT max(run_id) AS id FROM runs UNION ALL SELECT max(run_id) FROM samples
  UNION ALL SELECT max(run_id) FROM cycles UNION ALL SELECT max(run_id) FROM run_statistics
  UNION ALL SELECT max(run_id) FROM calibrations UNION ALL SELECT max(soft_run_id) FROM comparisons
  UNION ALL SELECT max(hard_run_id) FROM comparisons);
)sql";

/// Where a run's snapshots for ParaView are (docs/snapshots.md).
constexpr std::string_view v7_run_snapshots = R"sql(
CREATE TABLE run_snapshots (
  run_id      INTEGER PRIMARY KEY REFERENCES runs (run_id) ON DELETE CASCADE,
  folder      TEXT NOT NULL,                          -- the run's folder, absolute
  collection  TEXT NOT NULL,                          -- the .pvd in it, which ParaView opens
  interval_s  REAL NOT NULL CHECK (interval_s > 0),   -- simulated time between frames
  frames      INTEGER NOT NULL CHECK (frames >= 0)    -- frames written (0 until the run ends)
) STRICT;
)sql";

/// Studies: a study's definition, its points with their parameters,
/// status and lease, the runs of each point's attempts, and each completed point's
/// metrics. Frequency-response points (a later migration) join these tables: a curve of
/// ordered points, and their response metrics in a table of their own.
constexpr std::string_view v8_studies = R"sql(
CREATE TABLE studies (
  study_id       INTEGER PRIMARY KEY AUTOINCREMENT,
  name           TEXT NOT NULL UNIQUE,
  models         TEXT NOT NULL CHECK (models IN ('soft', 'hard', 'both')),
  n_points       INTEGER NOT NULL CHECK (n_points > 0),
  study_file     TEXT NOT NULL,  -- where the study file was read (absolute path)
  study_text     TEXT NOT NULL,  -- its text
  scenario_file  TEXT NOT NULL,  -- the base scenario file (absolute path)
  scenario_text  TEXT NOT NULL,  -- its text; the points are built from these two texts
  pdamp_version  TEXT NOT NULL,
  created_at     TEXT NOT NULL   -- ISO 8601, UTC
) STRICT;

CREATE TABLE study_points (
  study_id       INTEGER NOT NULL REFERENCES studies (study_id) ON DELETE CASCADE,
  point          INTEGER NOT NULL CHECK (point >= 1),  -- 1, 2, ... in the study file's order
  section        TEXT NOT NULL,                        -- the section it comes from: 'sweep' or 'sweep.NAME'
  status         TEXT NOT NULL DEFAULT 'pending'
                 CHECK (status IN ('pending', 'running', 'completed', 'failed', 'interrupted')),
  attempt        INTEGER NOT NULL DEFAULT 0,           -- times started; the latest attempt's runs count
  message        TEXT NOT NULL DEFAULT '',
  lease_host     TEXT,                                 -- while running: the host,
  lease_pid      INTEGER,                              -- process id
  lease_start    INTEGER,                              -- and start time (clock ticks after boot) of its process
  started_at     TEXT,
  ended_at       TEXT,
  comparison_id  INTEGER REFERENCES comparisons (comparison_id) ON DELETE SET NULL,  -- models = both
  PRIMARY KEY (study_id, point)
) STRICT;

CREATE TABLE study_point_values (
  study_id  INTEGER NOT NULL,
  point     INTEGER NOT NULL,
  key       TEXT NOT NULL,  -- scenario key, section.key
  value     TEXT NOT NULL,  -- as a scenario file would give it
  number    REAL,           -- the value if it is one number, else NULL
  PRIMARY KEY (study_id, point, key),
  FOREIGN KEY (study_id, point) REFERENCES study_points (study_id, point) ON DELETE CASCADE
) STRICT, WITHOUT ROWID;

CREATE TABLE study_point_runs (
  study_id  INTEGER NOT NULL,
  point     INTEGER NOT NULL,
  attempt   INTEGER NOT NULL,
  model     TEXT NOT NULL CHECK (model IN ('soft', 'hard')),
  run_id    INTEGER NOT NULL UNIQUE REFERENCES runs (run_id) ON DELETE CASCADE,
  PRIMARY KEY (study_id, point, attempt, model),
  FOREIGN KEY (study_id, point) REFERENCES study_points (study_id, point) ON DELETE CASCADE
) STRICT, WITHOUT ROWID;

CREATE TABLE study_point_metrics (
  study_id                INTEGER NOT NULL,
  point                   INTEGER NOT NULL,
  model                   TEXT NOT NULL CHECK (model IN ('soft', 'hard')),
  run_id                  INTEGER NOT NULL UNIQUE REFERENCES runs (run_id) ON DELETE CASCADE,
  dissipated_impact_J     REAL NOT NULL,  -- at the run's last sample
  dissipated_friction_J   REAL NOT NULL,
  dissipated_viscous_J    REAL NOT NULL,
  psi_peak                REAL,           -- the largest psi of a cycle; NULL without cycles
  psi_peak_gamma          REAL,           -- Gamma of that cycle
  final_amplitude_m       REAL,           -- amplitude of the last complete cycle
  cycles                  INTEGER NOT NULL,
  energy_balance_rel_err  REAL NOT NULL,  -- max over the run
  wall_time_s             REAL NOT NULL,
  PRIMARY KEY (study_id, point, model),
  FOREIGN KEY (study_id, point) REFERENCES study_points (study_id, point) ON DELETE CASCADE
) STRICT, WITHOUT ROWID;

-- A completed point one of whose runs is deleted (pdamp delete) is pending again, without
-- metrics: resuming the study runs it again.
CREATE TRIGGER study_point_run_deleted AFTER DELETE ON study_point_runs
BEGIN
  UPDATE study_points SET status = 'pending', comparison_id = NULL, ended_at = NULL,
         message = 'its ' || OLD.model || ' run ' || OLD.run_id || ' was deleted'
   WHERE study_id = OLD.study_id AND point = OLD.point AND attempt = OLD.attempt AND status = 'completed';
  DELETE FROM study_point_metrics WHERE study_id = OLD.study_id AND point = OLD.point
     AND (SELECT status FROM study_points WHERE study_id = OLD.study_id AND point = OLD.point) = 'pending';
END;

CREATE VIEW study_summary AS
SELECT s.study_id, s.name, s.models, s.n_points,
       sum(p.status = 'completed') AS completed, sum(p.status = 'failed') AS failed,
       sum(p.status = 'interrupted') AS interrupted, sum(p.status = 'running') AS running,
       sum(p.status = 'pending') AS pending, s.created_at, s.study_file
FROM studies s JOIN study_points p ON p.study_id = s.study_id
GROUP BY s.study_id;

CREATE VIEW study_results AS
SELECT p.study_id, s.name AS study, p.point, p.section, p.status, m.model, m.run_id,
       m.dissipated_impact_J, m.dissipated_friction_J, m.dissipated_viscous_J,
       m.dissipated_impact_J + m.dissipated_friction_J + m.dissipated_viscous_J AS dissipated_total_J,
       m.psi_peak, m.psi_peak_gamma, m.final_amplitude_m, m.cycles, m.energy_balance_rel_err, m.wall_time_s
FROM study_points p JOIN studies s ON s.study_id = p.study_id
LEFT JOIN study_point_metrics m ON m.study_id = p.study_id AND m.point = p.point;

CREATE VIEW study_agreement AS
SELECT p.study_id, p.point, c.comparison_id, c.soft_run_id, c.hard_run_id, c.envelope_max_rel_diff,
       c.envelope_rms_rel_diff, c.psi_mean_abs_diff, c.dissipated_rel_diff, c.small_amplitude_freq_soft_hz,
       c.small_amplitude_freq_hard_hz, c.wall_time_ratio
FROM study_points p JOIN comparisons c ON c.comparison_id = p.comparison_id;
)sql";

/// Studies on a Slurm cluster (pdamp study submit, collect, status): each job array
/// submitted, and each of its tasks: the point it runs and, once its shard store is
/// collected, how it ended. A shard store (written by one task, never shared) holds the
/// study, its point and its own task's row, not yet collected.
constexpr std::string_view v9_study_jobs = R"sql(
CREATE TABLE study_jobs (
  study_id      INTEGER NOT NULL REFERENCES studies (study_id) ON DELETE CASCADE,
  job_id        INTEGER NOT NULL CHECK (job_id > 0),  -- Slurm's id of the job array
  submitted_at  TEXT NOT NULL,                        -- ISO 8601, UTC
  script_file   TEXT NOT NULL,                        -- the job script (absolute path)
  shard_folder  TEXT NOT NULL,                        -- where its tasks write their shard stores
  PRIMARY KEY (study_id, job_id)
) STRICT;

CREATE TABLE study_tasks (
  study_id      INTEGER NOT NULL,
  job_id        INTEGER NOT NULL,
  task          INTEGER NOT NULL CHECK (task >= 0),  -- its array index, SLURM_ARRAY_TASK_ID
  point         INTEGER NOT NULL,                    -- the point it runs
  host          TEXT,                                -- the rest as its shard tells: the node,
  started_at    TEXT,
  ended_at      TEXT,
  outcome       TEXT CHECK (outcome IN ('completed', 'failed', 'interrupted')),  -- its point's status there
  message       TEXT NOT NULL DEFAULT '',
  shard_file    TEXT,
  collected_at  TEXT,                                -- NULL until its shard is merged into this store
  PRIMARY KEY (study_id, job_id, task),
  FOREIGN KEY (study_id, point) REFERENCES study_points (study_id, point) ON DELETE CASCADE
) STRICT, WITHOUT ROWID;
)sql";

/// Checkpoints and resume (docs/checkpoints.md): the process that runs a run (its lease,
/// so that a run whose process is gone reads as dead, not running), and each run's latest
/// checkpoint, written in one transaction with the samples and cycles recorded up to it.
constexpr std::string_view v10_run_checkpoints = R"sql(
ALTER TABLE runs ADD COLUMN lease_host TEXT;      -- while running: the host,
ALTER TABLE runs ADD COLUMN lease_pid INTEGER;    -- process id
ALTER TABLE runs ADD COLUMN lease_start INTEGER;  -- and start time (clock ticks after boot) of its process

CREATE TABLE run_checkpoints (
  run_id          INTEGER PRIMARY KEY REFERENCES runs (run_id) ON DELETE CASCADE,
  t_s             REAL NOT NULL,                       -- simulated time of the state saved
  samples         INTEGER NOT NULL CHECK (samples >= 0),  -- samples and cycles the run had recorded then
  cycles          INTEGER NOT NULL CHECK (cycles >= 0),
  pdamp_version   TEXT NOT NULL,                       -- the pdamp that wrote it (and may resume it)
  schema_version  INTEGER NOT NULL,                    -- the store's schema then
  written_at      TEXT NOT NULL,                       -- ISO 8601, UTC
  state           BLOB NOT NULL                        -- the run loop's and the engine's state (docs/checkpoints.md)
) STRICT;
)sql";

/// Frequency-response studies ([frf]): each point's place on its curve, its response
/// metrics, and its final state, which the next point of its curve starts from (the
/// particles kept as a settled bed is, in initial_states, under a key naming the run); the
/// study_frf view (study_frf_view) follows.
constexpr std::string_view v11_frf_studies = R"sql(
CREATE TABLE study_frf_points (
  study_id        INTEGER NOT NULL,
  point           INTEGER NOT NULL,
  curve           INTEGER NOT NULL CHECK (curve >= 1),  -- 1, 2, ...: one model, level and direction
  model           TEXT NOT NULL CHECK (model IN ('soft', 'hard')),
  direction       TEXT NOT NULL CHECK (direction IN ('up', 'down')),
  host_alone      INTEGER NOT NULL CHECK (host_alone IN (0, 1)),  -- the reference curve without particles
  mode            TEXT NOT NULL CHECK (mode IN ('force', 'base')),
  level           REAL NOT NULL,  -- F0 (N) under a force, Y (m) under base motion
  frequency_hz    REAL NOT NULL,
  step            INTEGER NOT NULL CHECK (step >= 1),  -- along the curve, in the order the points run
  previous_point  INTEGER,  -- the point whose final state this one starts from; NULL: the settled bed
  PRIMARY KEY (study_id, point),
  FOREIGN KEY (study_id, point) REFERENCES study_points (study_id, point) ON DELETE CASCADE
) STRICT, WITHOUT ROWID;

CREATE TABLE study_frf_metrics (
  study_id                  INTEGER NOT NULL,
  point                     INTEGER NOT NULL,
  run_id                    INTEGER NOT NULL UNIQUE REFERENCES runs (run_id) ON DELETE CASCADE,
  settled                   INTEGER NOT NULL CHECK (settled IN (0, 1)),
  cycles_to_steady          INTEGER NOT NULL,  -- cycles before the measured ones
  cycles_run                INTEGER NOT NULL,
  measured_cycles           INTEGER NOT NULL,
  amplitude_m               REAL NOT NULL,  -- X of the first harmonic over the measured cycles
  amplitude_spread_m        REAL NOT NULL,  -- max - min of the measured cycles' own X
  phase_rad                 REAL NOT NULL,  -- of the host against the excitation; < 0: it lags
  normalised_amplitude      REAL NOT NULL,  -- X/(F0/K) under a force, X/Y under base motion
  gamma                     REAL NOT NULL,  -- X w^2 / |g|
  impact_J_per_cycle        REAL NOT NULL,
  friction_J_per_cycle      REAL NOT NULL,
  viscous_J_per_cycle       REAL NOT NULL,  -- the host's damper
  loss_factor               REAL NOT NULL,  -- D_cycle / (2 pi 1/2 K X_s^2), X_s the spring's stretch
  apparent_mass_kg          REAL NOT NULL,
  equivalent_damping_N_s_m  REAL NOT NULL,
  particle_mass_kg          REAL NOT NULL,
  wall_time_s               REAL NOT NULL,
  PRIMARY KEY (study_id, point),
  FOREIGN KEY (study_id, point) REFERENCES study_points (study_id, point) ON DELETE CASCADE
) STRICT, WITHOUT ROWID;

CREATE TABLE study_point_states (
  study_id    INTEGER NOT NULL,
  point       INTEGER NOT NULL,
  run_id      INTEGER NOT NULL UNIQUE REFERENCES runs (run_id) ON DELETE CASCADE,
  state_id    INTEGER NOT NULL REFERENCES initial_states (state_id),  -- the spheres at the end
  t_s         REAL NOT NULL,  -- the run's time at its end (whole cycles)
  host_z_m    REAL NOT NULL,
  host_v_m_s  REAL NOT NULL,
  PRIMARY KEY (study_id, point),
  FOREIGN KEY (study_id, point) REFERENCES study_points (study_id, point) ON DELETE CASCADE
) STRICT, WITHOUT ROWID;

)sql";

/// The engines' counters, each with one meaning (EngineCounters), NULL where the run's
/// engine does not keep it: the soft engine's time steps and open contacts, the hard
/// engine's collisions and spheres riding the host. Older samples are mapped by their
/// run's model (steps and contacts of a soft run; events and contacts, which were its
/// riders, of a hard run); a run without spheres ran the host alone and kept none. The
/// views that read samples resolve to the new table by name (legacy_alter_table).
constexpr std::string_view v12_engine_counters = R"sql(
PRAGMA legacy_alter_table = ON;
CREATE TABLE samples_v12 (
  run_id                     INTEGER NOT NULL REFERENCES runs (run_id) ON DELETE CASCADE,
  t_s                        REAL NOT NULL,
  host_z_m                   REAL NOT NULL,
  host_v_m_s                 REAL NOT NULL,
  particle_translational_J   REAL NOT NULL,
  particle_rotational_J      REAL NOT NULL,
  host_kinetic_J             REAL NOT NULL,
  spring_potential_J         REAL NOT NULL,
  gravitational_potential_J  REAL NOT NULL,
  contact_elastic_J          REAL NOT NULL,
  excitation_work_J          REAL NOT NULL,
  dissipated_impact_J        REAL NOT NULL,
  dissipated_friction_J      REAL NOT NULL,
  dissipated_viscous_J       REAL NOT NULL,
  energy_balance_rel_err     REAL NOT NULL,
  time_steps                 INTEGER,  -- cumulative (soft)
  collisions                 INTEGER,  -- cumulative (hard)
  contacts                   INTEGER,  -- open at this instant (soft)
  riding_spheres             INTEGER,  -- riding the host at this instant (hard)
  PRIMARY KEY (run_id, t_s)
) STRICT, WITHOUT ROWID;
INSERT INTO samples_v12
SELECT s.run_id, s.t_s, s.host_z_m, s.host_v_m_s, s.particle_translational_J, s.particle_rotational_J,
       s.host_kinetic_J, s.spring_potential_J, s.gravitational_potential_J, s.contact_elastic_J, s.excitation_work_J,
       s.dissipated_impact_J, s.dissipated_friction_J, s.dissipated_viscous_J, s.energy_balance_rel_err,
       CASE WHEN r.model = 'soft' AND r.n_particles > 0 THEN s.steps END,
       CASE WHEN r.model = 'hard' AND r.n_particles > 0 THEN s.events END,
       CASE WHEN r.model = 'soft' AND r.n_particles > 0 THEN s.contacts END,
       CASE WHEN r.model = 'hard' AND r.n_particles > 0 THEN s.contacts END
FROM samples s LEFT JOIN runs r USING (run_id);
DROP TABLE samples;
ALTER TABLE samples_v12 RENAME TO samples;
PRAGMA legacy_alter_table = OFF;
)sql";

/// Characterisation studies ([characterise]): each point's place (one model and frequency
/// per curve, its points along the amplitude axis), its metrics, and the view with the
/// dimensionless axes. A point's final state goes to study_point_states as an FRF point's.
constexpr std::string_view v13_characterisation = R"sql(
CREATE TABLE study_characterise_points (
  study_id        INTEGER NOT NULL,
  point           INTEGER NOT NULL,
  curve           INTEGER NOT NULL CHECK (curve >= 1),  -- 1, 2, ...: one model and frequency
  model           TEXT NOT NULL CHECK (model IN ('soft', 'hard')),
  empty           INTEGER NOT NULL CHECK (empty IN (0, 1)),  -- the container without particles
  amplitude_m     REAL NOT NULL,  -- A of the container's motion z = A sin(2 pi f t)
  gamma_given     REAL,           -- Gamma as the study file gave it; NULL: it gave A
  frequency_hz    REAL NOT NULL,
  step            INTEGER NOT NULL CHECK (step >= 1),  -- along the amplitude axis, ascending
  previous_point  INTEGER,  -- the point whose final state this one starts from; NULL: the settled bed
  PRIMARY KEY (study_id, point),
  FOREIGN KEY (study_id, point) REFERENCES study_points (study_id, point) ON DELETE CASCADE
) STRICT, WITHOUT ROWID;

CREATE TABLE study_characterise_metrics (
  study_id                         INTEGER NOT NULL,
  point                            INTEGER NOT NULL,
  run_id                           INTEGER NOT NULL UNIQUE REFERENCES runs (run_id) ON DELETE CASCADE,
  settled                          INTEGER NOT NULL CHECK (settled IN (0, 1)),
  cycles_to_steady                 INTEGER NOT NULL,  -- cycles before the measured ones
  cycles_run                       INTEGER NOT NULL,
  measured_cycles                  INTEGER NOT NULL,
  amplitude_m                      REAL NOT NULL,  -- the container's first harmonic, as measured
  gamma                            REAL NOT NULL,  -- A w^2 / |g| (0 without gravity)
  apparent_mass_kg                 REAL NOT NULL,  -- F_p,1 = -m_app z'' - c_eq z'
  apparent_mass_spread_kg          REAL NOT NULL,  -- standard deviation of the measured cycles' own values
  equivalent_damping_N_s_m         REAL NOT NULL,
  equivalent_damping_spread_N_s_m  REAL NOT NULL,
  impact_J_per_cycle               REAL NOT NULL,
  friction_J_per_cycle             REAL NOT NULL,
  loss_factor                      REAL NOT NULL,  -- D_cycle / (2 pi 1/2 m_p (w A)^2); 0 without particles
  floor_contact_fraction           REAL NOT NULL,  -- of 64 instants a measured cycle, a sphere touching the floor
  lid_contact_fraction             REAL NOT NULL,  -- and the lid
  particle_mass_kg                 REAL NOT NULL,
  gravity_m_s2                     REAL NOT NULL,  -- |g|
  free_height_m                    REAL NOT NULL,  -- L: the cavity's height above the settled bed's top
  wall_time_s                      REAL NOT NULL,
  PRIMARY KEY (study_id, point),
  FOREIGN KEY (study_id, point) REFERENCES study_points (study_id, point) ON DELETE CASCADE
) STRICT, WITHOUT ROWID;

CREATE VIEW study_characterisation AS
SELECT p.study_id, p.point, p.status, c.curve, c.model, c.empty, c.amplitude_m, c.gamma_given, c.frequency_hz,
       c.step, c.previous_point, m.run_id, m.settled, m.cycles_to_steady, m.cycles_run, m.measured_cycles,
       m.amplitude_m AS measured_amplitude_m, m.gamma, m.amplitude_m / nullif(m.free_height_m, 0) AS amplitude_ratio,
       m.apparent_mass_kg, m.apparent_mass_spread_kg,
       m.apparent_mass_kg / nullif(m.particle_mass_kg, 0) AS apparent_mass_ratio,
       m.equivalent_damping_N_s_m, m.equivalent_damping_spread_N_s_m,
       m.equivalent_damping_N_s_m / nullif(m.particle_mass_kg * 6.283185307179586 * c.frequency_hz, 0) AS damping_ratio,  -- c_eq / (m_p 2 pi f)
       m.loss_factor, m.impact_J_per_cycle, m.friction_J_per_cycle,
       m.impact_J_per_cycle + m.friction_J_per_cycle AS dissipated_J_per_cycle,
       m.floor_contact_fraction, m.lid_contact_fraction, m.particle_mass_kg, m.gravity_m_s2, m.free_height_m,
       m.wall_time_s
FROM study_points p JOIN study_characterise_points c ON c.study_id = p.study_id AND c.point = p.point
LEFT JOIN study_characterise_metrics m ON m.study_id = p.study_id AND m.point = p.point;
)sql";

/// The runs of a `pdamp compare` under way, until its comparison is stored: what `pdamp
/// resume` needs to complete a comparison that was stopped or killed.
constexpr std::string_view v14_comparison_runs = R"sql(
CREATE TABLE comparison_runs (
  soft_run_id  INTEGER PRIMARY KEY REFERENCES runs (run_id) ON DELETE CASCADE,
  hard_run_id  INTEGER UNIQUE REFERENCES runs (run_id) ON DELETE CASCADE  -- NULL until the hard run begins
) STRICT;
)sql";

/// Frequency responses over a grid of scenario keys ([frf] keys with several values): each
/// point's curve records its values of the grid keys, and the study_frf view, made again
/// after this (study_frf_view), shows them.
constexpr std::string_view v15_frf_grids = R"sql(
ALTER TABLE study_frf_points ADD COLUMN grid TEXT NOT NULL DEFAULT '';  -- 'key = value, ...' of its curve; '': no grid
DROP VIEW study_frf;
)sql";

/// The study_frf view, made by migration 11 and again by migration 15 with the curve's
/// grid values after previous_point: written once, between its two halves.
constexpr std::string_view study_frf_view_head = R"sql(
CREATE VIEW study_frf AS
SELECT p.study_id, p.point, p.status, f.curve, f.model, f.direction, f.host_alone, f.mode, f.level, f.frequency_hz,
       f.step, f.previous_point, )sql";
constexpr std::string_view study_frf_view_tail =
    R"sql(m.run_id, m.settled, m.cycles_to_steady, m.cycles_run, m.measured_cycles,
       m.amplitude_m, m.amplitude_spread_m, m.phase_rad, m.normalised_amplitude, m.gamma, m.impact_J_per_cycle,
       m.friction_J_per_cycle, m.viscous_J_per_cycle,
       m.impact_J_per_cycle + m.friction_J_per_cycle + m.viscous_J_per_cycle AS dissipated_J_per_cycle,
       m.loss_factor, m.apparent_mass_kg, m.apparent_mass_kg / nullif(m.particle_mass_kg, 0) AS apparent_mass_ratio,
       m.equivalent_damping_N_s_m, m.particle_mass_kg, m.wall_time_s
FROM study_points p JOIN study_frf_points f ON f.study_id = p.study_id AND f.point = p.point
LEFT JOIN study_frf_metrics m ON m.study_id = p.study_id AND m.point = p.point;
)sql";

/// A run that starts from a stored bed moved rigidly along the axis (a `start = predict`
/// point of a frequency response) records the move instead of a copy of the moved bed.
constexpr std::string_view v16_bed_shift = R"sql(
ALTER TABLE runs ADD COLUMN bed_shift_z_m REAL;    -- NULL: the bed as stored
ALTER TABLE runs ADD COLUMN bed_shift_v_m_s REAL;  -- with bed_shift_z_m: every sphere's z and vz moved by these
)sql";

/// Γ of a weightless point is NULL, as in cycles: X ω²/|g| is undefined without gravity
/// (before, 0 was stored). The two metrics tables are rebuilt with the column nullable;
/// an [frf] point's stored 0 becomes NULL (a driven host's X is never 0, so Γ was 0 only
/// without gravity), a characterisation point's where its gravity_m_s2 is 0. The views
/// that read them resolve to the new tables by name (legacy_alter_table).
constexpr std::string_view v17_weightless_gamma = R"sql(
PRAGMA legacy_alter_table = ON;
CREATE TABLE study_frf_metrics_v17 (
  study_id                  INTEGER NOT NULL,
  point                     INTEGER NOT NULL,
  run_id                    INTEGER NOT NULL UNIQUE REFERENCES runs (run_id) ON DELETE CASCADE,
  settled                   INTEGER NOT NULL CHECK (settled IN (0, 1)),
  cycles_to_steady          INTEGER NOT NULL,  -- cycles before the measured ones
  cycles_run                INTEGER NOT NULL,
  measured_cycles           INTEGER NOT NULL,
  amplitude_m               REAL NOT NULL,  -- X of the first harmonic over the measured cycles
  amplitude_spread_m        REAL NOT NULL,  -- max - min of the measured cycles' own X
  phase_rad                 REAL NOT NULL,  -- of the host against the excitation; < 0: it lags
  normalised_amplitude      REAL NOT NULL,  -- X/(F0/K) under a force, X/Y under base motion
  gamma                     REAL,           -- X w^2 / |g|; NULL without gravity
  impact_J_per_cycle        REAL NOT NULL,
  friction_J_per_cycle      REAL NOT NULL,
  viscous_J_per_cycle       REAL NOT NULL,  -- the host's damper
  loss_factor               REAL NOT NULL,  -- D_cycle / (2 pi 1/2 K X_s^2), X_s the spring's stretch
  apparent_mass_kg          REAL NOT NULL,
  equivalent_damping_N_s_m  REAL NOT NULL,
  particle_mass_kg          REAL NOT NULL,
  wall_time_s               REAL NOT NULL,
  PRIMARY KEY (study_id, point),
  FOREIGN KEY (study_id, point) REFERENCES study_points (study_id, point) ON DELETE CASCADE
) STRICT, WITHOUT ROWID;
INSERT INTO study_frf_metrics_v17
SELECT study_id, point, run_id, settled, cycles_to_steady, cycles_run, measured_cycles, amplitude_m,
       amplitude_spread_m, phase_rad, normalised_amplitude, nullif(gamma, 0), impact_J_per_cycle, friction_J_per_cycle,
       viscous_J_per_cycle, loss_factor, apparent_mass_kg, equivalent_damping_N_s_m, particle_mass_kg, wall_time_s
FROM study_frf_metrics;
DROP TABLE study_frf_metrics;
ALTER TABLE study_frf_metrics_v17 RENAME TO study_frf_metrics;

CREATE TABLE study_characterise_metrics_v17 (
  study_id                         INTEGER NOT NULL,
  point                            INTEGER NOT NULL,
  run_id                           INTEGER NOT NULL UNIQUE REFERENCES runs (run_id) ON DELETE CASCADE,
  settled                          INTEGER NOT NULL CHECK (settled IN (0, 1)),
  cycles_to_steady                 INTEGER NOT NULL,  -- cycles before the measured ones
  cycles_run                       INTEGER NOT NULL,
  measured_cycles                  INTEGER NOT NULL,
  amplitude_m                      REAL NOT NULL,  -- the container's first harmonic, as measured
  gamma                            REAL,           -- A w^2 / |g|; NULL without gravity
  apparent_mass_kg                 REAL NOT NULL,  -- F_p,1 = -m_app z'' - c_eq z'
  apparent_mass_spread_kg          REAL NOT NULL,  -- standard deviation of the measured cycles' own values
  equivalent_damping_N_s_m         REAL NOT NULL,
  equivalent_damping_spread_N_s_m  REAL NOT NULL,
  impact_J_per_cycle               REAL NOT NULL,
  friction_J_per_cycle             REAL NOT NULL,
  loss_factor                      REAL NOT NULL,  -- D_cycle / (2 pi 1/2 m_p (w A)^2); 0 without particles
  floor_contact_fraction           REAL NOT NULL,  -- of 64 instants a measured cycle, a sphere touching the floor
  lid_contact_fraction             REAL NOT NULL,  -- and the lid
  particle_mass_kg                 REAL NOT NULL,
  gravity_m_s2                     REAL NOT NULL,  -- |g|
  free_height_m                    REAL NOT NULL,  -- L: the cavity's height above the settled bed's top
  wall_time_s                      REAL NOT NULL,
  PRIMARY KEY (study_id, point),
  FOREIGN KEY (study_id, point) REFERENCES study_points (study_id, point) ON DELETE CASCADE
) STRICT, WITHOUT ROWID;
INSERT INTO study_characterise_metrics_v17
SELECT study_id, point, run_id, settled, cycles_to_steady, cycles_run, measured_cycles, amplitude_m,
       CASE WHEN gravity_m_s2 > 0 THEN gamma END, apparent_mass_kg, apparent_mass_spread_kg, equivalent_damping_N_s_m,
       equivalent_damping_spread_N_s_m, impact_J_per_cycle, friction_J_per_cycle, loss_factor, floor_contact_fraction,
       lid_contact_fraction, particle_mass_kg, gravity_m_s2, free_height_m, wall_time_s
FROM study_characterise_metrics;
DROP TABLE study_characterise_metrics;
ALTER TABLE study_characterise_metrics_v17 RENAME TO study_characterise_metrics;
PRAGMA legacy_alter_table = OFF;
)sql";

std::string study_frf_view(std::string_view grid_column) {
  return std::string(study_frf_view_head) + std::string(grid_column) + std::string(study_frf_view_tail);
}

}  // namespace

std::span<const std::string_view> migrations() {
  static const std::string v11 = std::string(v11_frf_studies) + study_frf_view("");
  static const std::string v15 = std::string(v15_frf_grids) + study_frf_view("f.grid, ");
  static const std::array<std::string_view, 17> all{v1_runs_samples_cycles,
                                                    v2_run_statistics,
                                                    v3_initial_states,
                                                    v4_comparisons,
                                                    v5_solid_fraction,
                                                    v6_run_ids_never_reused,
                                                    v7_run_snapshots,
                                                    v8_studies,
                                                    v9_study_jobs,
                                                    v10_run_checkpoints,
                                                    v11,
                                                    v12_engine_counters,
                                                    v13_characterisation,
                                                    v14_comparison_runs,
                                                    v15,
                                                    v16_bed_shift,
                                                    v17_weightless_gamma};
  return all;
}

}  // namespace pdamp::schema
