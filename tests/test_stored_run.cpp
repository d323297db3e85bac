/// A run's life in the store: its row comes first, so whatever ends it is stored.
#include <doctest/doctest.h>

#include <chrono>

#include "pdamp/errors.hpp"
#include "pdamp/sim/stored_run.hpp"
#include "test_support.hpp"

using namespace pdamp;

namespace {

/// A bed that never comes: what a failure or a signal while settling looks like to the run.
template <class Failure>
BedSource failing_bed(const std::string& message) {
  return [message]() -> const InitialBed& { throw Failure(message); };
}

}  // namespace

TEST_CASE("a failure or a signal while the bed is prepared is stored with the run") {
  test::TempDir dir("stored-run-bed");
  RunStore store(dir / "runs.sqlite");
  const Scenario scenario = load_scenario(test::scenario_file("small"));
  const RunPlan plan = plan_run(Model::soft, scenario);

  struct Case {
    BedSource bed;
    RunStatus status;
    std::string status_name, message;
  };
  for (const auto& c : {Case{failing_bed<RuntimeFailure>("the bed did not come to rest"), RunStatus::failed, "failed",
                             "the bed did not come to rest"},
                        Case{failing_bed<Interrupted>("stopped while settling the bed"), RunStatus::interrupted,
                             "interrupted", "stopped while settling the bed"}}) {
    CAPTURE(c.status_name);
    const StoredRun run = run_and_store(store, plan, c.bed, RunControl{});
    CHECK(run.outcome.status == c.status);
    const auto s = store.summary(run.run_id);
    REQUIRE(s);
    CHECK(s->status == c.status_name);
    CHECK(s->message == c.message);
    CHECK(s->n_samples == 0);
    CHECK(s->sim_time_s == 0.0);
    CHECK(s->wall_time_s.has_value());
  }
}

TEST_CASE("a run records what it started from once its engine is built") {
  test::TempDir dir("stored-run-start");
  RunStore store(dir / "runs.sqlite");
  const Scenario scenario = load_scenario(test::scenario_file("table1"), {"particles.count=0", "run.duration_s=0.05"});
  const InitialBed bed{Particles(0), std::nullopt, false, 0.0};
  const StoredRun run = run_and_store(
      store, plan_run(Model::hard, scenario), [&]() -> const InitialBed& { return bed; }, RunControl{});
  CHECK(run.outcome.status == RunStatus::completed);
  const auto s = store.summary(run.run_id);
  REQUIRE(s);
  CHECK(s->status == "completed");
  CHECK(s->n_samples == 101);
  sqlite::Database db(store.file());
  sqlite::Statement start(db,
                          "SELECT dt_s IS NULL, initial_state_id IS NULL, solid_fraction FROM runs WHERE run_id = 1");
  REQUIRE(start.step());
  CHECK(start.column_int(0) == 1);  // the host alone has no time step
  CHECK(start.column_int(1) == 1);
  CHECK(start.column_double(2) == 0.0);
}

TEST_CASE("a restitution that cannot be calibrated is an input error, found before anything is settled") {
  // Table 4 at 500 Hz: impacts up to ~63 m/s, which the paper's k_n lets through.
  const Scenario scenario = load_scenario(test::scenario_file("table4_f500"), {"hard.restitution=calibrated"});
  const auto start = std::chrono::steady_clock::now();
  CHECK_THROWS_WITH_AS(plan_run(Model::hard, scenario),
                       doctest::Contains("hard.restitution = calibrated: calibrating the hard model's restitution"),
                       InputError);
  MESSAGE("refused after " << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() << " s");
  CHECK_NOTHROW(plan_run(Model::soft, scenario));  // the soft model needs no calibration
}
