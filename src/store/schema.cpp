/// The SQL schema of the run store, as an ordered list of migrations. Never edit a
/// migration that has shipped: add a new one. Column names carry their units.
#include "schema.hpp"

#include <array>

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

constexpr std::array<std::string_view, 3> all{v1_runs_samples_cycles, v2_run_statistics, v3_initial_states};

}  // namespace

std::span<const std::string_view> migrations() { return all; }

}  // namespace pdamp::schema
