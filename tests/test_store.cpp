#include <doctest/doctest.h>

#include <fstream>

#include "../src/store/schema.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/store/run_store.hpp"
#include "test_support.hpp"

using namespace pdamp;

namespace {

NewRun a_run() { return {"soft", "unit", "[host]\nmass_kg = 1\n", 7, 10, 1.0, 2.5e-6, std::nullopt}; }

Observation sample_at(double t) {
  Observation o;
  o.t_s = t;
  o.host = {0.001 * t, 0.5};
  o.energy.dissipated_impact_J = t;
  o.energy.dissipated_friction_J = 2 * t;
  o.energy.dissipated_viscous_J = 3 * t;
  o.counters.contacts = 12;
  return o;
}

}  // namespace

TEST_CASE("a new store gets the current schema in WAL mode") {
  test::TempDir dir("store-new");
  RunStore store(dir / "runs.sqlite");
  sqlite::Statement version(store.database(), "PRAGMA user_version");
  REQUIRE(version.step());
  CHECK(version.column_int(0) == RunStore::schema_version());
  sqlite::Statement mode(store.database(), "PRAGMA journal_mode");
  REQUIRE(mode.step());
  CHECK(mode.column_text(0) == "wal");
  sqlite::Statement keys(store.database(), "PRAGMA foreign_keys");
  REQUIRE(keys.step());
  CHECK(keys.column_int(0) == 1);
}

TEST_CASE("runs, samples and cycles round-trip through the public tables and view") {
  test::TempDir dir("store-roundtrip");
  RunStore store(dir / "runs.sqlite");
  const auto id = store.begin_run(a_run());
  {
    RunWriter writer(store, id);
    for (int i = 0; i <= 100; ++i) writer.record_sample(sample_at(i * 0.01), 1e-6 * i);
    CycleRecord c;
    c.cycle = 1;
    c.t_end_s = 0.05;
    c.amplitude_m = 0.01;
    c.freq_hz = 20;
    c.psi = 0.3;
    c.psi_impact = 0.2;
    c.psi_friction = 0.1;
    c.max_host_kinetic_J = 0.01;
    writer.record_cycle(c);
  }
  auto summary = store.summary(id);
  REQUIRE(summary);
  CHECK(summary->status == "running");
  CHECK(summary->n_samples == 101);
  CHECK(summary->n_cycles == 1);
  CHECK(*summary->dissipated_friction_J == doctest::Approx(2.0));
  store.finish_run(id, {RunStatus::completed, "", 1.0, 0.5, 0.05, 1e-4});
  summary = store.summary(id);
  CHECK(summary->status == "completed");
  CHECK(*summary->wall_time_s == 0.5);
  CHECK(*summary->energy_balance_rel_err == 1e-4);
  CHECK(store.list_runs().size() == 1);
  store.save_statistics(id, {{"events_wall", 12}, {"events_sphere_sphere", 40}});
  store.save_statistics(id, {{"events_wall", 13}});
  const EngineStatistics stats = store.statistics(id);
  REQUIRE(stats.size() == 2);
  CHECK(stats[0] == std::pair<std::string, std::int64_t>{"events_sphere_sphere", 40});
  CHECK(stats[1] == std::pair<std::string, std::int64_t>{"events_wall", 13});
  sqlite::Statement gamma(store.database(), "SELECT gamma IS NULL, seed, dt_s FROM cycles JOIN runs USING (run_id)");
  REQUIRE(gamma.step());
  CHECK(gamma.column_int(0) == 1);
  CHECK(gamma.column_int(1) == 7);
  CHECK(gamma.column_double(2) == 2.5e-6);
  // Foreign keys hold: samples of an unknown run are refused.
  CHECK_THROWS_AS(store.database().exec("INSERT INTO samples (run_id, t_s, host_z_m, host_v_m_s, "
                                        "particle_translational_J, particle_rotational_J, host_kinetic_J, "
                                        "spring_potential_J, gravitational_potential_J, contact_elastic_J, "
                                        "excitation_work_J, dissipated_impact_J, dissipated_friction_J, "
                                        "dissipated_viscous_J, energy_balance_rel_err, contacts, events, steps) "
                                        "VALUES (99, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)"),
                  RuntimeFailure);
}

TEST_CASE("two stores on one file write runs concurrently") {
  test::TempDir dir("store-concurrent");
  RunStore first(dir / "runs.sqlite");
  RunStore second(dir / "runs.sqlite");
  const auto a = first.begin_run(a_run());
  const auto b = second.begin_run(a_run());
  {
    RunWriter wa(first, a, std::chrono::milliseconds(0));
    RunWriter wb(second, b, std::chrono::milliseconds(0));
    for (int i = 0; i < 50; ++i) {
      wa.record_sample(sample_at(i), 0);
      wb.record_sample(sample_at(i), 0);
    }
  }
  CHECK(first.summary(b)->n_samples == 50);
  CHECK(second.summary(a)->n_samples == 50);
}

TEST_CASE("a store written by a newer pdamp, or a foreign database, is refused") {
  test::TempDir dir("store-refuse");
  {
    sqlite::Database db(dir / "newer.sqlite");
    db.exec("PRAGMA user_version = 999");
  }
  CHECK_THROWS_WITH_AS(RunStore(dir / "newer.sqlite"), doctest::Contains("newer"), InputError);
  {
    sqlite::Database db(dir / "foreign.sqlite");
    db.exec("CREATE TABLE things (x)");
  }
  CHECK_THROWS_WITH_AS(RunStore(dir / "foreign.sqlite"), doctest::Contains("did not create"), InputError);
  {
    std::ofstream text(dir / "text.sqlite");
    text << "this is not a database, just some text that is long enough to fill a header page.............\n";
  }
  CHECK_THROWS_AS(RunStore(dir / "text.sqlite"), InputError);
}

TEST_CASE("an older store is migrated forward and keeps its runs") {
  test::TempDir dir("store-migrate");
  const auto file = dir / "old.sqlite";
  std::int64_t id = 0;
  {
    // A store as the first schema left it, with one run.
    sqlite::Database v1(file);
    v1.exec(schema::migrations()[0]);
    v1.exec("PRAGMA user_version = 1");
    v1.exec(
        "INSERT INTO runs (model, scenario_name, scenario_text, seed, n_particles, duration_s, pdamp_version, "
        "status, started_at) VALUES ('soft', 'old', '', 1, 0, 1.0, '0.0.1', 'completed', '2026-01-01T00:00:00Z')");
    id = v1.last_insert_rowid();
  }
  RunStore store(file);
  sqlite::Statement version(store.database(), "PRAGMA user_version");
  REQUIRE(version.step());
  CHECK(version.column_int(0) == RunStore::schema_version());
  CHECK(store.summary(id).has_value());
  CHECK_NOTHROW(store.save_statistics(id, {{"steps", 1}}));
}
