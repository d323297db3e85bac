/// End-to-end tests of `pdamp study`: validation before anything is written, the stored
/// study, resuming without redoing, refusing a changed study, the same bits for any
/// --jobs, and a study killed mid-run that resumes to the same results.
#include <doctest/doctest.h>

#include <chrono>
#include <fstream>
#include <map>
#include <thread>
#include <tuple>

#include "pdamp/store/process_lease.hpp"
#include "pdamp/store/run_store.hpp"
#include "study_compare.hpp"
#include "test_process.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::test;

namespace {

/// A study file on small.ini.
std::string study_text(const std::string& models, const std::string& sweep) {
  return "[study]\nscenario = " + small() + "\nmodels = " + models + "\n\n[sweep]\n" + sweep;
}

/// Polls until `sql` holds: up to five minutes (the sanitizer build on a loaded machine did
/// not get a point under way within one); a pass returns at once.
bool wait_until(const std::filesystem::path& db, const std::string& sql) {
  for (int i = 0; i < 6000; ++i) {
    if (std::filesystem::exists(db) &&
        count_rows(db, "SELECT count(*) FROM sqlite_schema WHERE name = 'study_points'") && count_rows(db, sql) != 0) {
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

}  // namespace

TEST_CASE("a bad study exits with code 2 and one message naming the problem, and writes nothing") {
  test::TempDir dir("study-bad");
  const auto db = dir / "runs.sqlite";
  const std::string grid = "host.z0_m = 0.001:0.01:40\nhost.damping_N_s_m = 0.01:0.1:30\nparticles.count = 0\n";
  struct Case {
    std::string name, text, message;
    std::vector<std::string> extra = {};
  };
  const std::vector<Case> cases{
      {"misspelled key", study_text("hard", "particles.cont = 1, 2\n"),
       "[sweep] 'particles.cont' is not a scenario key; did you mean particles.count?"},
      {"unknown key", study_text("hard", "damper.size = 1, 2\n"), "'damper.size' is not a scenario key"},
      {"out of range at one point", study_text("hard", "host.z0_m = 0.01, 0.02\nhost.damping_N_s_m = 0.1, -0.1\n"),
       "point 2 of 4 ([sweep] host.z0_m = 0.01, host.damping_N_s_m = -0.1): swept host.damping_N_s_m: "
       "host.damping_N_s_m = '-0.1': must be >= 0"},
      {"empty range", study_text("hard", "host.z0_m = 0.01:0.01:3\n"), "the range is empty"},
      {"reversed range", study_text("hard", "host.z0_m = 0.02:0.01:3\n"), "the range is reversed"},
      {"count below 2", study_text("hard", "host.z0_m = 0.01:0.02:1\n"), "the count must be at least 2"},
      {"grid over the limit", study_text("hard", grid), "1200 points, more than the 1000 allowed without --force"},
      {"over the run budget", study_text("hard", "run.duration_s = 0.1, 1000\n"),
       "point 2 of 2 ([sweep] run.duration_s = 1000): run.max_samples = 1000000: "},
      {"a '#' in a value", study_text("hard", "host.z0_m = 0.01#m\n"), "'#' directly after text"},
      {"missing scenario", "[study]\nscenario = nowhere.ini\nmodels = hard\n[sweep]\nhost.z0_m = 0.01\n",
       "[study] scenario = nowhere.ini: base scenario '" + (dir / "nowhere.ini").string() +
           "' cannot be read (no such file); the path is relative to the study file"},
      {"missing models", "[study]\nscenario = " + small() + "\n[sweep]\nhost.z0_m = 0.01\n",
       "[study] models is missing (soft, hard or both)"},
      {"unknown models", study_text("all", "host.z0_m = 0.01\n"), "[study] models = 'all': must be soft, hard or both"},
      {"frequency response of a free host", "[study]\nscenario = " + small() + "\nmodels = hard\n[frf]\nmode = free\n",
       "[frf] mode = 'free': must be force"},
      {"no study file",
       "",
       "study file '" + (dir / "absent.ini").string() + "' cannot be read (no such file)",
       {"absent"}},
      {"bad jobs",
       study_text("hard", "host.z0_m = 0.01\n"),
       "--jobs '0': must be a whole number from 1 to 256",
       {"--jobs", "0"}},
  };
  for (const Case& c : cases) {
    CAPTURE(c.name);
    const auto file = dir / "study.ini";
    write_file(file, c.text);
    std::vector<std::string> args{"study", "run", file.string(), "--db", db.string()};
    if (!c.extra.empty() && c.extra[0] == "absent") {
      args[2] = (dir / "absent.ini").string();
    } else {
      args.insert(args.end(), c.extra.begin(), c.extra.end());
    }
    const Result r = pdamp_cli(args, dir);
    CHECK(r.code == 2);
    CHECK(r.err.find(c.message) != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(!std::filesystem::exists(db));
    INFO(r.err);
  }
  const Result directory = pdamp_cli({"study", "run", dir.path().string(), "--db", db.string()}, dir);
  CHECK(directory.code == 2);
  CHECK(directory.err.find("is a directory, not a regular file") != std::string::npos);
  CHECK(!std::filesystem::exists(db));
  // --force lifts the size limit (the host alone runs 1,200 points quickly; validation only here).
  write_file(dir / "study.ini", study_text("hard", grid));
  CHECK(pdamp_cli({"study", "run", (dir / "study.ini").string(), "--db", db.string(), "--jobs", "0", "--force"}, dir)
            .err.find("--jobs '0'") != std::string::npos);
}

TEST_CASE("a study runs into the store, lists and shows, resumes without redoing and refuses a changed file") {
  test::TempDir dir("study-host");
  const auto db = (dir / "runs.sqlite").string();
  const auto base = dir / "base.ini";
  write_file(base, "[particles]\ncount = 0\n[run]\nduration_s = 0.2\n");
  const auto file = dir / "host.ini";
  write_file(file,
             "[study]\nname = host alone\nscenario = base.ini\nmodels = hard\n[sweep]\n"
             "host.damping_N_s_m = 0.05:0.2:4\nhost.z0_m = 0.01, 0.02\n");
  Result r = pdamp_cli({"study", "run", file.string(), "--db", db, "--jobs", "2"}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("study 1 'host alone': models hard, 8 points (8 completed") == 0);
  CHECK(count_rows(db, "SELECT count(*) FROM runs WHERE status = 'completed'") == 8);
  CHECK(count_rows(db, "SELECT count(*) FROM study_point_metrics WHERE model = 'hard'") == 8);
  CHECK(count_rows(db, "SELECT count(*) FROM study_point_values WHERE key = 'host.damping_N_s_m' AND number = 0.1") ==
        2);
  // The runs are named after the study and their point.
  CHECK(count_rows(db,
                   "SELECT count(*) FROM runs r JOIN study_point_runs l USING (run_id) "
                   "WHERE r.scenario_name = 'host alone/' || l.point") == 8);
  // The host alone: the viscous damper dissipates it all, more for a stiffer damper.
  CHECK(count_rows(
            db, "SELECT count(*) FROM study_results WHERE dissipated_impact_J = 0 AND dissipated_viscous_J > 0") == 8);

  const Result list = pdamp_cli({"study", "list", "--db", db}, dir);
  CHECK(list.code == 0);
  CHECK(list.out.find("host alone") != std::string::npos);
  const Result show = pdamp_cli({"study", "show", "1", "--db", db}, dir);
  CHECK(show.code == 0);
  CHECK(show.out.find("host.damping_N_s_m = 0.15, host.z0_m = 0.02") != std::string::npos);
  CHECK(pdamp_cli({"study", "show", "7", "--db", db}, dir).code == 2);

  // Again, unchanged but reworded: nothing is run twice.
  write_file(file,
             "# the same study\n[study]\nname = host alone\nscenario = base.ini\nmodels = hard\n[sweep]\n"
             "host.damping_N_s_m = 0.05, 0.1, 0.15, 0.2\nhost.z0_m = 0.01,0.02\n");
  r = pdamp_cli({"study", "run", file.string(), "--db", db}, dir);
  CHECK(r.code == 0);
  CHECK(count_rows(db, "SELECT count(*) FROM runs") == 8);

  // A changed value, or a changed base scenario, is refused with the difference named.
  write_file(file,
             "[study]\nname = host alone\nscenario = base.ini\nmodels = hard\n[sweep]\n"
             "host.damping_N_s_m = 0.05:0.2:4\nhost.z0_m = 0.01, 0.03\n");
  r = pdamp_cli({"study", "run", file.string(), "--db", db}, dir);
  CHECK(r.code == 2);
  CHECK(r.err.find("study 'host alone' (study 1 in '" + db +
                   "') was made from another definition:\n"
                   "  [sweep] host.z0_m: '0.01, 0.03' now, '0.01, 0.02' stored") != std::string::npos);
  CHECK(pdamp_cli({"study", "resume", "1", "--db", db}, dir).code == 2);
  write_file(file,
             "[study]\nname = host alone\nscenario = base.ini\nmodels = hard\n[sweep]\n"
             "host.damping_N_s_m = 0.05:0.2:4\nhost.z0_m = 0.01, 0.02\n");
  write_file(base, "[particles]\ncount = 0\n[run]\nduration_s = 0.3\n");
  r = pdamp_cli({"study", "run", file.string(), "--db", db}, dir);
  CHECK(r.code == 2);
  CHECK(r.err.find("base scenario [run] duration_s: '0.3' now, '0.2' stored") != std::string::npos);
  CHECK(count_rows(db, "SELECT count(*) FROM runs") == 8);
  CHECK(count_rows(db, "SELECT count(*) FROM studies") == 1);

  // With its files gone, a study resumes from the definition stored with it.
  std::filesystem::remove(base);
  r = pdamp_cli({"study", "resume", "1", "--db", db}, dir);
  CHECK(r.code == 0);
  CHECK(r.err.find("resuming from the definition stored with it") != std::string::npos);
}

TEST_CASE("resume never stores the study its file now holds: another study there is refused, the difference named") {
  test::TempDir dir("study-resume-other");
  const auto db = (dir / "runs.sqlite").string();
  const auto file = dir / "rp.ini";
  write_file(file, "[study]\nname = rp\nscenario = " + small() +
                       "\nmodels = hard\n[sweep]\nhost.damping_N_s_m = 0.1, 0.2\nrun.duration_s = 0.02\n");
  Result r = pdamp_cli({"study", "run", file.string(), "--db", db}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::int64_t runs = count_rows(db, "SELECT count(*) FROM runs");

  write_file(file,
             "[study]\nname = other\nscenario = " + small() + "\nmodels = hard\n[sweep]\nhost.mass_kg = 0.03, 0.04\n");
  r = pdamp_cli({"study", "resume", "1", "--db", db}, dir);
  CHECK(r.code == 2);
  CHECK(r.err.find("study 1 ('rp' in '" + db + "'): its study file '" + file.string() +
                   "' now describes another study:\n  [study] name: 'other' now, 'rp' stored\n") != std::string::npos);
  CHECK(r.err.find("  [sweep] host.mass_kg: '0.03, 0.04' now, '(not given)' stored\n") != std::string::npos);
  CHECK(count_rows(db, "SELECT count(*) FROM studies") == 1);
  CHECK(count_rows(db, "SELECT count(*) FROM runs") == runs);
  // Shown as stored, and said so.
  const Result show = pdamp_cli({"study", "show", "1", "--db", db}, dir);
  CHECK(show.code == 0);
  CHECK(show.out.find("  study file     " + file.string() +
                      " (now another study: [study] name: 'other' now, 'rp' stored; ...; the study is shown as "
                      "stored)\n") != std::string::npos);
  CHECK(show.out.find("host.damping_N_s_m = 0.2, run.duration_s = 0.02") != std::string::npos);

  // The same study written otherwise resumes; with the file gone, from the stored definition.
  write_file(file, "[study]\nname = rp\nscenario = " + small() +
                       "\nmodels = hard\n[sweep]\nhost.damping_N_s_m = 1e-1, 0.20\nrun.duration_s = 0.020\n");
  r = pdamp_cli({"study", "resume", "1", "--db", db}, dir);
  CHECK(r.code == 0);
  CHECK(pdamp_cli({"study", "show", "1", "--db", db}, dir).out.find("  study file     " + file.string() + "\n") !=
        std::string::npos);
  std::filesystem::remove(file);
  r = pdamp_cli({"study", "resume", "1", "--db", db}, dir);
  CHECK(r.code == 0);
  CHECK(r.out.find("  study file     " + file.string() + " (gone; the study is shown as stored)\n") !=
        std::string::npos);
  CHECK(count_rows(db, "SELECT count(*) FROM studies") == 1);
  CHECK(count_rows(db, "SELECT count(*) FROM runs") == runs);
}

TEST_CASE("a study gives the same bits for any --jobs: every sample of every run, and the metrics") {
  test::TempDir dir("study-jobs");
  const auto file = dir / "both.ini";
  // Two beds (30 and 60 spheres), each run by both models at two host dampings.
  write_file(file,
             study_text("both", "particles.count = 30, 60\nhost.damping_N_s_m = 0.1, 0.3\nrun.duration_s = 0.08\n"));
  std::map<int, std::filesystem::path> stores;
  for (const int jobs : {1, 3}) {
    stores[jobs] = dir / ("jobs" + std::to_string(jobs) + ".sqlite");
    const Result r =
        pdamp_cli({"study", "run", file.string(), "--db", stores[jobs].string(), "--jobs", std::to_string(jobs)}, dir);
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(count_rows(stores[jobs], "SELECT count(*) FROM runs WHERE status = 'completed'") == 8);
    CHECK(count_rows(stores[jobs], "SELECT count(*) FROM study_agreement") == 4);
  }
  const auto [differing, compared] = sample_differences(stores[1], stores[3]);
  CHECK(compared == 8 * 161);
  CHECK(differing == 0);
  CHECK(metric_differences(stores[1], stores[3]) == 0);
  CHECK(count_rows(stores[3], "SELECT count(*) FROM study_point_metrics") == 8);
}

namespace {

/// Six points of small.ini's soft model, a quarter of a second each, one shared bed.
/// Six points of about a second each on an idle machine: a point stores its samples every
/// 0.25 s of wall time, so the tests below see one under way (at 0.25 s of simulated time a
/// point ran in about 0.4 s and was often seen only completed).
std::filesystem::path six_points(const test::TempDir& dir) {
  auto file = dir / "six.ini";
  write_file(file, study_text("soft", "host.damping_N_s_m = 0.1:0.6:6\nrun.duration_s = 0.6\n"));
  return file;
}

/// A point of the study is running and has stored some samples in its current attempt.
constexpr const char* mid_run =
    "SELECT count(*) > 40 FROM study_points p JOIN study_point_runs l USING (study_id, point, attempt) "
    "JOIN samples s USING (run_id) WHERE p.status = 'running'";

}  // namespace

TEST_CASE("a study killed mid-run continues its points in progress from their checkpoints, to the same bits") {
  test::TempDir dir("study-kill");
  const auto file = six_points(dir);
  const auto reference = dir / "reference.sqlite", killed = dir / "killed.sqlite";
  REQUIRE(pdamp_cli({"study", "run", file.string(), "--db", reference.string(), "--jobs", "2"}, dir).code == 0);
  const std::vector<std::string> run{"study",  "run", file.string(),        "--db", killed.string(),
                                     "--jobs", "2",   "--checkpoint-every", "0.05"};

  // SIGKILL of the study process alone: its workers stop and store their points as interrupted.
  {
    Process study(run, dir, "study", Group::own);
    REQUIRE(wait_until(killed, mid_run));
    study.signal(SIGKILL);
    CHECK(study.wait() == 128 + SIGKILL);
    REQUIRE(wait_until(killed, "SELECT count(*) = 0 FROM study_points WHERE status = 'running'"));
    CHECK(count_rows(killed,
                     "SELECT count(*) FROM study_points WHERE status = 'interrupted' "
                     "AND message LIKE '%stopped by a signal%'") >= 1);
    study.signal_group(SIGKILL);  // nothing should be left of it
  }
  // SIGKILL of the study and its workers once a point's run has a checkpoint: their points
  // stay 'running' under leases whose processes are gone.
  {
    Process study({"study", "resume", "1", "--db", killed.string(), "--jobs", "2", "--checkpoint-every", "0.05"}, dir,
                  "resume", Group::own);
    REQUIRE(wait_until(killed, std::string(mid_run) + " AND (" + test::checkpointed_unfinished_runs + ") > 0"));
    CHECK(study.kill_group() == 128 + SIGKILL);
  }
  const std::int64_t completed_before =
      count_rows(killed, "SELECT count(*) FROM study_points WHERE status = 'completed'");
  CHECK(count_rows(killed, "SELECT count(*) FROM study_points WHERE status = 'running'") >= 1);
  CHECK(completed_before < 6);
  CHECK(pdamp_cli({"study", "show", "1", "--db", killed.string()}, dir)
            .out.find(") is gone; 'pdamp study resume 1' runs it again") != std::string::npos);

  const std::string checkpointed = test::unfinished_checkpointed_run_ids(killed);
  // As if those processes had run on another host (a store copied from a node that went
  // down): their leases cannot be checked from here, so their points are left alone until
  // the user says that host runs them no more.
  const std::int64_t elsewhere = count_rows(killed, "SELECT count(*) FROM study_points WHERE status = 'running'");
  sqlite::Database(killed).exec("UPDATE study_points SET lease_host = 'node-gone' WHERE status = 'running'");
  CHECK(pdamp_cli({"study", "show", "1", "--db", killed.string()}, dir)
            .out.find("cannot be checked from here; if it runs there no more, 'pdamp study resume 1 --take-over "
                      "node-gone' runs it again") != std::string::npos);
  const Result left = pdamp_cli({"study", "resume", "1", "--db", killed.string(), "--jobs", "2"}, dir);
  CHECK(left.code == 1);
  CHECK(left.err.find("on node-gone (which cannot be checked from here; if it runs there no more: --take-over "
                      "node-gone)") != std::string::npos);
  CHECK(count_rows(killed, "SELECT count(*) FROM study_points WHERE status = 'completed'") == 6 - elsewhere);
  for (const std::string& host : {std::string(), this_host_name()}) {
    const Result refused = pdamp_cli({"study", "resume", "1", "--db", killed.string(), "--take-over", host}, dir);
    CHECK(refused.code == 2);
    CHECK(refused.err.find("--take-over") != std::string::npos);
  }
  const Result resumed =
      pdamp_cli({"study", "resume", "1", "--db", killed.string(), "--jobs", "2", "--take-over", "node-gone"}, dir);
  INFO(resumed.err);
  REQUIRE(resumed.code == 0);
  CHECK(resumed.err.find(": taken over from process ") != std::string::npos);
  CHECK(resumed.err.find(" on node-gone (--take-over node-gone); run again") != std::string::npos);
  CHECK(count_rows(killed, "SELECT count(*) FROM study_points WHERE status = 'completed'") == 6);
  // Completed points were not run again; the others continued their runs from their
  // checkpoints (a run without one starts over, the old one left interrupted).
  CHECK(count_rows(killed, "SELECT count(*) FROM study_points WHERE attempt = 1") >= completed_before);
  CHECK(count_rows(killed, "SELECT count(*) FROM study_points WHERE attempt > 1") >= 2);
  CHECK(count_rows(killed, "SELECT count(*) FROM runs WHERE status = 'running'") == 0);
  INFO("runs with a checkpoint before the resume: " << checkpointed);
  CHECK(checkpointed != "()");
  CHECK(test::runs_continued_by_their_points(killed, checkpointed) ==
        count_rows(killed, "SELECT count(*) FROM runs WHERE run_id IN " + checkpointed));
  CHECK(count_rows(killed, "SELECT count(*) FROM runs WHERE status = 'completed'") == 6);
  const auto [differing, compared] = sample_differences(reference, killed);
  CHECK(compared == 6 * 1201);  // 0.6 s sampled every 0.5 ms
  CHECK(differing == 0);
  CHECK(metric_differences(reference, killed) == 0);
}

TEST_CASE("SIGINT stops a study's workers promptly, and a crashed worker fails only its point") {
  test::TempDir dir("study-stop");
  const auto file = six_points(dir);
  const auto db = dir / "runs.sqlite";
  {
    Process study({"study", "run", file.string(), "--db", db.string(), "--jobs", "2"}, dir);
    REQUIRE(wait_until(db, mid_run));
    const auto asked = std::chrono::steady_clock::now();
    study.signal(SIGINT);
    CHECK(study.wait() == 128 + SIGINT);
    CHECK(std::chrono::steady_clock::now() - asked < std::chrono::seconds(5));
    CHECK(study.err().find("stopped; 'pdamp study resume 1' runs the") != std::string::npos);
    CHECK(count_rows(db, "SELECT count(*) FROM study_points WHERE status = 'running'") == 0);
    CHECK(count_rows(db, "SELECT count(*) FROM study_points WHERE status = 'interrupted'") >= 1);
  }
  {
    Process study({"study", "resume", "1", "--db", db.string(), "--jobs", "2"}, dir);
    REQUIRE(wait_until(db, mid_run));
    const std::int64_t worker = count_rows(db, "SELECT lease_pid FROM study_points WHERE status = 'running' LIMIT 1");
    REQUIRE(worker > 0);
    kill(static_cast<pid_t>(worker), SIGKILL);  // a crash (the sanitizers would turn a SIGSEGV into SIGABRT)
    CHECK(study.wait() == 1);
    CHECK(count_rows(db,
                     "SELECT count(*) FROM study_points WHERE status = 'failed' "
                     "AND message LIKE '%ended with signal 9%'") == 1);
    CHECK(count_rows(db, "SELECT count(*) FROM study_points WHERE status = 'completed'") == 5);
    CHECK(study.err().find("failed: its worker (process " + std::to_string(worker) + ") ended with signal 9") !=
          std::string::npos);
  }
  const Result resumed = pdamp_cli({"study", "resume", "1", "--db", db.string()}, dir);
  CHECK(resumed.code == 0);
  CHECK(count_rows(db, "SELECT count(*) FROM study_points WHERE status = 'completed'") == 6);
}

TEST_CASE("pdamp study plot draws a metric against the swept key") {
  test::TempDir dir("study-plot");
  const auto file = dir / "plot.ini";
  write_file(file, study_text("hard", "particles.count = 0\nhost.damping_N_s_m = 0.05:0.2:4\nrun.duration_s = 0.3\n"));
  const auto db = (dir / "runs.sqlite").string();
  REQUIRE(pdamp_cli({"study", "run", file.string(), "--db", db}, dir).code == 0);
  const auto png = dir / "plot.png";
  const Result r =
      pdamp_cli({"study", "plot", "1", "--db", db, "--metric", "dissipated_viscous_J", "--out", png.string()}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  std::ifstream in(png, std::ios::binary);
  char signature[8] = {};
  in.read(signature, 8);
  CHECK(std::string(signature + 1, 3) == "PNG");
  CHECK(std::filesystem::file_size(png) > 10'000);
  const Result bad = pdamp_cli({"study", "plot", "1", "--db", db, "--metric", "nonsense"}, dir);
  CHECK(bad.code == 2);
  CHECK(bad.err.find("'nonsense' is not a metric") != std::string::npos);
  CHECK(pdamp_cli({"study", "plot", "2", "--db", db}, dir).code == 2);
  // A picture it could not write, or in a format it does not draw: refused before plotting.
  for (const auto& [out, expected] :
       {std::pair<std::string, std::string>{(dir / "no" / "plot.png").string(), "does not exist"},
        {(dir / "plot.txt").string(), "name the picture .png, .svg or .pdf"},
        {(dir / "plot").string(), "name the picture .png, .svg or .pdf"}}) {
    CAPTURE(out);
    const Result refused = pdamp_cli({"study", "plot", "1", "--db", db, "--out", out}, dir);
    CHECK(refused.code == 2);
    CHECK(refused.err.find(expected) != std::string::npos);
  }
}
