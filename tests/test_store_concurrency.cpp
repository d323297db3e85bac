/// Many pdamp processes writing one store at once while a reader queries it: every run
/// ends completed with all its samples and cycles.
#include <doctest/doctest.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "pdamp/model/host.hpp"
#include "pdamp/model/placement.hpp"
#include "pdamp/sim/initial_bed.hpp"
#include "pdamp/store/run_store.hpp"
#include "test_process.hpp"
#include "test_support.hpp"

using namespace pdamp;

namespace {

constexpr int writers = 8;                    // half soft, half hard
constexpr double sample_interval_s = 0.0005;  // table1.ini's

std::string table1() { return test::scenario_file("table1").string(); }

/// Stores Table 1's placement as the bed its runs start from, under its settle key, so
/// the runs start at once: settling 1246 spheres takes 10-20 s, and this test is about
/// the store, not the bed.
void store_placed_bed(const std::filesystem::path& db) {
  const Scenario s = load_scenario(table1());
  RunStore store(db);
  store.save_initial_state(settle_key(s), place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m), 0.0,
                           0.0, 0.0);
}

/// Lists the runs over and over, each time from a new read-only connection as `pdamp runs`
/// does, until stopped.
class Reader {
 public:
  explicit Reader(const std::filesystem::path& db) : thread_([this, db] { loop(db); }) {}
  ~Reader() { stop(); }
  /// Stops reading; then queries() and errors() say how it went.
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  int queries() const { return queries_; }
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  void loop(const std::filesystem::path& db) {
    while (!stop_) {
      try {
        RunStore(db, StoreAccess::read).list_runs();
        ++queries_;
      } catch (const std::exception& e) {
        errors_.emplace_back(e.what());
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  std::atomic<bool> stop_{false};
  int queries_ = 0;
  std::vector<std::string> errors_;
  std::thread thread_;
};

std::int64_t scalar(sqlite::Database& d, const std::string& sql) {
  sqlite::Statement q(d, sql);
  REQUIRE(q.step());
  return q.column_int(0);
}

/// Starts `writers` runs of Table 1 into `db` at once, alternately soft and hard, with a
/// reader querying throughout; checks every process and every stored run.
void run_trial(const test::TempDir& dir, const std::filesystem::path& db, double soft_s, double hard_s) {
  std::int64_t before = 0;
  {
    sqlite::Database d(db);
    before = scalar(d, "SELECT coalesce(max(run_id), 0) FROM runs");
  }
  const auto start = std::chrono::steady_clock::now();
  std::vector<test::Process> runs;
  Reader reader(db);
  for (int i = 0; i < writers; ++i) {
    const bool hard = i % 2 == 1;
    runs.emplace_back(
        std::vector<std::string>{"run", "--scenario", table1(), "--model", hard ? "hard" : "soft", "--duration",
                                 std::to_string(hard ? hard_s : soft_s), "--threads", "1", "--db", db.string()},
        dir, "writer" + std::to_string(i));
  }
  for (int i = 0; i < writers; ++i) {
    CAPTURE(i);
    const int code = runs[static_cast<std::size_t>(i)].wait();
    INFO(runs[static_cast<std::size_t>(i)].err());
    CHECK(code == 0);
  }
  reader.stop();
  CHECK(reader.errors().empty());
  for (const auto& e : reader.errors()) MESSAGE("reader: " << e);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  MESSAGE(writers << " runs (soft " << soft_s << " s, hard " << hard_s << " s) in " << wall_s << " s; reader "
                  << reader.queries() << " queries");
  CHECK(reader.queries() > 0);

  sqlite::Database d(db);
  const std::string mine = " run_id > " + std::to_string(before);
  CHECK(scalar(d, "SELECT count(*) FROM runs WHERE" + mine) == writers);
  CHECK(scalar(d, "SELECT count(*) FROM runs WHERE status = 'completed' AND" + mine) == writers);
  for (const auto& [name, duration] :
       {std::pair{std::string("soft"), soft_s}, std::pair{std::string("hard"), hard_s}}) {
    const std::string& model = name;  // by name: clang before 16 cannot capture a structured binding
    CAPTURE(model);
    const std::string of_model = " FROM run_summary WHERE model = '" + model + "' AND" + mine;
    const auto samples = std::llround(duration / sample_interval_s) + 1;
    CHECK(scalar(d, "SELECT min(n_samples)" + of_model) == samples);
    CHECK(scalar(d, "SELECT max(n_samples)" + of_model) == samples);
    // Same scenario, bed and seed: the same cycles and the same bits in every sample.
    const std::int64_t cycles = scalar(d, "SELECT min(n_cycles)" + of_model);
    CHECK(cycles >= 1);
    CHECK(scalar(d, "SELECT max(n_cycles)" + of_model) == cycles);
    const std::int64_t first = scalar(d, "SELECT min(run_id)" + of_model);
    CHECK(scalar(d, "SELECT count(*) FROM samples a JOIN samples b ON b.run_id = " + std::to_string(first) +
                        " AND b.t_s = a.t_s AND b.host_z_m = a.host_z_m AND b.excitation_work_J = a.excitation_work_J "
                        "AND b.dissipated_impact_J = a.dissipated_impact_J JOIN runs r ON r.run_id = a.run_id "
                        "WHERE r.model = '" +
                        model + "' AND r." + mine.substr(1)) == samples * writers / 2);
  }
}

}  // namespace

TEST_CASE("eight processes run Table 1 into one store at once, a reader querying: every run complete") {
  test::TempDir dir("concurrent-runs");
  const auto db = dir / "runs.sqlite";
  store_placed_bed(db);
  for (int trial = 0; trial < 2; ++trial) {
    CAPTURE(trial);
    run_trial(dir, db, 0.065, 0.12);
  }
}

TEST_CASE("eight processes settle and run full Table 1 into one new store: three trials" *
          doctest::test_suite("slow")) {
  test::TempDir dir("concurrent-runs-full");
  const auto db = dir / "runs.sqlite";
  { const RunStore created(db); }  // the schema, without a bed: every process settles it in the first trial
  for (int trial = 0; trial < 3; ++trial) {
    CAPTURE(trial);
    run_trial(dir, db, 0.2, 1.5);
  }
  // All settled the same bed at once in the first trial; the first stored stays.
  sqlite::Database d(db);
  CHECK(scalar(d, "SELECT count(*) FROM initial_states") == 1);
  CHECK(scalar(d, "SELECT count(DISTINCT initial_state_id) FROM runs") == 1);
}

// Processes sharing a fresh store settle the same bed at once and the first to store it
// wins; the others must say they start from that stored bed, not that they stored it.
TEST_CASE("a bed another process stored while this one settled it counts as reused, not as stored here") {
  test::TempDir dir("concurrent-bed");
  const auto db = dir / "runs.sqlite";
  const Scenario s = load_scenario(test::small(), {"particles.count=10"});
  RunStore mine(db), other(db);
  bool stored_meanwhile = false;
  const InitialBed bed = prepare_initial_bed(s, mine, nullptr, [&](double, double) {
    if (stored_meanwhile) return;
    other.save_initial_state(settle_key(s), place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m),
                             0.0, 0.0, 0.0);
    stored_meanwhile = true;
  });
  REQUIRE(stored_meanwhile);
  CHECK(bed.reused);
  CHECK(bed.state_id == std::optional<std::int64_t>(1));
  sqlite::Database d(db);
  CHECK(scalar(d, "SELECT count(*) FROM initial_states") == 1);

  test::TempDir alone("concurrent-bed-alone");
  RunStore only(alone / "runs.sqlite");
  const InitialBed settled = prepare_initial_bed(s, only);
  CHECK_FALSE(settled.reused);
  CHECK(settled.state_id == std::optional<std::int64_t>(1));
  CHECK(prepare_initial_bed(s, only).reused);
}
