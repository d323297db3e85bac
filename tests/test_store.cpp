#include <doctest/doctest.h>

#include <atomic>
#include <fstream>
#include <sstream>
#include <thread>

#include "../src/store/schema.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/model/host_only_engine.hpp"
#include "pdamp/sim/run.hpp"
#include "pdamp/store/run_store.hpp"
#include "pdamp/store/study_store.hpp"
#include "test_support.hpp"

using namespace pdamp;

namespace {

NewRun a_run() { return {"soft", "unit", "[host]\nmass_kg = 1\n", 7, 10, 1.0}; }

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

CycleRecord cycle_number(int n) {
  CycleRecord c;
  c.cycle = n;
  c.t_start_s = 0.05 * (n - 1);
  c.t_end_s = 0.05 * n;
  c.amplitude_m = 0.01 / n;
  c.freq_hz = 20;
  c.psi = 0.3;
  c.max_host_kinetic_J = 0.01;
  return c;
}

std::int64_t scalar(sqlite::Database& db, const std::string& sql) {
  sqlite::Statement query(db, sql);
  REQUIRE(query.step());
  return query.column_int(0);
}

/// A store file as schema `version` left it: its migrations run, its user_version set.
void make_store_of_schema(sqlite::Database& db, int version) {
  for (int v = 0; v < version; ++v) db.exec(schema::migrations()[static_cast<std::size_t>(v)]);
  db.exec("PRAGMA user_version = " + std::to_string(version));
}

/// A store file of schema `version` in `dir` with the rows `old_rows` insert, as that
/// pdamp wrote them.
std::filesystem::path store_of_schema(const test::TempDir& dir, int version, const std::vector<std::string>& old_rows) {
  const auto file = dir / ("v" + std::to_string(version) + ".sqlite");
  sqlite::Database db(file);
  make_store_of_schema(db, version);
  for (const std::string& row : old_rows) db.exec(row);
  return file;
}

std::string file_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

/// Makes `table`'s root page unreadable (an invalid b-tree page type) in a closed store.
void damage_root_page(const std::filesystem::path& file, const std::string& table) {
  std::int64_t root = 0, page_size = 0;
  {
    sqlite::Database db(file);
    root = scalar(db, "SELECT rootpage FROM sqlite_schema WHERE name = '" + table + "'");
    page_size = scalar(db, "PRAGMA page_size");
  }
  std::fstream bytes(file, std::ios::in | std::ios::out | std::ios::binary);
  bytes.seekp((root - 1) * page_size + (root == 1 ? 100 : 0));
  bytes.put('\x63');
}

/// A store with two runs (samples, cycles, statistics; a calibration of the second), a
/// comparison of the two and a settled bed.
void store_two_runs(RunStore& store) {
  for (int r = 0; r < 2; ++r) {
    const auto id = store.begin_run(a_run());
    RunWriter writer(store, id);
    for (int i = 0; i < 10; ++i) writer.record_sample(sample_at(0.01 * i), 0.0);
    writer.record_cycle(cycle_number(1));
    writer.flush();
    store.save_statistics(id, {{"steps", 10}});
    store.finish_run(id, {RunStatus::completed, "", 0.09, 0.1, 0.05, 1e-9});
  }
  store.save_calibration(2, {{{0.1}, {0.7}, {0.3}}, {{0.1}, {0.8}, {0.3}}});
  ComparisonRecord c;
  c.scenario_name = "unit";
  c.soft_run_id = 1;
  c.hard_run_id = 2;
  c.hard_restitution = "constant";
  c.psi_bins.push_back({1.0, 2.0, 0.3, 0.3, 1, 1});
  c.energy.push_back({0.09, "soft", 0.1, 0.2, 0.3});
  store.save_comparison(c);
  store.save_initial_state("key", test::spheres({{0, 0, 0.001}}, {{0, 0, 0}}), 0.5, 0.0, 1.0);
}

}  // namespace

TEST_CASE("a new store gets the current schema in WAL mode") {
  test::TempDir dir("store-new");
  RunStore store(dir / "runs.sqlite");
  sqlite::Database db(store.file());  // a second connection: the store's own is private
  sqlite::Statement version(db, "PRAGMA user_version");
  REQUIRE(version.step());
  CHECK(version.column_int(0) == RunStore::schema_version());
  sqlite::Statement mode(db, "PRAGMA journal_mode");
  REQUIRE(mode.step());
  CHECK(mode.column_text(0) == "wal");
  sqlite::Statement keys(db, "PRAGMA foreign_keys");
  REQUIRE(keys.step());
  CHECK(keys.column_int(0) == 1);
}

TEST_CASE("a run another process deleted while it ran: its writes fail naming that, not on a foreign key") {
  test::TempDir dir("store-deleted-run");
  RunStore store(dir / "runs.sqlite");
  const auto id = store.begin_run(a_run());
  store.start_run(id, {2.5e-6, std::nullopt, 0.1});
  const std::int64_t ids[] = {id};
  RunStore(dir / "runs.sqlite").delete_runs(ids, true);
  const std::string why = "run " + std::to_string(id) + " is no longer in the store";
  const SampleRecord samples[] = {{sample_at(0.0), 0.0}};
  CHECK_THROWS_WITH_AS(store.append_results(id, samples, {}, nullptr), doctest::Contains(why.c_str()), RuntimeFailure);
  CHECK_THROWS_WITH_AS(store.save_statistics(id, {{"events", 1}}), doctest::Contains(why.c_str()), RuntimeFailure);
  // Its end would otherwise update no row, silently.
  CHECK_THROWS_WITH_AS(store.finish_run(id, RunEnd{}), doctest::Contains(why.c_str()), RuntimeFailure);
}

TEST_CASE("runs, samples and cycles round-trip through the public tables and view") {
  test::TempDir dir("store-roundtrip");
  RunStore store(dir / "runs.sqlite");
  const auto id = store.begin_run(a_run());
  store.start_run(id, {2.5e-6, std::nullopt, 0.1});
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
  CHECK(*summary->dissipated_friction_J == doctest::Approx(2.0).scale(1.0));
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
  sqlite::Database db(store.file());
  sqlite::Statement gamma(db, "SELECT gamma IS NULL, seed, dt_s FROM cycles JOIN runs USING (run_id)");
  REQUIRE(gamma.step());
  CHECK(gamma.column_int(0) == 1);
  CHECK(gamma.column_int(1) == 7);
  CHECK(gamma.column_double(2) == 2.5e-6);
  // Foreign keys hold: samples of an unknown run are refused.
  CHECK_THROWS_AS(db.exec("INSERT INTO samples (run_id, t_s, host_z_m, host_v_m_s, "
                          "particle_translational_J, particle_rotational_J, host_kinetic_J, "
                          "spring_potential_J, gravitational_potential_J, contact_elastic_J, "
                          "excitation_work_J, dissipated_impact_J, dissipated_friction_J, "
                          "dissipated_viscous_J, energy_balance_rel_err, time_steps, collisions, contacts, "
                          "riding_spheres) VALUES (99, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)"),
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
    RunStore store(dir / "newer.sqlite");
    sqlite::Database(store.file()).exec("PRAGMA user_version = 999");
  }
  CHECK_THROWS_WITH_AS(RunStore(dir / "newer.sqlite"), doctest::Contains("newer"), InputError);
  {
    sqlite::Database db(dir / "foreign.sqlite");
    db.exec("CREATE TABLE things (x)");
  }
  CHECK_THROWS_WITH_AS(RunStore(dir / "foreign.sqlite"), doctest::Contains("another program's SQLite database"),
                       InputError);
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
    make_store_of_schema(v1, 1);
    v1.exec(
        "INSERT INTO runs (model, scenario_name, scenario_text, seed, n_particles, duration_s, pdamp_version, "
        "status, started_at) VALUES ('soft', 'old', '', 1, 0, 1.0, '0.0.1', 'completed', '2026-01-01T00:00:00Z')");
    id = v1.last_insert_rowid();
  }
  RunStore store(file);
  sqlite::Database db(file);
  sqlite::Statement version(db, "PRAGMA user_version");
  REQUIRE(version.step());
  CHECK(version.column_int(0) == RunStore::schema_version());
  CHECK(store.summary(id).has_value());
  CHECK_NOTHROW(store.save_statistics(id, {{"steps", 1}}));
}

TEST_CASE("a run's writer holds no lock while the engine computes, and writes in short transactions") {
  test::TempDir dir("store-writer");
  const auto file = dir / "runs.sqlite";
  RunStore store(file);
  const auto id = store.begin_run(a_run());
  RunWriter writer(store, id, std::chrono::hours(1));  // never due: everything waits in memory
  for (int i = 0; i < 100; ++i) writer.record_sample(sample_at(i * 1e-3), 0.0);
  writer.record_cycle(cycle_number(1));
  // Another connection that will not wait takes the write lock at once.
  sqlite::Database other(file, sqlite::Access::read_write, std::chrono::milliseconds(0));
  CHECK_NOTHROW(other.exec("BEGIN IMMEDIATE; COMMIT"));
  CHECK(store.summary(id)->n_samples == 0);
  writer.flush();
  CHECK(store.summary(id)->n_samples == 100);
  CHECK(store.summary(id)->n_cycles == 1);
  // However soon, the rows waiting are bounded: 16384 are written at once.
  for (int i = 100; i < 16384 + 100; ++i) writer.record_sample(sample_at(i * 1e-3), 0.0);
  CHECK(store.summary(id)->n_samples == 16384 + 100);
}

TEST_CASE("a write waits for another connection's transaction, and past the limit fails saying why") {
  test::TempDir dir("store-busy");
  const auto file = dir / "runs.sqlite";
  { const RunStore created(file); }
  sqlite::Database holder(file);
  holder.exec("BEGIN IMMEDIATE");
  StoreOptions patient_briefly;
  patient_briefly.busy_limit = std::chrono::milliseconds(300);
  RunStore store(file, StoreAccess::write, patient_briefly);
  const auto start = std::chrono::steady_clock::now();
  CHECK_THROWS_WITH_AS(store.begin_run(a_run()),
                       doctest::Contains("stayed locked by another connection for longer than the 0.3 s pdamp waits"),
                       sqlite::Busy);
  CHECK(std::chrono::steady_clock::now() - start >= std::chrono::milliseconds(300));
  CHECK(store.list_runs().empty());
  // Released while the write waits: it goes through.
  std::thread release([&holder] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    holder.exec("COMMIT");
  });
  CHECK(store.begin_run(a_run()) == 1);
  release.join();
}

TEST_CASE("a run whose results cannot be stored ends failed and says why") {
  test::TempDir dir("store-busy-run");
  const auto file = dir / "runs.sqlite";
  StoreOptions patient_briefly;
  patient_briefly.busy_limit = std::chrono::milliseconds(200);
  RunStore store(file, StoreAccess::write, patient_briefly);
  const auto id = store.begin_run(a_run());
  const Scenario scenario = test::scenario_from("[particles]\ncount = 0\n[run]\nduration_s = 0.05\n");
  HostOnlyEngine engine(scenario);
  sqlite::Database holder(file);
  holder.exec("BEGIN IMMEDIATE");
  RunWriter writer(store, id, std::chrono::milliseconds(0));
  const RunOutcome outcome = run_simulation(engine, scenario, writer);
  holder.exec("ROLLBACK");
  CHECK(outcome.status == RunStatus::failed);
  CHECK(outcome.message.find("results not all stored") != std::string::npos);
  CHECK(outcome.message.find("stayed locked") != std::string::npos);
}

TEST_CASE("threads, each with its own connection, write runs into one store while another thread reads") {
  test::TempDir dir("store-threads");
  const auto file = dir / "runs.sqlite";
  { const RunStore created(file); }
  constexpr int threads = 8, samples = 300, cycles = 6;
  std::atomic<int> failures{0}, writing{threads};
  std::vector<std::thread> writers;
  writers.reserve(threads);
  for (int t = 0; t < threads; ++t) {
    writers.emplace_back([&] {
      try {
        RunStore store(file);
        const auto id = store.begin_run(a_run());
        RunWriter writer(store, id, std::chrono::milliseconds(0));  // a transaction per row: the most contention
        for (int i = 0; i < samples; ++i) {
          writer.record_sample(sample_at(i * 1e-3), 0.0);
          if ((i + 1) % (samples / cycles) == 0) writer.record_cycle(cycle_number((i + 1) / (samples / cycles)));
        }
        writer.flush();
        store.finish_run(id, {RunStatus::completed, "", 0.3, 0.1, 0.05, 1e-9});
      } catch (const std::exception& e) {
        MESSAGE(e.what());
        ++failures;
      }
      --writing;
    });
  }
  int reads = 0, read_failures = 0;
  RunStore reader(file, StoreAccess::read);
  while (writing > 0) {
    try {
      reader.list_runs();
      ++reads;
    } catch (const std::exception& e) {
      MESSAGE(e.what());
      ++read_failures;
    }
  }
  for (auto& w : writers) w.join();
  CHECK(failures == 0);
  CHECK(read_failures == 0);
  CHECK(reads > 0);
  const auto runs = reader.list_runs();
  REQUIRE(runs.size() == threads);
  for (const auto& run : runs) {
    CAPTURE(run.run_id);
    CHECK(run.status == "completed");
    CHECK(run.n_samples == samples);
    CHECK(run.n_cycles == cycles);
  }
}

TEST_CASE("a file is examined before anything is written to it") {
  test::TempDir dir("store-examine");
  SUBCASE("another program's database is left as it was") {
    const auto file = dir / "foreign.sqlite";
    {
      sqlite::Database db(file);
      db.exec("CREATE TABLE things (x); INSERT INTO things VALUES (1)");
    }
    const std::string before = file_bytes(file);
    for (const StoreAccess access : {StoreAccess::read, StoreAccess::modify, StoreAccess::write}) {
      CHECK_THROWS_WITH_AS(RunStore(file, access), doctest::Contains("tables things); give another --db"), InputError);
    }
    CHECK(file_bytes(file) == before);
    CHECK_FALSE(std::filesystem::exists(dir / "foreign.sqlite-wal"));
  }
  SUBCASE("an empty file is a store only for writing") {
    const auto file = dir / "empty.sqlite";
    { std::ofstream created(file); }
    CHECK_THROWS_WITH_AS(RunStore(file, StoreAccess::read), doctest::Contains("is empty"), InputError);
    CHECK_THROWS_WITH_AS(RunStore(file, StoreAccess::modify), doctest::Contains("is empty"), InputError);
    CHECK(std::filesystem::file_size(file) == 0);
    { const RunStore created(file); }
    CHECK(RunStore(file, StoreAccess::read).list_runs().empty());
  }
  SUBCASE("a missing file is not created for reading") {
    const auto file = dir / "missing.sqlite";
    CHECK_THROWS_WITH_AS(RunStore(file, StoreAccess::read), doctest::Contains("does not exist"), InputError);
    CHECK_FALSE(std::filesystem::exists(file));
  }
  SUBCASE("a directory or a text file is not a store") {
    CHECK_THROWS_WITH_AS(RunStore(dir.path()), doctest::Contains("is not a file"), InputError);
    std::ofstream(dir / "text.sqlite") << "name,value\n";
    CHECK_THROWS_WITH_AS(RunStore(dir / "text.sqlite"), doctest::Contains("not an SQLite database"), InputError);
  }
  SUBCASE("reading a store does not write it") {
    const auto file = dir / "runs.sqlite";
    {
      RunStore store(file);
      store_two_runs(store);
    }
    const std::string before = file_bytes(file);
    RunStore store(file, StoreAccess::read);
    CHECK(store.list_runs().size() == 2);
    CHECK(store.summary(1)->n_samples == 10);
    CHECK(store.statistics(1).size() == 1);
    CHECK(file_bytes(file) == before);
    CHECK_THROWS_AS(store.begin_run(a_run()), sqlite::NotWritable);
  }
}

TEST_CASE("a damaged store is refused on open, or where it is read, with a clear message") {
  test::TempDir dir("store-damaged");
  const auto file = dir / "runs.sqlite";
  auto make_store = [&] {
    std::filesystem::remove(file);
    RunStore store(file);
    store_two_runs(store);
  };
  SUBCASE("a small store is checked whole") {
    for (const std::string table : {"runs", "samples", "initial_particles"}) {
      CAPTURE(table);
      make_store();
      damage_root_page(file, table);
      for (const StoreAccess access : {StoreAccess::read, StoreAccess::write}) {
        CHECK_THROWS_WITH_AS(RunStore(file, access), doctest::Contains("is damaged ("), InputError);
      }
    }
  }
  SUBCASE("a large store: its run tables on open, its samples as they are read") {
    StoreOptions large;
    large.full_check_limit_bytes = 0;
    make_store();
    damage_root_page(file, "run_statistics");
    CHECK_THROWS_WITH_AS(RunStore(file, StoreAccess::read, large), doctest::Contains("is damaged"), InputError);
    make_store();
    damage_root_page(file, "samples");
    RunStore store(file, StoreAccess::read, large);
    try {
      store.list_runs();
      FAIL("a damaged samples table was read");
    } catch (const sqlite::Damaged& e) {
      const std::string message = e.what();
      CHECK(message.find("is damaged (SQLite: database disk image is malformed)") != std::string::npos);
      CHECK(message.find(".recover") != std::string::npos);
      CHECK(message.find("SELECT") == std::string::npos);
    }
  }
}

TEST_CASE("delete_runs removes runs with every row that refers to them, all or nothing") {
  test::TempDir dir("store-delete");
  RunStore store(dir / "runs.sqlite");
  store_two_runs(store);
  sqlite::Database db(store.file());
  auto rows_of = [&](const std::string& table, const std::string& column = "run_id") {
    return scalar(db, "SELECT count(*) FROM " + table + " WHERE " + column + " = 2");
  };
  const std::vector<std::int64_t> unknown{2, 7};
  CHECK_THROWS_WITH_AS(store.delete_runs(unknown, false), doctest::Contains("run 7 is not in"), InputError);
  CHECK(rows_of("runs") == 1);
  const auto running = store.begin_run(a_run());
  const std::vector<std::int64_t> live{running};
  CHECK_THROWS_WITH_AS(store.delete_runs(live, false), doctest::Contains("is running"), InputError);

  store.save_snapshots(2, {"/frames/run-2", "/frames/run-2/run-2.pvd", 0.01, 11});
  const std::vector<std::int64_t> both{2, running, 2};
  const auto deleted = store.delete_runs(both, true);
  REQUIRE(deleted.size() == 2);
  CHECK(deleted[0].run.run_id == 2);
  CHECK(deleted[0].run.n_samples == 10);
  CHECK(deleted[0].comparisons == 1);
  for (const auto& table : {"runs", "samples", "cycles", "run_statistics", "calibrations", "run_snapshots"}) {
    CAPTURE(table);
    CHECK(rows_of(table) == 0);
  }
  CHECK(scalar(db, "SELECT count(*) FROM comparisons") == 0);
  CHECK(scalar(db, "SELECT count(*) FROM comparison_psi_bins") == 0);
  CHECK(scalar(db, "SELECT count(*) FROM comparison_energy") == 0);
  // The other run and the settled bed stay.
  CHECK(store.summary(1)->n_samples == 10);
  CHECK(scalar(db, "SELECT count(*) FROM initial_particles") == 1);
  // The deleted ids are never used again.
  CHECK(store.begin_run(a_run()) == running + 1);
}

TEST_CASE("where a run's snapshots are: none, recorded, then updated with the frames written") {
  test::TempDir dir("store-snapshots");
  RunStore store(dir / "runs.sqlite");
  const auto id = store.begin_run(a_run());
  CHECK_FALSE(store.snapshots(id));
  store.save_snapshots(id, {"/frames/run-1", "/frames/run-1/run-1.pvd", 0.01, 0});
  store.save_snapshots(id, {"/frames/run-1", "/frames/run-1/run-1.pvd", 0.01, 151});
  const auto s = store.snapshots(id);
  REQUIRE(s);
  CHECK(s->folder == "/frames/run-1");
  CHECK(s->collection == "/frames/run-1/run-1.pvd");
  CHECK(s->interval_s == 0.01);
  CHECK(s->frames == 151);
  sqlite::Database db(store.file());
  CHECK(scalar(db, "SELECT count(*) FROM run_snapshots") == 1);
  CHECK_THROWS_AS(store.save_snapshots(id, {"/f", "/f/r.pvd", 0.0, 1}), std::exception);  // interval_s > 0
}

TEST_CASE("a store of schema 5 is migrated: every row kept, and run ids beyond any left behind") {
  test::TempDir dir("store-migrate-5");
  const auto file = dir / "v5.sqlite";
  {
    sqlite::Database v5(file);
    v5.exec("PRAGMA journal_mode = WAL");
    make_store_of_schema(v5, 5);
  }
  {
    // What pdamp 5 wrote: two runs and their rows, a third deleted by hand in the sqlite3
    // shell (foreign keys off) with its samples left behind.
    sqlite::Database v5(file);
    for (int r = 1; r <= 3; ++r) {
      v5.exec(
          "INSERT INTO runs (model, scenario_name, scenario_text, seed, n_particles, duration_s, pdamp_version, "
          "status, started_at) VALUES ('soft', 'old', '', 1, 0, 1.0, '0.1.0', 'completed', '2026-01-01')");
      v5.exec("INSERT INTO samples VALUES (" + std::to_string(r) +
              ", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)");
      v5.exec("INSERT INTO cycles VALUES (" + std::to_string(r) + ", 1, 0, 0.05, 0.01, 20, 1, 0.3, 0.2, 0.1, 0, 0.01)");
    }
    v5.exec("INSERT INTO run_statistics VALUES (1, 'steps', 5)");
    v5.exec(
        "INSERT INTO comparisons (scenario_name, soft_run_id, hard_run_id, hard_restitution, created_at) "
        "VALUES ('old', 1, 2, 'constant', '2026-01-01')");
    v5.exec("PRAGMA foreign_keys = OFF; DELETE FROM runs WHERE run_id = 3");
  }
  RunStore store(file);
  sqlite::Database db(store.file());
  CHECK(scalar(db, "PRAGMA user_version") == RunStore::schema_version());
  CHECK(scalar(db, "PRAGMA application_id") == 1885626733);
  CHECK(scalar(db, "SELECT count(*) FROM runs") == 2);
  CHECK(scalar(db, "SELECT count(*) FROM samples") == 3);
  CHECK(scalar(db, "SELECT count(*) FROM cycles") == 3);
  CHECK(scalar(db, "SELECT count(*) FROM run_statistics") == 1);
  CHECK(scalar(db, "SELECT count(*) FROM comparisons") == 1);
  CHECK(scalar(db, "SELECT count(*) FROM run_summary WHERE n_samples = 1 AND n_cycles = 1") == 2);
  CHECK(scalar(db, "SELECT count(*) FROM pragma_foreign_key_list('samples') WHERE \"table\" = 'runs'") == 1);
  // Run 3's samples are still there: the next run is 4, and its rows go in.
  const auto id = store.begin_run(a_run());
  CHECK(id == 4);
  RunWriter writer(store, id);
  writer.record_sample(sample_at(0.0), 0.0);
  CHECK_NOTHROW(writer.flush());
}

TEST_CASE("a store of schema 11 is migrated: each run's counters go to the columns of its engine") {
  test::TempDir dir("store-migrate-11");
  const auto file = dir / "v11.sqlite";
  {
    // Before schema 12, a sample held contacts, events and steps for every engine:
    // contacts open (soft) or spheres riding the host (hard). Here 4, 5 and 6 for a soft
    // run, a hard run and a run of the host alone (no spheres).
    sqlite::Database v11(file);
    make_store_of_schema(v11, 11);
    for (const char* run : {"'soft', 10", "'hard', 10", "'hard', 0"}) {
      v11.exec(
          "INSERT INTO runs (model, n_particles, scenario_name, scenario_text, seed, duration_s, pdamp_version, "
          "status, started_at) VALUES (" +
          std::string(run) + ", 'old', '', 1, 1.0, '0.1.0', 'completed', '2026-01-01')");
      v11.exec("INSERT INTO samples VALUES (last_insert_rowid(), 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 4, 5, 6)");
    }
  }
  RunStore store(file);
  sqlite::Database db(store.file());
  CHECK(scalar(db, "PRAGMA user_version") == RunStore::schema_version());
  const auto counters = [&](int run) { return store.results(run).samples.at(0).observation.counters; };
  CHECK(counters(1) == EngineCounters{6, std::nullopt, 4, std::nullopt});
  CHECK(counters(2) == EngineCounters{std::nullopt, 5, std::nullopt, 4});
  CHECK(counters(3) == EngineCounters{});
  CHECK(scalar(db, "SELECT count(*) FROM run_summary WHERE n_samples = 1") == 3);
  CHECK(scalar(db, "SELECT count(*) FROM pragma_foreign_key_list('samples') WHERE \"table\" = 'runs'") == 1);
  // What the engines store now reads back, NULL where an engine keeps no counter.
  const auto id = store.begin_run(a_run());
  Observation o = sample_at(0.0);
  o.counters = {7, std::nullopt, 3, std::nullopt};
  {
    RunWriter writer(store, id);
    writer.record_sample(o, 0.0);
  }
  CHECK(store.results(id).samples.at(0).observation.counters == o.counters);
  CHECK(scalar(db, "SELECT count(*) FROM samples WHERE run_id = " + std::to_string(id) +
                       " AND collisions IS NULL AND riding_spheres IS NULL") == 1);
}

TEST_CASE("a store of schema 15 is migrated: its runs started from their beds as stored, without a shift") {
  test::TempDir dir("store-migrate-15");
  RunStore store(store_of_schema(
      dir, 15,
      {"INSERT INTO runs (model, scenario_name, scenario_text, seed, n_particles, duration_s, pdamp_version, status, "
       "started_at) VALUES ('hard', 'old', '', 1, 0, 0.1, '0.1.0', 'completed', '2026-01-01')"}));
  sqlite::Database db(store.file());
  CHECK(scalar(db, "PRAGMA user_version") == RunStore::schema_version());
  CHECK(scalar(db, "SELECT count(*) FROM runs WHERE bed_shift_z_m IS NULL AND bed_shift_v_m_s IS NULL") == 1);
}

TEST_CASE("a store of schema 16 is migrated: a weightless point's Gamma, stored as 0, is NULL, the others kept") {
  test::TempDir dir("store-migrate-16");
  std::vector<std::string> rows{
      "INSERT INTO studies (name, models, n_points, study_file, study_text, scenario_file, scenario_text, "
      "pdamp_version, created_at) VALUES ('old', 'hard', 4, 'a', 'b', 'c', 'd', '0.1.0', '2026-01-01')"};
  for (int point = 1; point <= 4; ++point) {
    const std::string p = std::to_string(point);
    rows.push_back(
        "INSERT INTO runs (model, scenario_name, scenario_text, seed, n_particles, duration_s, "
        "pdamp_version, status, started_at) VALUES ('hard', 'old/" +
        p + "', '', 1, 0, 0.1, '0.1.0', 'completed', '2026-01-01')");
    rows.push_back("INSERT INTO study_points (study_id, point, section, status) VALUES (1, " + p + ", '" +
                   (point <= 2 ? "frf" : "characterise") + "', 'completed')");
  }
  // Points 1 and 2 of an [frf] study, weightless and not; 3 and 4 of a characterisation.
  for (const auto& [point, gamma] : {std::pair{1, "0"}, std::pair{2, "1.5"}}) {
    rows.push_back("INSERT INTO study_frf_metrics VALUES (1, " + std::to_string(point) + ", " + std::to_string(point) +
                   ", 1, 10, 20, 10, 0.001, 0, -0.1, 2.0, " + gamma + ", 0, 0, 0.01, 0.02, 0.004, 0.1, 0.004, 1.0)");
  }
  for (const auto& [point, gravity] : {std::pair{3, "0"}, std::pair{4, "9.81"}}) {
    rows.push_back(
        "INSERT INTO study_characterise_points (study_id, point, curve, model, empty, amplitude_m, "
        "frequency_hz, step) VALUES (1, " +
        std::to_string(point) + ", " + std::to_string(point - 2) + ", 'hard', 0, 0.001, 20, 1)");
    rows.push_back("INSERT INTO study_characterise_metrics VALUES (1, " + std::to_string(point) + ", " +
                   std::to_string(point) + ", 1, 10, 20, 10, 0.001, " + (point == 3 ? "0" : "2.5") +
                   ", 0.004, 0, 0.1, 0, 0.01, 0, 0.2, 1, 0, 0.004, " + gravity + ", 0.01, 1.0)");
  }
  RunStore store(store_of_schema(dir, 16, rows));
  sqlite::Database db(store.file());
  CHECK(scalar(db, "PRAGMA user_version") == RunStore::schema_version());
  CHECK(scalar(db, "SELECT count(*) FROM study_frf_metrics WHERE point = 1 AND gamma IS NULL") == 1);
  CHECK(scalar(db,
               "SELECT count(*) FROM study_frf_metrics WHERE point = 2 AND gamma = 1.5 AND amplitude_m = 0.001 "
               "AND wall_time_s = 1.0") == 1);
  CHECK(scalar(db, "SELECT count(*) FROM study_characterise_metrics WHERE point = 3 AND gamma IS NULL") == 1);
  CHECK(scalar(db,
               "SELECT count(*) FROM study_characterise_metrics WHERE point = 4 AND gamma = 2.5 AND "
               "gravity_m_s2 = 9.81 AND wall_time_s = 1.0") == 1);
  // The views read the new tables, and a point's run still takes its metrics with it.
  CHECK(scalar(db, "SELECT count(*) FROM study_characterisation WHERE gamma IS NULL") == 1);
  CHECK(scalar(db, "SELECT count(*) FROM study_characterisation WHERE gamma = 2.5") == 1);
  CHECK(scalar(db, "SELECT count(*) FROM pragma_foreign_key_check") == 0);
  db.exec("PRAGMA foreign_keys = ON; DELETE FROM runs WHERE run_id IN (1, 3)");
  CHECK(scalar(db, "SELECT count(*) FROM study_frf_metrics") +
            scalar(db, "SELECT count(*) FROM study_characterise_metrics") ==
        2);
}

TEST_CASE("a store of schema 14 is migrated: its [frf] points have no grid, and study_frf shows the column") {
  test::TempDir dir("store-migrate-14");
  const auto file =
      store_of_schema(dir, 14,
                      {"INSERT INTO studies (name, models, n_points, study_file, study_text, scenario_file, "
                       "scenario_text, pdamp_version, created_at) VALUES ('old', 'hard', 1, 'a', 'b', 'c', 'd', "
                       "'0.1.0', '2026-01-01')",
                       "INSERT INTO study_points (study_id, point, section) VALUES (1, 1, 'frf')",
                       "INSERT INTO study_frf_points (study_id, point, curve, model, direction, host_alone, mode, "
                       "level, frequency_hz, step) VALUES (1, 1, 1, 'hard', 'up', 0, 'force', 0.1, 15, 1)"});
  {
    sqlite::Database v14(file);
    CHECK(scalar(v14, "SELECT count(*) FROM pragma_table_info('study_frf') WHERE name = 'grid'") == 0);
  }
  RunStore store(file);
  sqlite::Database db(store.file());
  CHECK(scalar(db, "PRAGMA user_version") == RunStore::schema_version());
  CHECK(scalar(db, "SELECT count(*) FROM study_frf WHERE grid = '' AND frequency_hz = 15") == 1);
  const auto rows = StudyStore(store).frf_points(1);
  REQUIRE(rows.size() == 1);
  CHECK(rows[0].place.grid.empty());
  CHECK(rows[0].place.frequency_hz == 15.0);
}
