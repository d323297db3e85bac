/// End-to-end tests of the pdamp executable: scenario -> run -> store -> query.
#include <doctest/doctest.h>
#include <fcntl.h>
#include <grp.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "pdamp/store/run_store.hpp"
#include "test_process.hpp"
#include "test_support.hpp"

using namespace pdamp;
using test::count_rows;
using test::pdamp_cli;
using test::Process;
using test::Result;

namespace {

std::string table1() { return test::scenario_file("table1").string(); }

}  // namespace

// Without spheres either --model runs the host-alone engine (the soft and hard engines need
// spheres): the same exact decay whichever model the run names.
TEST_CASE("host alone, either --model: the stored free decay is the exact Table 1 solution") {
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
  CHECK(count_rows(db, "SELECT count(*) FROM run_statistics WHERE run_id = 1 AND name LIKE 'diagnosis_%'") == 0);
  CHECK(count_rows(db, "SELECT count(*) FROM samples WHERE run_id = 1") == 601);
  // --diagnose-events adds its counts, and the same samples.
  const Result diagnosed = pdamp_cli({"run", "--scenario", test::scenario_file("small").string(), "--model", "hard",
                                      "--diagnose-events", "--db", db.string()},
                                     dir);
  REQUIRE(diagnosed.code == 0);
  CHECK(count_rows(db, "SELECT count(*) FROM run_statistics WHERE run_id = 2 AND name LIKE 'diagnosis_%'") == 60);
  CHECK(count_rows(db,
                   "SELECT count(*) FROM (SELECT t_s, host_z_m FROM samples WHERE run_id = 1 EXCEPT "
                   "SELECT t_s, host_z_m FROM samples WHERE run_id = 2)") == 0);
  // The fill: 100 spheres of 1.5 mm in a 12 mm x 10 mm hole.
  sqlite::Statement fill(
      d, "SELECT solid_fraction, impact_share + friction_share + viscous_share FROM energy_partition WHERE run_id = 1");
  REQUIRE(fill.step());
  CHECK(fill.column_double(0) == test::relative(100 * 0.75 * 0.75 * 0.75 * 4.0 / 3.0 / (6.0 * 6.0 * 10.0)));
  CHECK(fill.column_double(1) == doctest::Approx(1.0).scale(1.0));
}

TEST_CASE("a hard run failing at a known limitation says which, and what to run instead, also in the store") {
  // docs/hard-engine.md, "Resting beds and inelastic collapse": the small damper's settled bed
  // pressed against the side wall by gravity across the axis fails at t = 0.014 s; without
  // resting, pressed against the floor, at 0.031 s. Known limitations, not defects to report.
  test::TempDir dir("cli-known-failures");
  const auto db = dir / "runs.sqlite";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"gravity.g_m_s2=9.81 0 0",
       "(here 9.81 m/s^2 of it across the cylinder's axis): run this scenario with --model soft"},
      {"hard.rest_speed_m_s=0", "Resting is off (hard.rest_speed_m_s = 0 without hard.rest_tc_window)"}};
  for (const auto& [setting, expected] : cases) {
    CAPTURE(setting);
    const Result r = pdamp_cli({"run", "--scenario", test::scenario_file("small").string(), "--model", "hard", "--set",
                                setting, "--duration", "0.05", "--db", db.string()},
                               dir);
    INFO(r.err);
    CHECK(r.code == 1);
    CHECK(r.err.find(expected) != std::string::npos);
    CHECK(r.err.find("a defect to report") == std::string::npos);
  }
  sqlite::Database d(db);
  sqlite::Statement runs(d, "SELECT status, message FROM runs WHERE model = 'hard' ORDER BY run_id");
  for (const auto& [setting, expected] : cases) {
    CAPTURE(setting);
    REQUIRE(runs.step());
    CHECK(runs.column_text(0) == "failed");
    CHECK(runs.column_text(1).find(expected) != std::string::npos);
  }
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
      {{"run", "--scenario", table1(), "--model", "soft", "--diagnose-events", "--db", db.string()},
       "--diagnose-events counts the event-driven engine's collisions: it needs --model hard"},
      {{"frobnicate"}, "unknown command"},
      {{"show", "abc", "--db", db.string()}, "RUN_ID 'abc'"},
      {{"resume", "-1", "--db", db.string()}, "unrecognised option '-1': a negative number, where pdamp takes IDs"},
      {{"run", "--scenario", table1(), "--model", "soft", "--threads", "0", "--db", db.string()}, "--threads '0'"},
      {{"run", "--scenario", table1(), "--model", "soft", "--simd", "avx1024", "--db", db.string()},
       "--simd 'avx1024': must be sse2, avx2 or avx512"},
      {{"runs", "--db", (dir / "missing.sqlite").string()}, "does not exist"},
      // Inputs that once hung, crashed or filled the disk: refused, naming the key.
      {{"run", "--scenario", table1(), "--model", "soft", "--set", "soft.kn_N_m1_5=1e308", "--db", db.string()},
       "run.max_steps = 1000000000: settling the bed"},
      {{"run", "--scenario", table1(), "--model", "hard", "--set", "host.mass_kg=1e-300", "--db", db.string()},
       "run.max_steps = 1000000000: observing the run every"},
      {{"run", "--scenario", table1(), "--model", "hard", "--set", "particles.density_kg_m3=1e308", "--db",
        db.string()},
       "particles.density_kg_m3 = '1e308'"},
      {{"run", "--scenario", table1(), "--model", "soft", "--set", "run.sample_interval_s=1e-300", "--db", db.string()},
       "run.max_samples = 1000000"},
      {{"run", "--scenario", table1(), "--model", "soft", "--set", "soft.cn_N_s_m=1000", "--db", db.string()},
       "soft.cn_N_s_m"},
      {{"run", "--scenario", table1(), "--model", "soft", "--set", "run.dt_s=1e-6", "--set", "soft.cn_N_s_m=5", "--db",
        db.string()},
       "relaxes in tau = m/c"},
      {{"run", "--scenario", dir.path().string(), "--model", "soft", "--db", db.string()},
       "is a directory, not a regular file"},
      {{"run", "--scenario", "/dev/zero", "--model", "soft", "--db", db.string()}, "is a device, not a regular file"},
      {{"run", "--scenario", table1(), "--model", "soft", "--set", "scenario.name=run#7", "--db", db.string()},
       "a value cannot contain '#'"},
      {{"run", "--scenario", table1(), "--model", "soft", "--set", "host.z0_m=0.01\nhost.mass_kg=1", "--db",
        db.string()},
       "without line breaks"},
      // Names SQLite takes for something else than a file: the runs would be lost.
      {{"run", "--scenario", table1(), "--model", "hard", "--db", ""},
       "SQLite takes this name for a temporary database"},
      {{"runs", "--db", ":memory:"}, "SQLite takes this name for a database in memory"},
      {{"run", "--scenario", table1(), "--model", "hard", "--db", "file:" + db.string()},
       "SQLite takes this name for a URI"},
      // Options written whole, and no arguments where a command takes none.
      {{"delete", "1", "--f", "--db", db.string()}, "unrecognised option '--f'"},
      {{"run", "--scen", table1(), "--model", "hard", "--db", db.string()}, "unrecognised option '--scen'"},
      {{"rom", "--tab", "x.csv"}, "unrecognised option '--tab'"},
      {{"keys", "extra"}, "pdamp keys takes no arguments, not 'extra'"},
      {{"show", "--db", db.string()}, "pdamp show: RUN_ID is required"},
      {{"study", "show", "--db", db.string()}, "pdamp study show: STUDY_ID is required"},
      {{"--version", "extra"}, "--version takes no arguments, not 'extra'"},
      // An option that takes one value, given twice: which one was meant is not for pdamp to guess.
      {{"run", "--scenario", table1(), "--model", "soft", "--duration", "0.1", "--duration", "0.2", "--db",
        db.string()},
       "option '--duration' cannot be specified more than once"},
      {{"resume", "1", "--until", "1", "--until", "2", "--db", db.string()},
       "option '--until' cannot be specified more than once"},
      {{"rom", "--table", "x.csv", "--mass", "1", "--mass", "2"}, "option '--mass' cannot be specified more than once"},
  };
  for (const auto& c : cases) {
    CAPTURE(c.expected);
    const Result r = pdamp_cli(c.args, dir);
    CHECK(r.code == 2);
    CHECK(r.err.find(c.expected) != std::string::npos);
  }
  CHECK_FALSE(std::filesystem::exists(db));
}

TEST_CASE("output that cannot be written fails the command, naming the cause") {
  test::TempDir dir("cli-full");
  for (const std::string& command : {std::string("keys"), "check --scenario " + table1()}) {
    CAPTURE(command);
    const Result r = pdamp_cli({"-c", std::string(PDAMP_EXECUTABLE) + " " + command + " > /dev/full"}, dir, "/bin/sh");
    CHECK(r.code == 1);
    CHECK(r.err.find("the output could not be written to stdout: No space left on device") != std::string::npos);
  }
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
  for (const auto& [args, message] : cases) {
    const std::string& expected = message;  // by name: clang before 16 cannot capture a structured binding
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

TEST_CASE("tools/check-same-bits.sh: a binary against itself gives the same bits, a changed law does not") {
  // 20 spheres for 0.05 s, so that settling the bed and the runs take a moment; the
  // changed binary is pdamp with another e_n at the walls.
  test::TempDir dir("same-bits");
  {
    std::ofstream scenario(dir / "few.ini");
    scenario << "[particles]\ncount = 20\ndiameter_m = 0.002\n[cavity]\ndiameter_m = 0.02\nheight_m = 0.01\n";
    std::ofstream changed(dir / "changed-pdamp");
    changed << "#!/bin/sh\nexec " << PDAMP_EXECUTABLE << " \"$@\" --set hard_wall.en=0.7\n";
  }
  std::filesystem::permissions(dir / "changed-pdamp", std::filesystem::perms::owner_exec,
                               std::filesystem::perm_options::add);
  const std::string script = (test::source_dir() / "tools" / "check-same-bits.sh").string();
  const std::string cases = (dir / "few.ini").string() + "@0.05";
  const Result same = pdamp_cli({PDAMP_EXECUTABLE, PDAMP_EXECUTABLE, "hard", cases}, dir, script);
  INFO(same.out, same.err);
  CHECK(same.code == 0);
  CHECK(same.out.find("few@0.05: same bits (51 samples") != std::string::npos);
  const Result changed =
      pdamp_cli({"--keep", (dir / "kept").string(), PDAMP_EXECUTABLE, (dir / "changed-pdamp").string(), "hard", cases},
                dir, script);
  INFO(changed.out, changed.err);
  CHECK(changed.code == 1);
  CHECK(changed.out.find("few@0.05: DIFFERENT") != std::string::npos);
  CHECK(changed.out.find("samples: dissipated_impact_J differs") != std::string::npos);
  CHECK(std::filesystem::exists(dir / "kept" / "few@0.05" / "new.sqlite"));
  // Usage errors: exit 2, naming the problem.
  const Result unknown = pdamp_cli({PDAMP_EXECUTABLE, PDAMP_EXECUTABLE, "hard", "no-such-case"}, dir, script);
  CHECK(unknown.code == 2);
  CHECK(unknown.err.find("no-such-case") != std::string::npos);
  const Result model = pdamp_cli({PDAMP_EXECUTABLE, PDAMP_EXECUTABLE, "stiff", cases}, dir, script);
  CHECK(model.code == 2);
  CHECK(model.err.find("MODEL 'stiff'") != std::string::npos);
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
  // Each engine of the table says what it is for the scenario: the soft one its step.
  CHECK(check.out.find("# soft engine: time step ") != std::string::npos);
  CHECK(check.out.find("# hard engine: event-driven, no time step") != std::string::npos);
  const Result keys = pdamp_cli({"run", "--help"}, dir);
  CHECK(keys.code == 0);
  CHECK(keys.out.find("host.stiffness_N_m = 470 [N/m]") != std::string::npos);
  CHECK(pdamp_cli({"--version"}, dir).out.find("pdamp 0.") == 0);
}

namespace {

/// Starts a run that would take hours and waits until it has committed samples.
Process start_endless_run(const test::TempDir& dir, const std::filesystem::path& db) {
  Process p({"run", "--scenario", table1(), "--model", "soft", "--set", "particles.count=0", "--set",
             "run.sample_interval_s=1e-5", "--duration", "1e5", "--set", "run.max_samples=1e11", "--set",
             "run.max_steps=1e11", "--db", db.string()},
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
  CHECK(s->status == "dead");  // nobody was left to mark it: its lease's process is gone
  CHECK(s->n_samples > 1000);
  // The committed samples are a gap-free prefix of the run.
  sqlite::Statement span(d, "SELECT count(*), max(t_s) FROM samples WHERE run_id = 1");
  REQUIRE(span.step());
  CHECK(span.column_int(0) == std::llround(span.column_double(1) / 1e-5) + 1);
}

namespace {

std::string file_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

/// A store holding one run of the host alone (Table 1, 0.05 s, hard model).
void store_host_run(const test::TempDir& dir, const std::filesystem::path& db) {
  REQUIRE(pdamp_cli({"run", "--scenario", table1(), "--model", "hard", "--set", "particles.count=0", "--duration",
                     "0.05", "--db", db.string()},
                    dir)
              .code == 0);
}

/// Runs pdamp as a user who can read a directory but write neither it nor its files:
/// `nobody` when the tests run as root (root writes anything), else the test's user with
/// the directory and its files made read-only. pdamp and Table 1's scenario are copied
/// where any user can run and read them (the build and source trees may be private).
class ReadOnlyUser {
 public:
  ReadOnlyUser() : staging_("cli-read-only-user") {
    std::filesystem::copy_file(PDAMP_EXECUTABLE, staging_ / "pdamp");
    std::filesystem::copy_file(table1(), staging_ / "table1.ini");
  }
  std::string scenario() const { return (staging_ / "table1.ini").string(); }

  Result run(const std::vector<std::string>& args, const test::TempDir& dir) const {
    using std::filesystem::perms;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
      std::filesystem::permissions(entry.path(), perms::owner_read | perms::group_read | perms::others_read);
    }
    std::filesystem::permissions(dir.path(), perms::owner_read | perms::owner_exec | perms::group_read |
                                                 perms::group_exec | perms::others_read | perms::others_exec);
    test::Argv argv((staging_ / "pdamp").string(), args);
    const pid_t pid = fork();
    if (pid == 0) {
      dup2(open((staging_ / "out").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644), 1);
      dup2(open((staging_ / "err").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644), 2);
      if (geteuid() == 0 && (setgroups(0, nullptr) != 0 || setgid(65534) != 0 || setuid(65534) != 0)) _exit(126);
      execv(argv.program(), argv.get());
      _exit(127);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    std::filesystem::permissions(dir.path(), perms::owner_all, std::filesystem::perm_options::add);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), file_bytes(staging_ / "out"),
            file_bytes(staging_ / "err")};
  }

 private:
  test::TempDir staging_;
};

/// Runs pdamp with its stderr on a pseudo-terminal for `seconds`, then stops it with
/// SIGTERM; returns what it wrote to the terminal.
std::string stderr_on_terminal(const std::vector<std::string>& args, const test::TempDir& dir, double seconds) {
  const int master = posix_openpt(O_RDWR | O_NOCTTY);
  REQUIRE(master >= 0);
  REQUIRE(grantpt(master) == 0);
  REQUIRE(unlockpt(master) == 0);
  const std::string terminal = ptsname(master);
  test::Argv argv(PDAMP_EXECUTABLE, args);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, (dir / "terminal.out").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, terminal.c_str(), O_RDWR | O_NOCTTY, 0);
  pid_t pid = 0;
  REQUIRE(posix_spawn(&pid, argv.program(), &actions, nullptr, argv.get(), environ) == 0);
  posix_spawn_file_actions_destroy(&actions);
  std::string text;
  const auto start = std::chrono::steady_clock::now();
  bool stopped = false;
  for (int status = 0;;) {
    pollfd ready{master, POLLIN, 0};
    if (poll(&ready, 1, 50) > 0 && (ready.revents & POLLIN)) {
      char buffer[4096];
      if (const ssize_t n = read(master, buffer, sizeof buffer); n > 0)
        text.append(buffer, static_cast<std::size_t>(n));
    }
    if (!stopped && std::chrono::steady_clock::now() - start > std::chrono::duration<double>(seconds)) {
      kill(pid, SIGTERM);
      stopped = true;
    }
    if (waitpid(pid, &status, WNOHANG) == pid) break;
  }
  for (char buffer[4096];;) {  // what is left once it ended
    pollfd ready{master, POLLIN, 0};
    if (poll(&ready, 1, 100) <= 0 || !(ready.revents & POLLIN)) break;
    const ssize_t n = read(master, buffer, sizeof buffer);
    if (n <= 0) break;
    text.append(buffer, static_cast<std::size_t>(n));
  }
  close(master);
  return text;
}

/// Every command that opens a store, with `--db db`.
std::vector<std::vector<std::string>> store_commands(const std::filesystem::path& db) {
  std::vector<std::vector<std::string>> commands{
      {"run", "--scenario", table1(), "--model", "hard", "--set", "particles.count=0", "--duration", "0.01"},
      {"runs"},
      {"show", "1"},
      {"delete", "1"}};
  for (auto& command : commands) command.insert(command.end(), {"--db", db.string()});
  return commands;
}

}  // namespace

TEST_CASE("pdamp delete removes runs with all their rows, and their ids are not used again") {
  test::TempDir dir("cli-delete");
  const auto db = dir / "runs.sqlite";
  store_host_run(dir, db);
  store_host_run(dir, db);
  const Result deleted = pdamp_cli({"delete", "2", "--db", db.string()}, dir);
  INFO(deleted.err);
  CHECK(deleted.code == 0);
  CHECK(deleted.out ==
        "deleted run 2: hard model, scenario 'table1', completed (101 samples, 0 cycles, 0 comparisons)\n");
  CHECK(pdamp_cli({"show", "2", "--db", db.string()}, dir).code == 2);
  CHECK(count_rows(db, "SELECT count(*) FROM samples WHERE run_id = 2") == 0);
  CHECK(count_rows(db, "SELECT count(*) FROM run_statistics WHERE run_id = 2") == 0);
  CHECK(count_rows(db, "SELECT count(*) FROM samples WHERE run_id = 1") == 101);
  const Result again = pdamp_cli({"delete", "1", "2", "--db", db.string()}, dir);
  CHECK(again.code == 2);
  CHECK(again.err.find("run 2 is not in") != std::string::npos);
  CHECK(count_rows(db, "SELECT count(*) FROM runs") == 1);  // all or nothing
  store_host_run(dir, db);
  CHECK(count_rows(db, "SELECT max(run_id) FROM runs") == 3);
  const Result none = pdamp_cli({"delete", "--db", db.string()}, dir);
  CHECK(none.code == 2);
  CHECK(none.err.find("give the RUN_IDs") != std::string::npos);
  CHECK(pdamp_cli({"delete", "x1", "--db", db.string()}, dir).err.find("RUN_ID 'x1'") != std::string::npos);
  const auto missing = dir / "missing.sqlite";
  CHECK(pdamp_cli({"delete", "1", "--db", missing.string()}, dir).code == 2);
  CHECK_FALSE(std::filesystem::exists(missing));
}

TEST_CASE("pdamp runs escapes control characters in names and fits its columns") {
  test::TempDir dir("cli-runs-names");
  const auto db = dir / "runs.sqlite";
  {
    RunStore store(db);
    for (const std::string name : {"table1", "evil\x1b[2J\nname\t", "a scenario name far longer than the column"}) {
      store.finish_run(store.begin_run({"soft", name, "", 1, 0, 1.0}), {RunStatus::completed, "", 1.0, 0.5, 0.0, 0.0});
    }
  }
  const Result runs = pdamp_cli({"runs", "--db", db.string()}, dir);
  REQUIRE(runs.code == 0);
  CHECK(runs.out.find('\x1b') == std::string::npos);
  CHECK(runs.out.find('\t') == std::string::npos);
  CHECK(runs.out.find("evil\\x1b[2J\\nname\\t") != std::string::npos);
  CHECK(runs.out.find("a scenario name far longer than the col…") != std::string::npos);
  // Every line has its status where the header has it (counted in characters).
  std::istringstream lines(runs.out);
  std::vector<std::string> all;
  for (std::string line; std::getline(lines, line);) all.push_back(line);
  REQUIRE(all.size() == 4);
  auto column_of = [](const std::string& line, const std::string& word) {
    const auto at = line.find(word);
    REQUIRE(at != std::string::npos);
    return std::count_if(line.begin(), line.begin() + static_cast<std::ptrdiff_t>(at),
                         [](char c) { return (static_cast<unsigned char>(c) & 0xc0) != 0x80; });
  };
  const auto status_column = column_of(all[0], "status");
  for (std::size_t i = 1; i < all.size(); ++i) CHECK(column_of(all[i], "completed") == status_column);
  const Result show = pdamp_cli({"show", "2", "--db", db.string()}, dir);
  CHECK(show.out.find("scenario 'evil\\x1b[2J\\nname\\t'") != std::string::npos);
}

TEST_CASE("SIGTERM while the bed settles: the run is stored as interrupted") {
  test::TempDir dir("cli-sigterm-settling");
  const auto db = dir / "runs.sqlite";
  Process p({"run", "--scenario", table1(), "--model", "soft", "--db", db.string()}, dir);
  // The run's row comes before the bed, whose settling takes seconds.
  for (int i = 0; i < 600; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (std::filesystem::exists(db) && count_rows(db, "SELECT count(*) FROM sqlite_master WHERE name = 'runs'") > 0 &&
        count_rows(db, "SELECT count(*) FROM runs") > 0) {
      break;
    }
  }
  p.signal(SIGTERM);
  CHECK(p.wait() == 128 + SIGTERM);
  RunStore store(db, StoreAccess::read);
  const auto s = store.summary(1);
  REQUIRE(s);
  CHECK(s->status == "interrupted");
  CHECK(s->message == "stopped while settling the bed");
  CHECK(s->n_samples == 0);
  CHECK(count_rows(db, "SELECT count(*) FROM initial_states") == 0);
}

TEST_CASE("a restitution that cannot be calibrated is refused before the store is touched") {
  test::TempDir dir("cli-calibration");
  const auto db = dir / "runs.sqlite";
  const Result r = pdamp_cli({"run", "--scenario", test::scenario_file("table4_f500").string(), "--model", "hard",
                              "--set", "hard.restitution=calibrated", "--db", db.string()},
                             dir);
  CHECK(r.code == 2);
  CHECK(r.err.find("hard.restitution = calibrated:") != std::string::npos);
  CHECK(r.err.find("use [hard] restitution = constant") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(db));
}

TEST_CASE("another program's database and an empty file are left as they were") {
  test::TempDir dir("cli-foreign");
  const auto foreign = dir / "foreign.sqlite", empty = dir / "empty.sqlite";
  {
    sqlite::Database d(foreign);
    d.exec("CREATE TABLE notes (text); INSERT INTO notes VALUES ('mine')");
  }
  { std::ofstream created(empty); }
  const std::string before = file_bytes(foreign);
  for (const auto& args : store_commands(foreign)) {
    CAPTURE(args[0]);
    const Result r = pdamp_cli(args, dir);
    CHECK(r.code == 2);
    CHECK(r.err.find("is not a pdamp run store: it is another program's SQLite database (tables notes)") !=
          std::string::npos);
  }
  for (const auto& args : store_commands(empty)) {
    if (args[0] == "run") continue;  // an empty file becomes a store when a run is stored in it
    CAPTURE(args[0]);
    const Result r = pdamp_cli(args, dir);
    CHECK(r.code == 2);
    CHECK(r.err.find("is empty") != std::string::npos);
  }
  CHECK(file_bytes(foreign) == before);
  CHECK_FALSE(std::filesystem::exists(dir / "foreign.sqlite-wal"));
  CHECK_FALSE(std::filesystem::exists(dir / "foreign.sqlite-shm"));
  CHECK(std::filesystem::file_size(empty) == 0);
}

TEST_CASE("a store its reader cannot write lists and shows runs") {
  test::TempDir dir("cli-read-only");
  const auto db = dir / "runs.sqlite";
  store_host_run(dir, db);
  const ReadOnlyUser user;
  const Result runs = user.run({"runs", "--db", db.string()}, dir);
  INFO(runs.err);
  CHECK(runs.code == 0);
  CHECK(runs.out.find("table1") != std::string::npos);
  const Result show = user.run({"show", "1", "--db", db.string()}, dir);
  CHECK(show.code == 0);
  CHECK(show.out.find("run 1: hard model") != std::string::npos);
  const Result run = user.run({"run", "--scenario", user.scenario(), "--model", "hard", "--set", "particles.count=0",
                               "--duration", "0.01", "--db", db.string()},
                              dir);
  CHECK(run.code == 2);
  CHECK(run.err.find("can only be read: its file is not writable by this user") != std::string::npos);
  CHECK(count_rows(db, "SELECT count(*) FROM runs") == 1);
}

TEST_CASE("a damaged store is refused by every command, with a message and no SQL") {
  test::TempDir dir("cli-damaged");
  const auto db = dir / "runs.sqlite";
  store_host_run(dir, db);
  std::int64_t root = 0;
  {
    sqlite::Database d(db);
    sqlite::Statement q(d, "SELECT rootpage FROM sqlite_schema WHERE name = 'samples'");
    REQUIRE(q.step());
    root = q.column_int(0);
  }
  {
    std::fstream bytes(db, std::ios::in | std::ios::out | std::ios::binary);
    bytes.seekp((root - 1) * 4096);
    bytes.write("\x63\x63\x63\x63", 4);
  }
  const std::string before = file_bytes(db);
  for (const auto& args : store_commands(db)) {
    CAPTURE(args[0]);
    const Result r = pdamp_cli(args, dir);
    CHECK(r.code == 2);
    CHECK(r.err.find("is damaged") != std::string::npos);
    CHECK(r.err.find(".recover") != std::string::npos);
    CHECK(r.err.find("SELECT") == std::string::npos);
  }
  CHECK(file_bytes(db) == before);
}

// A schema changed by hand (a view dropped) passes SQLite's checks: a run into such a store
// computed, then failed with exit 1 when it came to store or print its results.
TEST_CASE("a store lacking one of pdamp's views or tables is refused by every command before any work") {
  test::TempDir dir("cli-schema");
  const auto db = dir / "runs.sqlite";
  store_host_run(dir, db);
  {
    sqlite::Database d(db);
    d.exec("CREATE VIEW my_runs AS SELECT run_id FROM runs");  // a user's own: no harm
    REQUIRE(pdamp_cli({"runs", "--db", db.string()}, dir).code == 0);
    d.exec("DROP VIEW run_summary");
  }
  const std::string before = file_bytes(db);
  for (const auto& args : store_commands(db)) {
    CAPTURE(args[0]);
    const Result r = pdamp_cli(args, dir);
    CHECK(r.code == 2);
    CHECK(r.err.find("runs.sqlite' is damaged: its schema lacks view run_summary, which pdamp created") !=
          std::string::npos);
  }
  CHECK(file_bytes(db) == before);
}

TEST_CASE("progress on a terminal: percent and time left on one line, for a run and for it resumed") {
  test::TempDir dir("cli-terminal");
  const std::string text =
      stderr_on_terminal({"run", "--scenario", table1(), "--model", "soft", "--set", "particles.count=0", "--set",
                          "run.sample_interval_s=1e-5", "--set", "run.max_samples=1e8", "--duration", "200", "--db",
                          (dir / "runs.sqlite").string()},
                         dir, 4.0);
  INFO(text);
  CHECK(text.find("\r  soft model: t = ") != std::string::npos);
  CHECK(text.find(" of 200.0000 s, ") != std::string::npos);
  CHECK(text.find(" %, ") != std::string::npos);
  CHECK(text.find(" left\x1b[K") != std::string::npos);
  // Resumed, it shows the same: the time left from the work done since the resume.
  const std::string resumed = stderr_on_terminal({"resume", "1", "--db", (dir / "runs.sqlite").string()}, dir, 4.0);
  INFO(resumed);
  CHECK(resumed.find("\r  resumed run: t = ") != std::string::npos);
  CHECK(resumed.find(" of 200.0000 s, ") != std::string::npos);
  CHECK(resumed.find(" left\x1b[K") != std::string::npos);
}

TEST_CASE("a FIFO as the scenario is refused at once, not waited on") {
  test::TempDir dir("cli-fifo");
  const auto fifo = dir / "scenario.ini";
  REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
  Process p({"check", "--scenario", fifo.string()}, dir);
  CHECK(p.wait_at_most(std::chrono::seconds(5)) == 2);
  CHECK(p.err().find("is a FIFO, not a regular file") != std::string::npos);
}

TEST_CASE("check counts a wide cavity's capacity in bounded time and memory, and refuses a vast one at once") {
  test::TempDir dir("cli-wide");
  struct Case {
    std::string diameter;
    int code;
  };
  // 0.4 m took 3.1 GB and 18 s when every lattice site was listed; 1 m ran out of memory.
  for (const Case& c : {Case{"0.4", 0}, Case{"1", 0}, Case{"1e6", 2}}) {
    CAPTURE(c.diameter);
    const auto start = std::chrono::steady_clock::now();
    Process p({"check", "--scenario", table1(), "--set", "cavity.diameter_m=" + c.diameter}, dir);
    CHECK(p.wait_at_most(std::chrono::seconds(10)) == c.code);
    CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(2));
    CHECK(p.peak_memory_kB() < 100'000);
  }
}

TEST_CASE("--set and --duration: for a key given twice the last on the command line wins") {
  test::TempDir dir("cli-order");
  const auto db = (dir / "runs.sqlite").string();
  auto simulated = [&](const std::vector<std::string>& order) {
    std::vector<std::string> args{"run",   "--scenario",        table1(), "--model", "hard",
                                  "--set", "particles.count=0", "--db",   db};
    args.insert(args.end(), order.begin(), order.end());
    const Result r = pdamp_cli(args, dir);
    REQUIRE(r.code == 0);
    const auto at = r.out.find("simulated");
    REQUIRE(at != std::string::npos);
    return std::stod(r.out.substr(at + 9));
  };
  CHECK(simulated({"--set", "run.duration_s=0.1", "--duration", "0.2"}) == 0.2);
  CHECK(simulated({"--duration", "0.2", "--set", "run.duration_s=0.1"}) == 0.1);
  CHECK(simulated({"--set", "run.duration_s=0.2", "--set", "run.duration_s=0.05"}) == 0.05);
}

TEST_CASE("a large normal dashpot: the automatic step resolves it, the run completes and keeps its books") {
  // c_n = 40 on 1.5 mm lead spheres: c_n dt / m* was 10 at the old automatic step, and the
  // run crashed on a position that was not a number. Without gravity: no settling.
  test::TempDir dir("cli-dashpot");
  const auto db = dir / "runs.sqlite";
  const Result r = pdamp_cli(
      {"run", "--scenario", test::scenario_file("small").string(), "--model", "soft", "--set", "soft.cn_N_s_m=40",
       "--set", "gravity.g_m_s2=0", "--set", "particles.count=20", "--duration", "0.01", "--db", db.string()},
      dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  RunStore store(db);
  const auto s = store.summary(1);
  REQUIRE(s);
  CHECK(s->status == "completed");
  REQUIRE(s->energy_balance_rel_err.has_value());
  CHECK(*s->energy_balance_rel_err < 1e-5);
  const Result check =
      pdamp_cli({"check", "--scenario", test::scenario_file("small").string(), "--set", "soft.cn_N_s_m=40"}, dir);
  CHECK(check.out.find("(automatic: tau/10)") != std::string::npos);
  CHECK(check.out.find("the sphere-sphere normal dashpot soft.cn_N_s_m") != std::string::npos);
}

namespace {

/// Signals `p` and returns how long it took to exit, and its exit code.
std::pair<std::chrono::duration<double>, int> stop_and_time(Process& p, int signal_number) {
  const auto start = std::chrono::steady_clock::now();
  p.signal(signal_number);
  const int code = p.wait_at_most(std::chrono::seconds(30));
  return {std::chrono::steady_clock::now() - start, code};
}

}  // namespace

TEST_CASE("SIGTERM inside a long advance of the engine ends the run within a second, stored as interrupted") {
  // Each observation is 0.1 s apart in steps of 2e-8 s: five million steps an advance.
  test::TempDir dir("cli-long-advance");
  const auto db = dir / "runs.sqlite";
  Process p({"run", "--scenario", test::scenario_file("small").string(), "--model", "soft", "--set", "soft.cn_N_s_m=40",
             "--set", "gravity.g_m_s2=0", "--set", "host.stiffness_N_m=1e-3", "--set", "run.sample_interval_s=0.1",
             "--set", "run.max_steps=1e10", "--duration", "100", "--db", db.string()},
            dir);
  for (int i = 0; i < 200; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (std::filesystem::exists(db) && count_rows(db, "SELECT count(*) FROM sqlite_master WHERE name = 'runs'") > 0 &&
        count_rows(db, "SELECT count(*) FROM runs") > 0) {
      break;
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const auto [took, code] = stop_and_time(p, SIGTERM);
  CHECK(code == 128 + SIGTERM);
  CHECK(took < std::chrono::seconds(1));
  RunStore store(db);
  const auto s = store.summary(1);
  REQUIRE(s);
  CHECK(s->status == "interrupted");
}

TEST_CASE("SIGINT while the bed settles ends pdamp within a second") {
  // Settling c_n = 40 takes minutes in steps of 2e-8 s.
  test::TempDir dir("cli-settling-sigint");
  const auto db = dir / "runs.sqlite";
  Process p({"run", "--scenario", test::scenario_file("small").string(), "--model", "hard", "--set", "soft.cn_N_s_m=40",
             "--db", db.string()},
            dir);
  for (int i = 0; i < 200 && !std::filesystem::exists(db); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const auto [took, code] = stop_and_time(p, SIGINT);
  CHECK(code == 128 + SIGINT);
  CHECK(took < std::chrono::seconds(1));
  CHECK(p.out().find("interrupted (stopped while settling the bed)") != std::string::npos);
  RunStore store(db, StoreAccess::read);
  const auto s = store.summary(1);
  REQUIRE(s);
  CHECK(s->status == "interrupted");
  CHECK(s->message == "stopped while settling the bed");
}

TEST_CASE("pdamp compare runs both models from one bed and stores their comparison") {
  test::TempDir dir("cli-compare");
  const auto db = dir / "runs.sqlite";
  const Result r = pdamp_cli({"compare", "--scenario", test::scenario_file("small").string(), "--set",
                              "particles.count=30", "--duration", "0.08", "--db", db.string()},
                             dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("comparison 1: scenario 'small', soft run 1, hard run 2") == 0);
  CHECK(count_rows(db, "SELECT count(*) FROM runs WHERE status = 'completed' AND initial_state_id = 1") == 2);
  CHECK(count_rows(db,
                   "SELECT count(*) FROM comparisons WHERE soft_run_id = 1 AND hard_run_id = 2 "
                   "AND initial_state_id = 1 AND hard_restitution = 'constant'") == 1);
  CHECK(count_rows(db, "SELECT count(*) FROM comparison_energy WHERE comparison_id = 1") == 4);  // 0.05 s and the end
  // What is stored, recomputed in SQL from the runs' own rows: the last samples' losses and
  // counts, the wall times, each model's energy at 0.05 s, and the cycles in the Γ bins.
  const std::string last = "(SELECT * FROM samples WHERE run_id = ?1 ORDER BY t_s DESC LIMIT 1)";
  auto same = [&](const std::string& stored, const std::string& recomputed) {
    CAPTURE(stored);
    return count_rows(db, "SELECT (" + stored + ") IS (" + recomputed + ")");
  };
  auto in_run = [](std::string sql, int run) {
    for (auto at = sql.find("?1"); at != std::string::npos; at = sql.find("?1"))
      sql.replace(at, 2, std::to_string(run));
    return sql;
  };
  const std::string total = "SELECT dissipated_impact_J + dissipated_friction_J + dissipated_viscous_J FROM " + last;
  CHECK(same("SELECT dissipated_soft_J FROM comparisons", in_run(total, 1)));
  CHECK(same("SELECT dissipated_hard_J FROM comparisons", in_run(total, 2)));
  CHECK(same("SELECT soft_steps FROM comparisons", in_run("SELECT time_steps FROM " + last, 1)));
  CHECK(same("SELECT hard_events FROM comparisons", in_run("SELECT collisions FROM " + last, 2)));
  CHECK(same("SELECT wall_time_ratio FROM comparisons",
             "SELECT s.wall_time_s / h.wall_time_s FROM runs s, runs h WHERE s.run_id = 1 AND h.run_id = 2"));
  for (const auto& [name, run] : {std::pair{"soft", 1}, std::pair{"hard", 2}}) {
    const char* const model = name;  // by name: clang before 16 cannot capture a structured binding
    CAPTURE(model);
    CHECK(same(std::string("SELECT friction_J FROM comparison_energy WHERE t_s = 0.05 AND model = '") + model + "'",
               in_run("SELECT dissipated_friction_J FROM samples WHERE run_id = ?1 AND t_s <= 0.05 "
                      "ORDER BY t_s DESC LIMIT 1",
                      run)));
  }
  CHECK(same("SELECT sum(cycles_soft) + sum(cycles_hard) FROM comparison_psi_bins",
             "SELECT count(*) FROM cycles WHERE gamma > 0"));
}
