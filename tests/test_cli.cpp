/// End-to-end tests of the pdamp executable: scenario -> run -> store -> query.
#include <doctest/doctest.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "pdamp/store/run_store.hpp"
#include "test_support.hpp"

extern char** environ;

using namespace pdamp;

namespace {

/// An executable (pdamp unless named) started with arguments, its output captured in files.
class Process {
 public:
  Process(const std::vector<std::string>& args, const test::TempDir& dir) : Process(PDAMP_EXECUTABLE, args, dir) {}
  Process(const std::string& executable, const std::vector<std::string>& args, const test::TempDir& dir)
      : out_(dir / "stdout"), err_(dir / "stderr") {
    std::vector<std::string> all{executable};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    REQUIRE(posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ) == 0);
    posix_spawn_file_actions_destroy(&actions);
  }
  /// Waits for the exit and returns the exit code (128 + signal if killed).
  int wait() {
    int status = 0;
    waitpid(pid_, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  void signal(int number) const { kill(pid_, number); }
  std::string out() const { return slurp(out_); }
  std::string err() const { return slurp(err_); }

 private:
  static std::string slurp(const std::filesystem::path& file) {
    std::ifstream in(file);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  }
  pid_t pid_ = 0;
  std::filesystem::path out_, err_;
};

struct Result {
  int code;
  std::string out, err;
};

Result pdamp_cli(const std::vector<std::string>& args, const test::TempDir& dir,
                 const std::string& executable = PDAMP_EXECUTABLE) {
  Process p(executable, args, dir);
  const int code = p.wait();
  return {code, p.out(), p.err()};
}

std::string table1() { return test::scenario_file("table1").string(); }

std::int64_t count_rows(const std::filesystem::path& db, const std::string& sql) {
  sqlite::Database d(db);
  sqlite::Statement q(d, sql);
  q.step();
  return q.column_int(0);
}

}  // namespace

TEST_CASE("host alone, both models: the stored free decay is the exact Table 1 solution") {
  for (const std::string model : {"soft", "hard"}) {
    CAPTURE(model);
    test::TempDir dir("cli-host-" + model);
    const auto db = dir / "runs.sqlite";
    const Result r = pdamp_cli({"run", "--scenario", table1(), "--model", model, "--set", "particles.count=0", "--db",
                                db.string(), "--duration", "1.0"},
                               dir);
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(r.out.find("completed") != std::string::npos);

    sqlite::Database d(db);
    // Frequency: every cycle of the decay at f_d = f_0 sqrt(1 - zeta^2) = 17.79 Hz.
    sqlite::Statement cycles(d, "SELECT min(freq_hz), max(freq_hz), count(*) FROM cycles WHERE run_id = 1");
    REQUIRE(cycles.step());
    CHECK(cycles.column_int(2) >= 16);
    CHECK(std::round(cycles.column_double(0) * 100) / 100 == 17.79);
    CHECK(std::round(cycles.column_double(1) * 100) / 100 == 17.79);
    // Every stored sample on the analytic decay, to 1e-9 of the envelope z0 e^{-alpha t}.
    const double m = 0.0376, k = 470, c = 0.1, z0 = 0.0157;
    const double alpha = c / (2 * m), wd = std::sqrt(k / m - alpha * alpha);
    sqlite::Statement samples(d, "SELECT t_s, host_z_m, energy_balance_rel_err FROM samples WHERE run_id = 1");
    int n = 0;
    double worst = 0, worst_balance = 0;
    while (samples.step()) {
      const double t = samples.column_double(0);
      const double envelope = z0 * std::exp(-alpha * t);
      const double exact = envelope * (std::cos(wd * t) + alpha / wd * std::sin(wd * t));
      worst = std::max(worst, std::abs(samples.column_double(1) - exact) / envelope);
      worst_balance = std::max(worst_balance, samples.column_double(2));
      ++n;
    }
    CHECK(n == 2001);  // table1.ini samples every 0.5 ms
    CHECK(worst <= 1e-9);
    CHECK(worst_balance <= 1e-12);
  }
}

TEST_CASE("pdamp run --model hard on small.ini: completed, balanced to 1e-9, event statistics stored") {
  test::TempDir dir("cli-hard");
  const auto db = dir / "runs.sqlite";
  const Result r = pdamp_cli(
      {"run", "--scenario", test::scenario_file("small").string(), "--model", "hard", "--db", db.string()}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("completed") != std::string::npos);
  sqlite::Database d(db);
  sqlite::Statement run(d, "SELECT energy_balance_rel_err, sim_time_s, n_cycles FROM run_summary WHERE run_id = 1");
  REQUIRE(run.step());
  CHECK(run.column_double(0) <= 1e-9);
  CHECK(run.column_double(1) == 0.3);
  CHECK(run.column_int(2) >= 4);
  for (const char* name :
       {"events_sphere_sphere", "events_wall", "events_cap", "events_cell_crossing", "events_stale"}) {
    CAPTURE(name);
    CHECK(count_rows(db, "SELECT value FROM run_statistics WHERE run_id = 1 AND name = '" + std::string(name) + "'") >
          0);
  }
  CHECK(count_rows(db, "SELECT count(*) FROM samples WHERE run_id = 1") == 601);
  // The fill: 100 spheres of 1.5 mm in a 12 mm x 10 mm hole.
  sqlite::Statement fill(
      d, "SELECT solid_fraction, impact_share + friction_share + viscous_share FROM energy_partition WHERE run_id = 1");
  REQUIRE(fill.step());
  CHECK(fill.column_double(0) == doctest::Approx(100 * 0.75 * 0.75 * 0.75 * 4.0 / 3.0 / (6.0 * 6.0 * 10.0)));
  CHECK(fill.column_double(1) == doctest::Approx(1.0));
}

TEST_CASE("bad input exits with code 2, names the problem and writes nothing") {
  test::TempDir dir("cli-bad");
  const auto db = dir / "runs.sqlite";
  struct Case {
    std::vector<std::string> args;
    std::string expected;
  };
  const std::vector<Case> cases{
      {{"run", "--scenario", table1(), "--model", "soft", "--set", "host.mass_kg=-2", "--db", db.string()},
       "host.mass_kg"},
      {{"run", "--scenario", table1(), "--model", "squishy", "--db", db.string()}, "--model 'squishy'"},
      {{"run", "--scenario", "/no/such.ini", "--model", "hard", "--db", db.string()}, "/no/such.ini"},
      {{"run", "--model", "hard", "--db", db.string()}, "--scenario is required"},
      {{"run", "--scenario", table1(), "--model", "soft", "--duration", "-1", "--db", db.string()}, "run.duration_s"},
      {{"run", "--scenario", table1(), "--model", "soft", "--bogus", "--db", db.string()}, "bogus"},
      {{"frobnicate"}, "unknown command"},
      {{"show", "abc", "--db", db.string()}, "RUN_ID 'abc'"},
      {{"run", "--scenario", table1(), "--model", "soft", "--threads", "0", "--db", db.string()}, "--threads '0'"},
      {{"run", "--scenario", table1(), "--model", "soft", "--simd", "avx1024", "--db", db.string()},
       "--simd 'avx1024': must be sse2, avx2 or avx512"},
      {{"runs", "--db", (dir / "missing.sqlite").string()}, "does not exist"},
  };
  for (const auto& c : cases) {
    CAPTURE(c.expected);
    const Result r = pdamp_cli(c.args, dir);
    CHECK(r.code == 2);
    CHECK(r.err.find(c.expected) != std::string::npos);
  }
  CHECK_FALSE(std::filesystem::exists(db));
}

TEST_CASE("the hard engine's benchmark refuses bad options with code 2, naming the option and what is valid") {
  test::TempDir dir("bench-bad");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases{
      {{"--particles", "abc"}, "('abc') for option '--particles' is invalid"},
      {{"--particles", "1"}, "--particles 1: must be from 2 to 10000000"},
      {{"--host", "wobbly"}, "--host 'wobbly': must be fixed or free"},
      {{"--packing", "0.8"}, "--packing 0.800000: must be above 0 and below 0.74"},
      {{"--collisions", "0"}, "--collisions 0: must be at least 1"},
      {{"--frobnicate", "1"}, "unrecognised option '--frobnicate'"},
      {{"--packing", "0.6"}, "at most 978 spheres"},  // the placement's own refusal
  };
  for (const auto& [args, expected] : cases) {
    CAPTURE(expected);
    const Result r = pdamp_cli(args, dir, PDAMP_BENCH_EXECUTABLE);
    CHECK(r.code == 2);
    CHECK(r.err.find(expected) != std::string::npos);
  }
}

TEST_CASE("the hard engine's benchmark times a small gas and says what the run was given of its core") {
  test::TempDir dir("bench-small");
  const Result r = pdamp_cli({"--particles", "100", "--collisions", "2000"}, dir, PDAMP_BENCH_EXECUTABLE);
  REQUIRE(r.code == 0);
  CAPTURE(r.out);
  // The number after `label` on the benchmark's line.
  const auto figure = [&](const std::string& label) {
    const auto at = r.out.find(label);
    REQUIRE(at != std::string::npos);
    return std::stod(r.out.substr(at + label.size()));
  };
  CHECK(figure("collisions ") >= 2000);
  CHECK(figure("energy change ") < 1e-12);  // elastic, frictionless, fixed walls
  CHECK(figure("collisions/s ") > 0);
  // The core probe: a clock any core runs at, and a median share at least the lowest. A
  // probe preempted on a loaded machine measures a share that prints as 0.00.
  CHECK(figure("clock ") > 0.1);
  CHECK(figure("clock ") < 10.0);
  CHECK(figure("lowest ") >= 0.0);
  CHECK(figure("core share ") >= figure("lowest "));
}

TEST_CASE("runs, show, check, keys and version") {
  test::TempDir dir("cli-list");
  const auto db = (dir / "runs.sqlite").string();
  REQUIRE(pdamp_cli({"run", "--scenario", table1(), "--model", "hard", "--set", "particles.count=0", "--db", db,
                     "--duration", "0.2"},
                    dir)
              .code == 0);
  const Result runs = pdamp_cli({"runs", "--db", db}, dir);
  CHECK(runs.code == 0);
  CHECK(runs.out.find("table1") != std::string::npos);
  const Result show = pdamp_cli({"show", "1", "--db", db}, dir);
  CHECK(show.code == 0);
  CHECK(show.out.find("17.79") != std::string::npos);
  CHECK(pdamp_cli({"show", "5", "--db", db}, dir).code == 2);
  const Result check = pdamp_cli({"check", "--scenario", table1()}, dir);
  CHECK(check.code == 0);
  CHECK(check.out.find("[soft_wall]") != std::string::npos);
  const Result keys = pdamp_cli({"run", "--help"}, dir);
  CHECK(keys.code == 0);
  CHECK(keys.out.find("host.stiffness_N_m = 470 [N/m]") != std::string::npos);
  CHECK(pdamp_cli({"--version"}, dir).out.find("pdamp 0.") == 0);
}

namespace {

/// Starts a run that would take hours and waits until it has committed samples.
Process start_endless_run(const test::TempDir& dir, const std::filesystem::path& db) {
  Process p({"run", "--scenario", table1(), "--model", "soft", "--set", "particles.count=0", "--set",
             "run.sample_interval_s=1e-5", "--duration", "1e5", "--db", db.string()},
            dir);
  for (int i = 0; i < 200; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    // The file appears before its schema does: wait for the samples table, then for samples.
    if (!std::filesystem::exists(db) ||
        count_rows(db, "SELECT count(*) FROM sqlite_master WHERE name = 'samples'") == 0) {
      continue;
    }
    if (count_rows(db, "SELECT count(*) FROM samples") > 1000) break;
  }
  return p;
}

}  // namespace

TEST_CASE("SIGTERM ends a run cleanly: interrupted, samples kept") {
  test::TempDir dir("cli-sigterm");
  const auto db = dir / "runs.sqlite";
  Process p = start_endless_run(dir, db);
  p.signal(SIGTERM);
  CHECK(p.wait() == 128 + SIGTERM);
  RunStore store(db);
  const auto s = store.summary(1);
  REQUIRE(s);
  CHECK(s->status == "interrupted");
  CHECK(s->n_samples > 1000);
  CHECK(s->sim_time_s > 0.01);
  CHECK(s->wall_time_s.has_value());
}

TEST_CASE("SIGKILL loses nothing committed: the file opens with its samples intact") {
  test::TempDir dir("cli-sigkill");
  const auto db = dir / "runs.sqlite";
  Process p = start_endless_run(dir, db);
  p.signal(SIGKILL);
  CHECK(p.wait() == 128 + SIGKILL);
  sqlite::Database d(db);
  sqlite::Statement integrity(d, "PRAGMA integrity_check");
  REQUIRE(integrity.step());
  CHECK(integrity.column_text(0) == "ok");
  RunStore store(db);
  const auto s = store.summary(1);
  REQUIRE(s);
  CHECK(s->status == "running");  // nobody was left to mark it
  CHECK(s->n_samples > 1000);
  // The committed samples are a gap-free prefix of the run.
  sqlite::Statement span(d, "SELECT count(*), max(t_s) FROM samples WHERE run_id = 1");
  REQUIRE(span.step());
  CHECK(span.column_int(0) == std::llround(span.column_double(1) / 1e-5) + 1);
}
