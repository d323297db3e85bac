/// `pdamp study submit|collect|status|task` end to end against stand-ins for Slurm's
/// programs (sbatch records the job script, squeue and sacct answer as a cluster without
/// accounting whose queue has emptied), the job scripts run as Slurm runs them: the study's
/// results are the bits of the same study run locally, also after a task killed mid-run is
/// resubmitted. tools/slurm-study-test.sh does the same on a real Slurm.
#include <doctest/doctest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <fstream>
#include <thread>

#include "study_compare.hpp"
#include "test_process.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::test;

namespace {

void write(const std::filesystem::path& file, const std::string& text, bool executable = false) {
  std::ofstream(file) << text;
  if (executable) chmod(file.c_str(), 0755);
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string read(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// sbatch, squeue, sacct and scontrol stand-ins first in PATH while it lives. sbatch records
/// each job script and answers job ids from 100 on (or refuses while `refuse` is on, or from
/// the job `refuse_from` names); squeue lists nothing and sacct answers as a cluster without
/// slurmdbd, unless given an answer; scontrol tells a MaxArraySize of 1001 unless given one.
class FakeSlurm {
 public:
  explicit FakeSlurm(const TempDir& dir) : bin_(dir / "bin"), path_(std::getenv("PATH")) {
    std::filesystem::create_directories(bin_);
    write(bin_ / "sbatch",
          "#!/bin/sh\n[ \"$1\" = --parsable ] || exit 9\nn=$(cat \"$0.next\" 2>/dev/null || echo 100)\n"
          "if [ -e \"$0.refuse\" ] || { [ -e \"$0.refuse_from\" ] && [ \"$n\" -ge \"$(cat \"$0.refuse_from\")\" ]; }; "
          "then\n"
          "  echo 'sbatch: error: Invalid account' >&2; exit 1\nfi\necho $((n + 1)) > \"$0.next\"\n"
          "echo \"$2\" >> \"$0.scripts\"\necho \"$n\"\n",
          true);
    write(bin_ / "squeue", "#!/bin/sh\necho \"$@\" >> \"$0.args\"\ncat \"$0.answer\" 2>/dev/null\nexit 0\n", true);
    write(bin_ / "sacct",
          "#!/bin/sh\nif [ -e \"$0.answer\" ]; then cat \"$0.answer\"; exit 0; fi\n"
          "echo 'sacct: error: Slurm accounting storage is disabled' >&2\nexit 1\n",
          true);
    write(bin_ / "scontrol",
          "#!/bin/sh\n[ \"$1 $2\" = \"show config\" ] || exit 9\n"
          "echo \"MaxArraySize            = $(cat \"$0.max\" 2>/dev/null || echo 1001)\"\n",
          true);
    setenv("PATH", (bin_.string() + ":" + path_).c_str(), 1);
  }
  ~FakeSlurm() { setenv("PATH", path_.c_str(), 1); }
  FakeSlurm(const FakeSlurm&) = delete;
  FakeSlurm& operator=(const FakeSlurm&) = delete;

  /// The job scripts sbatch was given, in order.
  std::vector<std::filesystem::path> scripts() const {
    std::vector<std::filesystem::path> files;
    std::istringstream lines(read(bin_ / "sbatch.scripts"));
    for (std::string line; std::getline(lines, line);) files.emplace_back(line);
    return files;
  }
  /// What squeue or sacct prints from now on ("JOB|TASK|STATE" lines, "JOB_TASK|STATE" lines).
  void answer(const std::string& program, const std::string& text) const { write(bin_ / (program + ".answer"), text); }
  /// The arguments squeue was called with, a line per call.
  std::string queue_questions() const { return read(bin_ / "squeue.args"); }
  void max_array_size(int size) const { write(bin_ / "scontrol.max", std::to_string(size)); }
  void refuse_from(std::int64_t job) const { write(bin_ / "sbatch.refuse_from", std::to_string(job)); }
  void refuse(bool on) const {
    if (on) {
      write(bin_ / "sbatch.refuse", "");
    } else {
      std::filesystem::remove(bin_ / "sbatch.refuse");
    }
  }

 private:
  std::filesystem::path bin_;
  std::string path_;
};

/// A task of a job array started as Slurm starts it: the script run by bash with the
/// array's variables set.
Process start_task(const std::filesystem::path& script, std::int64_t job, std::int64_t task, const TempDir& dir) {
  setenv("SLURM_ARRAY_JOB_ID", std::to_string(job).c_str(), 1);
  setenv("SLURM_ARRAY_TASK_ID", std::to_string(task).c_str(), 1);
  Process p("/bin/bash", {script.string()}, dir, "task-" + std::to_string(job) + "-" + std::to_string(task));
  unsetenv("SLURM_ARRAY_JOB_ID");
  unsetenv("SLURM_ARRAY_TASK_ID");
  return p;
}

int run_task(const std::filesystem::path& script, std::int64_t job, std::int64_t task, const TempDir& dir) {
  Process p = start_task(script, job, task, dir);
  const int code = p.wait();
  INFO(p.out() << p.err());
  CHECK(code == 0);
  return code;
}

/// The #SBATCH --array line of a job script.
std::string array_line(const std::filesystem::path& script) {
  const std::string text = read(script);
  const auto at = text.find("#SBATCH --array=");
  return at == std::string::npos ? "" : text.substr(at, text.find('\n', at) - at);
}

/// A study of small.ini's two models from one bed each point: four host dampings.
std::filesystem::path four_points(const TempDir& dir) {
  auto file = dir / "four.ini";
  write(file, "[study]\nname = four\nscenario = " + scenario_file("small").string() +
                  "\nmodels = both\n[sweep]\nhost.damping_N_s_m = 0.1:0.4:4\nrun.duration_s = 0.1\n");
  return file;
}

}  // namespace

TEST_CASE("a study on Slurm, one task killed and resubmitted, collects to the bits of the study run locally") {
  TempDir dir("slurm-cli");
  FakeSlurm slurm(dir);
  const auto file = four_points(dir);
  const auto reference = dir / "reference.sqlite", db = dir / "runs.sqlite";
  REQUIRE(pdamp_cli({"study", "run", file.string(), "--db", reference.string(), "--jobs", "2"}, dir).code == 0);

  Result r = pdamp_cli(
      {"study", "submit", file.string(), "--slurm", "--db", db.string(), "--max-parallel", "2", "--time", "5"}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(contains(r.out,
                 "study 1 'four': 4 points submitted as 1 job array\n  job 100 (array 0-3: points 1-4), script "
                 "submit-1.sh\n"));
  REQUIRE(slurm.scripts().size() == 1);
  const auto script = slurm.scripts()[0];
  CHECK(script == dir / "runs.sqlite.shards/study-1/submit-1.sh");
  CHECK(array_line(script) == "#SBATCH --array=0-3%2");
  CHECK(count_rows(db, "SELECT count(*) FROM study_tasks WHERE job_id = 100 AND collected_at IS NULL") == 4);
  CHECK(count_rows(db, "SELECT count(*) FROM runs") == 0);

  for (const int task : {0, 1, 3}) run_task(script, 100, task, dir);
  // Task 2 (point 3) killed as it starts: its shard stays unfinished.
  const auto part = dir / "runs.sqlite.shards/study-1/task-2.job-100.sqlite.part";
  {
    Process task = start_task(script, 100, 2, dir);
    for (int i = 0; i < 2000 && !std::filesystem::exists(part); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    task.signal(SIGKILL);
    CHECK(task.wait() == 128 + SIGKILL);
  }
  REQUIRE(std::filesystem::exists(part));
  CHECK(count_rows(db, "SELECT count(*) FROM runs") == 0);  // the tasks never write the study's store

  r = pdamp_cli({"study", "status", "1", "--db", db.string()}, dir);
  CHECK(r.code == 0);
  CHECK(contains(r.out, "study 1 'four': 0 of 4 points completed, 1 jobs submitted"));
  CHECK(contains(r.out, "shard waiting"));
  CHECK(contains(r.out, "task 2 of job 100 left an unfinished shard: it was killed while running"));
  CHECK(contains(r.out,
                 "sacct: error: Slurm accounting storage is disabled; tasks that left the queue are known "
                 "from their shards only"));

  r = pdamp_cli({"study", "collect", "1", "--db", db.string()}, dir);
  INFO(r.out);
  CHECK(r.code == 0);
  CHECK(contains(r.out, "collected task 0 of job 100 (point 1, "));
  CHECK(contains(r.out, "collected task 3 of job 100 (point 4, "));
  CHECK(contains(r.out, "): completed, 2 runs, 1 beds added, 0 shared"));
  CHECK(contains(r.out, "): completed, 2 runs, 0 beds added, 1 shared"));
  CHECK(
      contains(r.out, "pdamp: point 3: task 2 of job 100 left an unfinished shard: it was killed while running (log: " +
                          (dir / "runs.sqlite.shards/study-1/logs/100_2.log").string() + ")"));
  CHECK(contains(r.out, "study 1 'four': 3 of 4 points completed; 3 shards collected now, 0 before"));
  r = pdamp_cli({"study", "collect", "1", "--db", db.string()}, dir);
  CHECK(contains(r.out, "3 of 4 points completed; 0 shards collected now, 3 before"));

  // Only the killed task's point is submitted again.
  r = pdamp_cli({"study", "submit", "--resume", "1", "--slurm", "--db", db.string()}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(contains(r.out, "1 points submitted as 1 job array\n  job 101 (array 0-0: points 3)"));
  REQUIRE(slurm.scripts().size() == 2);
  CHECK(array_line(slurm.scripts()[1]) == "#SBATCH --array=0-0");
  run_task(slurm.scripts()[1], 101, 0, dir);
  r = pdamp_cli({"study", "collect", "1", "--db", db.string()}, dir);
  CHECK(r.code == 0);
  CHECK(contains(r.out, "study 1 'four': 4 of 4 points completed; 1 shards collected now, 3 before"));
  r = pdamp_cli({"study", "submit", "--resume", "1", "--slurm", "--db", db.string()}, dir);
  CHECK(r.code == 0);
  CHECK(contains(r.err, "study 1 has no point to submit"));
  CHECK(slurm.scripts().size() == 2);

  // The same bits as the study run locally: every sample and cycle of every run, the runs'
  // rows, the point metrics and the models' agreement; one bed, as locally.
  const auto [samples_differing, samples] = sample_differences(reference, db);
  CHECK(samples == 4 * 2 * 201);
  CHECK(samples_differing == 0);
  const auto [cycles_differing, cycles] = cycle_differences(reference, db);
  CHECK(cycles > 0);
  CHECK(cycles_differing == 0);
  const auto [runs_differing, runs] = run_differences(reference, db);
  CHECK(runs == 8);
  CHECK(runs_differing == 0);
  CHECK(metric_differences(reference, db) == 0);
  CHECK(count_rows(db, "ATTACH '" + reference.string() +
                           "' AS r; SELECT count(*) FROM (SELECT point, envelope_max_rel_diff, psi_mean_abs_diff, "
                           "dissipated_rel_diff FROM main.study_agreement EXCEPT SELECT point, envelope_max_rel_diff, "
                           "psi_mean_abs_diff, dissipated_rel_diff FROM r.study_agreement)") == 0);
  CHECK(count_rows(db, "SELECT count(*) FROM study_agreement") == 4);
  CHECK(count_rows(db, "SELECT count(*) FROM initial_states") == 1);
  CHECK(count_rows(reference, "SELECT count(*) FROM initial_states") == 1);
  CHECK(count_rows(db, "SELECT count(*) FROM study_points WHERE point = 3 AND attempt = 1") == 1);
}

TEST_CASE("status and --resume follow squeue and sacct, and collect reports the failed and the missing tasks") {
  TempDir dir("slurm-states");
  FakeSlurm slurm(dir);
  // Points 1 and 2 fail: the hard engine reaches run.max_events long before 0.05 s.
  const auto file = dir / "failing.ini";
  write(file, "[study]\nname = failing\nscenario = " + scenario_file("small").string() +
                  "\nmodels = hard\n[sweep]\nrun.max_events = 100, 10000000000\nhost.damping_N_s_m = 0.1, 0.2\n"
                  "run.duration_s = 0.05\n");
  const auto db = dir / "runs.sqlite";
  const std::vector<std::string> status{"study", "status", "1", "--db", db.string()},
      collect{"study", "collect", "1", "--db", db.string()},
      resume{"study", "submit", "--resume", "1", "--slurm", "--db", db.string()};
  REQUIRE(pdamp_cli({"study", "submit", file.string(), "--slurm", "--db", db.string()}, dir).code == 0);
  const auto script = slurm.scripts().at(0);

  // Queued and running tasks: status shows squeue's states, and nothing is submitted again.
  slurm.answer("squeue", "100|0|RUNNING\n100|[1-3]|PENDING\n");
  Result r = pdamp_cli(status, dir);
  INFO(r.out << r.err);
  CHECK(r.code == 0);
  CHECK(contains(slurm.queue_questions(), "--name=pdamp-study-1 --format=%F|%K|%T"));
  CHECK(contains(r.out, "study 1 'failing': 0 of 4 points completed, 1 jobs submitted"));
  CHECK(contains(r.out, "task 0 of job 100 is RUNNING"));
  CHECK(contains(r.out, "task 3 of job 100 is PENDING"));
  r = pdamp_cli(resume, dir);
  CHECK(r.code == 0);
  CHECK(contains(r.err, "study 1 has no point to submit: every point is completed or queued"));
  CHECK(slurm.scripts().size() == 1);

  // Tasks 0 to 2 ran points 1 to 3 (1 and 2 failing, exit 1), task 3 was cancelled before it
  // started; the queue has forgotten them, accounting has not.
  for (const int task : {0, 1, 2}) {
    Process p = start_task(script, 100, task, dir);
    CHECK(p.wait() == (task == 2 ? 0 : 1));
  }
  slurm.answer("squeue", "");
  slurm.answer("sacct", "100_0|FAILED\n100_1|FAILED\n100_2|COMPLETED\n100_3|CANCELLED by 0\n");
  r = pdamp_cli(collect, dir);
  CHECK(r.code == 0);
  CHECK(contains(r.out, "collected task 0 of job 100 (point 1, "));
  CHECK(contains(r.out, "): failed, 1 runs, 1 beds added, 0 shared"));
  for (const char* point : {"pdamp: point 1: failed in task 0 of job 100: run ", "pdamp: point 2: failed in task 1"}) {
    CAPTURE(point);
    CHECK(contains(r.out, point));
  }
  CHECK(contains(r.out, "run.max_events = 100 events"));
  CHECK(contains(r.out,
                 "pdamp: point 4: task 3 of job 100 left no shard: it never ran, or died before it could "
                 "write one (log: " +
                     (dir / "runs.sqlite.shards/study-1/logs/100_3.log").string() + ")"));
  CHECK(contains(r.out, "study 1 'failing': 1 of 4 points completed; 3 shards collected now, 0 before"));
  CHECK(count_rows(db, "SELECT count(*) FROM study_tasks WHERE outcome = 'failed' AND collected_at IS NOT NULL") == 2);

  r = pdamp_cli(status, dir);
  CHECK(contains(r.out, "COMPLETED"));
  CHECK(contains(r.out, "task 3 of job 100 left no shard (Slurm: CANCELLED)"));
  CHECK(!contains(r.out, "accounting storage is disabled"));

  // The failed and the missing points are submitted again, not the completed one.
  r = pdamp_cli(resume, dir);
  CHECK(r.code == 0);
  CHECK(contains(r.out, "3 points submitted as 1 job array\n  job 101 (array 0-2: points 1-2,4)"));
  REQUIRE(slurm.scripts().size() == 2);
  CHECK(array_line(slurm.scripts()[1]) == "#SBATCH --array=0-2");
}

TEST_CASE("submit checks everything before it writes: exit 2 with the reason, and a dry run writes nothing") {
  TempDir dir("slurm-submit");
  FakeSlurm slurm(dir);
  const auto file = four_points(dir);
  const auto db = dir / "runs.sqlite";
  const std::string study = file.string();
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases{
      {{study}, "--slurm is required"},
      {{"--slurm"}, "give a STUDY.ini or --resume STUDY_ID"},
      {{study, "--slurm", "--resume", "1"}, "give a STUDY.ini or --resume STUDY_ID"},
      {{study, "--slurm", "--time", "2h"}, "--time '2h': a time limit per task as Slurm takes it"},
      {{study, "--slurm", "--partition", "a b"}, "--partition 'a b'"},
      {{study, "--slurm", "--max-parallel", "0"}, "--max-parallel '0': must be a whole number from 1"},
      {{study, "--slurm", "--max-parallel", "4x"}, "--max-parallel '4x'"},
      {{study, "--slurm", "--account", "lab;rm"}, "--account 'lab;rm': an account name"},
      {{study, "--slurm", "--partition", ""}, "--partition '': a partition name"},
      {{study, "--slurm", "--threads", "0"}, "--threads '0'"},
      {{study, "--slurm", "--scratch", "$(id)"}, "--scratch '$(id)'"},
      {{study, "--slurm", "--checkpoint-every", "-1"}, "--checkpoint-every '-1': must be a number of seconds"},
      {{(dir / "absent.ini").string(), "--slurm"}, "cannot be read (no such file)"},
      {{"--resume", "1", "--slurm"}, "does not exist"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args{"study", "submit"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    args.insert(args.end(), {"--db", db.string()});
    const Result r = pdamp_cli(args, dir);
    CAPTURE(r.err);
    CHECK(r.code == 2);
    CHECK(contains(r.err, c.message));
    CHECK(!std::filesystem::exists(db));
  }
  const auto spaced = dir / "my runs.sqlite";
  const Result space = pdamp_cli({"study", "submit", study, "--slurm", "--db", spaced.string()}, dir);
  CHECK(space.code == 2);
  CHECK(contains(space.err, "that a job script's #SBATCH lines cannot hold"));
  CHECK(!std::filesystem::exists(spaced));
  write(dir / "bad.ini", read(file) + "particles.cont = 1\n");
  CHECK(pdamp_cli({"study", "submit", (dir / "bad.ini").string(), "--slurm", "--db", db.string()}, dir).code == 2);

  Result r =
      pdamp_cli({"study", "submit", study, "--slurm", "--dry-run", "--db", db.string(), "--account", "lab"}, dir);
  CHECK(r.code == 0);
  CHECK(contains(r.out, "#SBATCH --array=0-3\n#SBATCH --ntasks=1\n"));
  CHECK(contains(r.out, "--points 1-4 "));
  CHECK(contains(r.out, "#SBATCH --account=lab\n"));
  CHECK(contains(r.err, "dry run: 1 job script for 4 points of study 1; nothing was written or submitted"));
  CHECK(!std::filesystem::exists(db));
  CHECK(!std::filesystem::exists(dir / "runs.sqlite.shards"));
  CHECK(slurm.scripts().empty());

  // sbatch refusing: its reason, no job recorded, no script left.
  slurm.refuse(true);
  r = pdamp_cli({"study", "submit", study, "--slurm", "--db", db.string()}, dir);
  CHECK(r.code == 1);
  CHECK(contains(r.err, "sbatch refused the job script"));
  CHECK(contains(r.err, "Invalid account"));
  CHECK(count_rows(db, "SELECT count(*) FROM study_jobs") == 0);
  CHECK(!std::filesystem::exists(dir / "runs.sqlite.shards/study-1/submit-1.sh"));
  slurm.refuse(false);
  r = pdamp_cli({"study", "submit", study, "--slurm", "--db", db.string()}, dir);
  CHECK(r.code == 0);
  // A dry run of the stored study: what is left to submit, here every task, as none is in the
  // (empty) queue or left a shard.
  const std::string stored = read(db);
  r = pdamp_cli({"study", "submit", "--resume", "1", "--slurm", "--dry-run", "--db", db.string()}, dir);
  CHECK(r.code == 0);
  CHECK(contains(r.out, "#SBATCH --array=0-3\n"));
  CHECK(slurm.scripts().size() == 1);
  CHECK(read(db) == stored);
  CHECK(!std::filesystem::exists(dir / "runs.sqlite.shards/study-1/submit-2.sh"));
  // A dry run of another definition under the stored study's name: refused as study run
  // refuses it, naming the difference.
  const auto changed = dir / "changed.ini";
  std::string text = read(file);
  text.replace(text.find("0.1:0.4:4"), 9, "0.1:0.5:4");
  write(changed, text);
  r = pdamp_cli({"study", "submit", changed.string(), "--slurm", "--dry-run", "--db", db.string()}, dir);
  CHECK(r.code == 2);
  CHECK(contains(r.err, "study 'four' (study 1 in '" + db.string() + "') was made from another definition:"));
  CHECK(contains(r.err, "host.damping_N_s_m"));
  CHECK(read(db) == stored);

  // Without sbatch: refused before anything is written.
  const auto other = dir / "other.sqlite";
  const std::string path = std::getenv("PATH");
  setenv("PATH", "/nonexistent", 1);
  r = pdamp_cli({"study", "submit", study, "--slurm", "--db", other.string()}, dir);
  setenv("PATH", path.c_str(), 1);
  CHECK(r.code == 1);
  CHECK(contains(r.err, "sbatch is not installed here"));
  CHECK(!std::filesystem::exists(other));
}

TEST_CASE(
    "a study larger than the cluster's MaxArraySize goes as several job arrays, each recorded as it is submitted") {
  TempDir dir("slurm-arrays");
  FakeSlurm slurm(dir);
  slurm.max_array_size(3);
  const auto file = four_points(dir);
  const auto db = dir / "runs.sqlite";
  Result r = pdamp_cli({"study", "submit", file.string(), "--slurm", "--dry-run", "--db", db.string()}, dir);
  CHECK(r.code == 0);
  CHECK(contains(r.out, "#SBATCH --array=0-2\n"));
  CHECK(contains(r.out, "--points 1-3 "));
  CHECK(contains(r.out, "#SBATCH --array=0-0\n"));
  CHECK(contains(r.out, "--points 4 "));
  CHECK(contains(r.err, "dry run: 2 job scripts for 4 points of study 1"));

  // sbatch refuses the second array: the first stays recorded, and the user is told.
  slurm.refuse_from(101);
  r = pdamp_cli({"study", "submit", file.string(), "--slurm", "--db", db.string()}, dir);
  INFO(r.out << r.err);
  CHECK(r.code == 1);
  CHECK(contains(r.err,
                 "Invalid account; 3 of 4 points were submitted and recorded before (job 100 (array 0-2: points "
                 "1-3), script submit-1.sh); 'pdamp study submit --resume 1 --slurm' submits the rest"));
  CHECK(count_rows(db, "SELECT count(*) FROM study_tasks WHERE job_id = 100 AND task + 1 = point") == 3);
  CHECK(count_rows(db, "SELECT count(*) FROM study_tasks") == 3);
  CHECK(!std::filesystem::exists(dir / "runs.sqlite.shards/study-1/submit-2.sh"));

  std::filesystem::remove(dir / "bin/sbatch.refuse_from");
  slurm.answer("squeue", "100|[0-2]|PENDING\n");
  r = pdamp_cli({"study", "submit", "--resume", "1", "--slurm", "--db", db.string()}, dir);
  CHECK(r.code == 0);
  CHECK(contains(r.out, "1 points submitted as 1 job array\n  job 101 (array 0-0: points 4), script submit-2.sh"));
  const auto scripts = slurm.scripts();
  REQUIRE(scripts.size() == 2);
  for (const int task : {0, 1, 2}) run_task(scripts[0], 100, task, dir);
  run_task(scripts[1], 101, 0, dir);
  slurm.answer("squeue", "");
  r = pdamp_cli({"study", "collect", "1", "--db", db.string()}, dir);
  CHECK(r.code == 0);
  CHECK(contains(r.out, "collected task 0 of job 101 (point 4, "));
  CHECK(contains(r.out, "study 1 'four': 4 of 4 points completed; 4 shards collected now, 0 before"));
}
