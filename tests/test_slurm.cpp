/// Studies on Slurm without Slurm: the job script, the shard folder's names, the options'
/// checks, reading Slurm's answers, running programs, and collecting shard stores (merged
/// once, shared beds, refusals) from tasks run in this process.
#include <doctest/doctest.h>

#include <atomic>
#include <fstream>
#include <functional>

#include "pdamp/slurm/collect.hpp"
#include "pdamp/slurm/job_script.hpp"
#include "pdamp/slurm/program.hpp"
#include "pdamp/slurm/shard_task.hpp"
#include "pdamp/slurm/slurm.hpp"
#include "pdamp/store/shard_merge.hpp"
#include "pdamp/study/study_runner.hpp"
#include "study_compare.hpp"
#include "test_process.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::slurm;

namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("array ranges join consecutive tasks") {
  CHECK(array_ranges({5, 1, 2, 3, 8, 7, 8}) == "1-3,5,7-8");
  CHECK(array_ranges({4}) == "4");
  CHECK(array_ranges({}).empty());
}

TEST_CASE("a task finds its point in the array's list of points, which is never expanded") {
  const std::string points = array_ranges({2, 3, 4, 9, 1500, 1501});
  const std::vector<std::int64_t> expected{2, 3, 4, 9, 1500, 1501};
  for (std::size_t task = 0; task < expected.size(); ++task) {
    CHECK(nth_in_ranges(points, static_cast<std::int64_t>(task), 2000) == expected[task]);
  }
  // A range of a billion points is walked, not expanded.
  CHECK(nth_in_ranges("1-1000000000", 999'999'999, 1'000'000'000) == 1'000'000'000);
  CHECK_THROWS_WITH_AS(nth_in_ranges(points, 6, 2000), doctest::Contains("it has 6 points, so no task 6"), InputError);
  CHECK_THROWS_WITH_AS(nth_in_ranges(points, -1, 2000), doctest::Contains("no task -1"), InputError);
  for (const char* bad : {"", "0", "3-2", "1,,2", "1-", "-4", "a", "2,1", "1-3,3", "1-2001", " 1"}) {
    CAPTURE(bad);
    CHECK_THROWS_WITH_AS(nth_in_ranges(bad, 0, 2000), doctest::Contains("the list of points '"), InputError);
  }
}

TEST_CASE("points are split into job arrays the cluster's MaxArraySize takes") {
  const auto chunks = array_chunks({7, 1, 2, 3, 5, 9, 8, 2}, 3);
  REQUIRE(chunks.size() == 3);
  CHECK(chunks[0] == std::vector<std::int64_t>{1, 2, 3});
  CHECK(chunks[1] == std::vector<std::int64_t>{5, 7, 8});
  CHECK(chunks[2] == std::vector<std::int64_t>{9});
  CHECK(array_chunks({4, 5}, default_max_array_size).size() == 1);

  CHECK(parse_max_array_size("Configuration data as of 2026-12-04T09:00:00\nMaxArraySize            = 40001\n"
                             "MaxJobCount             = 10000\n") == 40001);
  CHECK(parse_max_array_size("MaxJobCount = 10000\n") == std::nullopt);
  CHECK(parse_max_array_size("MaxArraySize = many\n") == std::nullopt);
}

TEST_CASE("a study's shard folder names its files after the store, the study, the job and the task") {
  const ShardFolder folder("/data/x/../runs.sqlite", 3);
  CHECK(folder.path() == "/data/runs.sqlite.shards/study-3");
  CHECK(folder.template_store() == "/data/runs.sqlite.shards/study-3/study.sqlite");
  CHECK(folder.shard(812, 7) == "/data/runs.sqlite.shards/study-3/task-7.job-812.sqlite");
  CHECK(folder.unfinished(812, 7) == "/data/runs.sqlite.shards/study-3/task-7.job-812.sqlite.part");
  CHECK(folder.log(812, 7) == "/data/runs.sqlite.shards/study-3/logs/812_7.log");
  CHECK(folder.script(2) == "/data/runs.sqlite.shards/study-3/submit-2.sh");

  const auto finished = ShardFolder::parse(folder.shard(812, 7));
  REQUIRE(finished);
  CHECK(finished->job == 812);
  CHECK(finished->task == 7);
  CHECK(finished->finished);
  const auto part = ShardFolder::parse(folder.unfinished(9, 0));
  REQUIRE(part);
  CHECK((part->job == 9 && part->task == 0 && !part->finished));
  for (const char* other : {"study.sqlite", "task-1.job-.sqlite", "task-x.job-2.sqlite", "task-1.job-2.sqlite-wal",
                            "task--1.job-2.sqlite", "task-1.job-2.db", "submit-1.sh"}) {
    CAPTURE(other);
    CHECK(!ShardFolder::parse(other));
  }

  test::TempDir dir("slurm-folder");
  const ShardFolder here(dir.path());
  for (const auto& file : {here.shard(12, 3), here.unfinished(12, 3), here.shard(4, 10), here.unfinished(12, 1),
                           here.template_store(), dir / "task-1.job-1.sqlite-journal"}) {
    std::ofstream(file) << "x";
  }
  const auto found = here.scan();
  REQUIRE(found.size() == 4);
  CHECK((found[0].job == 4 && found[0].task == 10 && found[0].finished));
  CHECK((found[1].job == 12 && found[1].task == 1 && !found[1].finished));
  CHECK((found[2].job == 12 && found[2].task == 3 && !found[2].finished));
  CHECK((found[3].job == 12 && found[3].task == 3 && found[3].finished));
}

TEST_CASE("the Slurm options are checked, naming the option and what is valid") {
  for (const char* good : {"30", "30:00", "2:00:00", "1-12", "1-12:30", "1-0:30:00", "UNLIMITED", "infinite"}) {
    CAPTURE(good);
    CHECK(parse_time_limit(good) == good);
  }
  for (const char* bad : {"", "1h", "2:00:00:00", "-5", "1-", "30 ", "1:2:3:4", "UNLIMITEDx", "never"}) {
    CAPTURE(bad);
    CHECK_THROWS_WITH_AS(parse_time_limit(bad), doctest::Contains("--time '"), InputError);
  }
  CHECK(parse_partition("short,long") == "short,long");
  CHECK_THROWS_WITH_AS(parse_partition("a b"), doctest::Contains("--partition 'a b': a partition name"), InputError);
  CHECK_THROWS_AS(parse_partition(""), InputError);
  CHECK(parse_account("lab-42") == "lab-42");
  CHECK_THROWS_AS(parse_account("lab;rm"), InputError);
  for (const char* good : {"$TMPDIR", "${TMPDIR:-/tmp}/pdamp", "/scratch/local", "$SLURM_TMPDIR"}) {
    CAPTURE(good);
    CHECK(parse_scratch(good) == good);
  }
  for (const char* bad : {"$(rm -rf x)", "`id`", "a b", "/tmp;id", "\"x\"", ""}) {
    CAPTURE(bad);
    CHECK_THROWS_WITH_AS(parse_scratch(bad), doctest::Contains("--scratch '"), InputError);
  }
}

TEST_CASE("the job script: one array task per point, from 0, throttled, with the options and the task command") {
  JobScriptRequest request{7,
                           "fill study",
                           "/opt/pdamp's build/pdamp",
                           ShardFolder("/data/runs.sqlite", 7),
                           {9, 1, 2, 3, 5},
                           {"short", "lab", "1:00:00", 4, 2, "$TMPDIR"}};
  const std::string script = job_script(request);
  CHECK(script.starts_with("#!/bin/bash\n"));
  for (const char* line :
       {"#SBATCH --job-name=pdamp-study-7\n", "#SBATCH --array=0-4%4\n", "#SBATCH --ntasks=1\n",
        "#SBATCH --cpus-per-task=2\n", "#SBATCH --output=/data/runs.sqlite.shards/study-7/logs/%A_%a.log\n",
        "#SBATCH --partition=short\n", "#SBATCH --account=lab\n", "#SBATCH --time=1:00:00\n",
        ("\nexec '/opt/pdamp'\\''s build/pdamp' study task '/data/runs.sqlite.shards/study-7' --job "
         "\"$SLURM_ARRAY_JOB_ID\" --task \"$SLURM_ARRAY_TASK_ID\" --points 1-3,5,9 --threads "
         "\"${SLURM_CPUS_PER_TASK:-1}\" --checkpoint-every '60' "
         "--scratch \"$TMPDIR\"\n")}) {
    CAPTURE(line);
    CHECK(contains(script, line));
  }
  // The #SBATCH lines come before the first command, as sbatch reads them.
  CHECK(script.rfind("#SBATCH") < script.find("\nexec "));

  // Options not given leave the cluster's defaults.
  request.options = {};
  request.options.checkpoint_every = "0.5";
  const std::string plain = job_script(request);
  CHECK(contains(plain, " --checkpoint-every '0.5'\n"));
  CHECK(contains(plain, "#SBATCH --array=0-4\n"));
  for (const char* absent : {"--partition", "--account", "--time", "--scratch"}) CHECK(!contains(plain, absent));

  // A folder that #SBATCH lines cannot hold is refused.
  for (const char* store : {"/data/my runs.sqlite", "/data/100%.sqlite", "/data/it's.sqlite"}) {
    CAPTURE(store);
    request.folder = ShardFolder(store, 7);
    CHECK_THROWS_WITH_AS(job_script(request), doctest::Contains("that a job script's #SBATCH lines cannot hold"),
                         InputError);
  }
}

TEST_CASE("Slurm's answers: sbatch's job id, squeue's and sacct's task states") {
  CHECK(parse_job_id("4711\n") == 4711);
  CHECK(parse_job_id("4711;cluster\n") == 4711);
  CHECK_THROWS_AS(parse_job_id("Submitted batch job 4711\n"), RuntimeFailure);
  CHECK_THROWS_AS(parse_job_id(""), RuntimeFailure);

  const TaskStates queue =
      parse_queue("12|3|RUNNING\n12|[4-6,9%2]|PENDING\n99|1|RUNNING\ngarbage\n13|2|COMPLETED\n", {12, 13});
  CHECK(queue.size() == 6);
  CHECK(queue.at({12, 3}) == "RUNNING");
  CHECK(queue.at({12, 5}) == "PENDING");
  CHECK(queue.at({12, 9}) == "PENDING");
  CHECK(queue.at({13, 2}) == "COMPLETED");
  CHECK(!queue.contains({99, 1}));

  const TaskStates accounting =
      parse_accounting("12_3|COMPLETED\n12_4|CANCELLED by 0\n12_[5-6]|PENDING\n12|RUNNING\n7_1|FAILED\n", {12});
  CHECK(accounting.size() == 4);
  CHECK(accounting.at({12, 4}) == "CANCELLED");
  CHECK(accounting.at({12, 6}) == "PENDING");

  CHECK(in_flight("PENDING"));
  CHECK(in_flight("RUNNING"));
  CHECK(!in_flight("COMPLETED"));
  CHECK(!in_flight("CANCELLED"));
  CHECK(!in_flight(""));
}

TEST_CASE("a program runs without a shell, its output and exit code captured, and is stopped when late") {
  const ProgramResult r = run_program({"sh", "-c", "echo out; echo err >&2; exit 3"});
  CHECK(r.exit_code == 3);
  CHECK(r.out == "out\n");
  CHECK(r.err == "err\n");
  CHECK(run_program({"echo", "a b", "$HOME"}).out == "a b $HOME\n");
  CHECK(find_program("sh"));
  CHECK(!find_program("pdamp-no-such-program"));
  CHECK_THROWS_WITH_AS(run_program({"pdamp-no-such-program"}), doctest::Contains("cannot run"), RuntimeFailure);
  const auto started = std::chrono::steady_clock::now();
  CHECK_THROWS_WITH_AS(run_program({"sleep", "20"}, std::chrono::milliseconds(300)),
                       doctest::Contains("did not answer"), RuntimeFailure);
  CHECK(std::chrono::steady_clock::now() - started < std::chrono::seconds(5));
}

TEST_CASE("collect merges every table a shard's point has, and leaves the study's definition alone") {
  test::TempDir dir("slurm-tables");
  RunStore store(dir / "runs.sqlite");
  sqlite::Database db(store.file());
  sqlite::Statement tables(db, "SELECT name FROM sqlite_schema WHERE type = 'table' ORDER BY name");
  int n = 0;
  while (tables.step()) {
    const std::string name = tables.column_text(0);
    CAPTURE(name);
    const auto in = [&](std::span<const std::string_view> list) { return std::count(list.begin(), list.end(), name); };
    CHECK(in(merged_tables()) + in(unmerged_tables()) == 1);
    ++n;
  }
  CHECK(static_cast<std::size_t>(n) == merged_tables().size() + unmerged_tables().size());
}

namespace {

/// A study of small.ini's hard model, `points` host dampings, in a store of its own.
struct ShardedStudy {
  ShardedStudy(const test::TempDir& dir, const std::string& name, int points, const std::string& store_name)
      : db(dir / store_name), store(db) {
    const auto file = dir / (name + ".ini");
    test::write_file(file, "[study]\nname = " + name + "\nscenario = " + test::small() +
                               "\nmodels = hard\n[sweep]\nhost.damping_N_s_m = 0.1:0.4:" + std::to_string(points) +
                               "\nrun.duration_s = 0.05\n");
    const study::Study study = study::make_study(study::read_study_source(file), false);
    id = study::find_or_create_study(store, study);
    record = *StudyStore(store).study(id);
    folder = ShardFolder(db, id);
    std::filesystem::create_directories(folder.logs());
    write_folder_study(folder, store, record);
  }
  /// Runs point `point` as the task of that index of job `job` into its shard, as `pdamp
  /// study task` does (any index may run any point; this one keeps the names readable).
  ShardTaskResult task(std::int64_t job, std::int64_t point) const {
    return run_shard_task({folder, job, point, point, {}}, study::PointRunControl{});
  }
  std::int64_t count(const std::string& sql) { return test::count_rows(db, sql); }

  std::filesystem::path db;
  RunStore store;
  std::int64_t id = 0;
  StudyRecord record;
  ShardFolder folder{std::filesystem::path()};
};

/// Changes a shard file by SQL.
void tamper(const std::filesystem::path& shard, const std::string& sql) {
  sqlite::Database db(shard);
  db.exec(sql);
}

}  // namespace

TEST_CASE("the store's functions for the Slurm layer: the next study id, a self-contained file, a template's studies") {
  test::TempDir dir("slurm-store");
  {
    RunStore empty(dir / "empty.sqlite");
    CHECK(StudyStore(empty).next_study_id() == 1);
    empty.make_self_contained();
    sqlite::Database db(empty.file(), sqlite::Access::snapshot);
    sqlite::Statement mode(db, "PRAGMA journal_mode");
    REQUIRE(mode.step());
    CHECK(mode.column_text(0) == "delete");
  }
  CHECK_FALSE(std::filesystem::exists(dir / "empty.sqlite-wal"));
  ShardedStudy s(dir, "ids", 2, "runs.sqlite");
  CHECK(StudyStore(s.store).next_study_id() == s.id + 1);
  // The template the tasks read: whole by itself, the study as the store holds it.
  CHECK_FALSE(std::filesystem::exists(s.folder.template_store().string() + "-wal"));
  const StoreFileStudies held = read_store_studies(s.folder.template_store());
  CHECK(held.schema_version == RunStore::schema_version());
  REQUIRE(held.studies.size() == 1);
  CHECK(held.studies[0].study_id == s.id);
  CHECK(held.studies[0].name == "ids");
}

TEST_CASE("collect merges finished shards once, shares their beds, keeps completed points and refuses strangers") {
  test::TempDir dir("slurm-collect");
  ShardedStudy s(dir, "sharded", 4, "runs.sqlite");
  for (int t = 1; t <= 4; ++t) {
    const ShardTaskResult r = s.task(50, t);
    CHECK(r.point.status == PointStatus::completed);
    CHECK(r.shard == s.folder.shard(50, t));
  }
  // The store was not touched by the tasks.
  CHECK(s.count("SELECT count(*) FROM runs") == 0);
  // Task 4's bed is not the one the others settled: refused, nothing of it added.
  tamper(s.folder.shard(50, 4), "UPDATE initial_particles SET x_m = x_m + 1e-12 WHERE particle = 7");

  CollectReport report = collect_shards(s.store, s.record, {s.folder});
  REQUIRE(report.merged.size() == 3);
  CHECK(report.already_collected == 0);
  REQUIRE(report.refused.size() == 1);
  CHECK(contains(report.refused[0], "task-4.job-50.sqlite': its settled bed differs from the store's bed"));
  CHECK(report.merged[0].beds_added == 1);
  CHECK(report.merged[1].beds_shared == 1);
  CHECK(report.merged[2].beds_shared == 1);
  CHECK(s.count("SELECT count(*) FROM initial_states") == 1);
  CHECK(s.count("SELECT count(*) FROM runs WHERE status = 'completed'") == 3);
  CHECK(s.count("SELECT count(*) FROM runs r JOIN initial_states b ON b.state_id = r.initial_state_id") == 3);
  CHECK(s.count("SELECT count(*) FROM study_points WHERE status = 'completed' AND attempt = 1") == 3);
  CHECK(s.count("SELECT count(*) FROM study_point_metrics") == 3);
  CHECK(s.count("SELECT count(*) FROM study_tasks WHERE collected_at IS NOT NULL AND outcome = 'completed' "
                "AND host <> '' AND started_at <= ended_at") == 3);
  // Every sample and cycle of the shards, and nothing else.
  CHECK(s.count("SELECT count(*) FROM samples") == 3 * 101);
  CHECK(s.count("SELECT count(*) FROM cycles") ==
        test::count_rows(s.folder.shard(50, 1), "SELECT count(*) FROM cycles") +
            test::count_rows(s.folder.shard(50, 2), "SELECT count(*) FROM cycles") +
            test::count_rows(s.folder.shard(50, 3), "SELECT count(*) FROM cycles"));

  // Again: nothing is added.
  const auto rows = [&] { return s.count("SELECT (SELECT count(*) FROM runs) + (SELECT count(*) FROM samples)"); };
  const std::int64_t before = rows();
  report = collect_shards(s.store, s.record, {s.folder});
  CHECK(report.merged.empty());
  CHECK(report.already_collected == 3);
  CHECK(report.refused.size() == 1);
  CHECK(rows() == before);

  // Point 2 run again in another job: the store keeps its first results.
  CHECK(s.task(51, 2).point.status == PointStatus::completed);
  // Point 4 run again, its bed as the others'.
  CHECK(s.task(51, 4).point.status == PointStatus::completed);
  report = collect_shards(s.store, s.record, {s.folder});
  REQUIRE(report.merged.size() == 2);
  CHECK(!report.merged[0].results_added);
  CHECK(contains(report.merged[0].not_added, "point 2 was completed already"));
  CHECK(report.merged[1].results_added);
  CHECK(report.merged[1].beds_shared == 1);
  CHECK(s.count("SELECT count(*) FROM runs") == 4);
  CHECK(s.count("SELECT count(*) FROM study_points WHERE status = 'completed'") == 4);
  CHECK(s.count("SELECT count(*) FROM study_tasks WHERE job_id = 51 AND message LIKE '%completed already%'") == 1);

  // Shards that are not this study's, refused with the reason; nothing added.
  const auto stranger = [&](int task, const std::string& sql) {
    const auto file = s.folder.shard(60, task);
    std::filesystem::copy_file(s.folder.shard(50, 3), file);
    tamper(file, "UPDATE study_tasks SET job_id = 60, task = " + std::to_string(task) + "; " + sql);
  };
  stranger(2, "PRAGMA user_version = 99");
  stranger(3, "CREATE TABLE extra (x)");
  stranger(4, "UPDATE studies SET created_at = '2020-01-01T00:00:00.000Z'");
  std::ofstream(s.folder.shard(60, 1)) << "not a store";
  ShardedStudy other(dir, "other", 2, "other.sqlite");
  other.task(70, 1);
  std::filesystem::copy_file(other.folder.shard(70, 1), s.folder.shard(70, 1));
  report = collect_shards(s.store, s.record, {s.folder});
  // Task 4 of job 50, refused for its bed, is now recorded without its results: its point
  // was completed by job 51.
  REQUIRE(report.merged.size() == 1);
  CHECK((report.merged[0].task.job_id == 50 && !report.merged[0].results_added));
  REQUIRE(report.refused.size() == 5);
  const std::string all =
      report.refused[0] + report.refused[1] + report.refused[2] + report.refused[3] + report.refused[4];
  INFO(all);
  CHECK(contains(all, "task-1.job-60.sqlite' is not a pdamp store"));
  CHECK(contains(all, "has schema version 99, the store " + std::to_string(RunStore::schema_version()) +
                          ": it was written by another version of pdamp"));
  CHECK(contains(all, "but other tables than the store's"));
  CHECK(contains(all, "belongs to study 1 'sharded' created 2020-01-01T00:00:00.000Z, not to study 1 'sharded'"));
  CHECK(contains(all, "task-1.job-70.sqlite' belongs to study 1 'other'"));
  CHECK(rows() == before + 1 + 101);  // point 4 of job 51: one run and its samples
}

TEST_CASE("a stopped task ends its point as interrupted and still puts its shard in place") {
  test::TempDir dir("slurm-stopped");
  ShardedStudy s(dir, "stopped", 2, "runs.sqlite");
  std::atomic<bool> stop{true};
  study::PointRunControl control;
  control.stop = &stop;
  const ShardTaskResult r = run_shard_task({s.folder, 8, 2, 2, {}}, control);
  CHECK(r.point.status == PointStatus::interrupted);
  CHECK(std::filesystem::exists(s.folder.shard(8, 2)));
  CHECK(!std::filesystem::exists(s.folder.unfinished(8, 2)));
  const CollectReport report = collect_shards(s.store, s.record, {s.folder});
  REQUIRE(report.merged.size() == 1);
  CHECK(report.merged[0].task.outcome == PointStatus::interrupted);
  CHECK(s.count("SELECT count(*) FROM study_points WHERE point = 2 AND status = 'interrupted' AND attempt = 1") == 1);
  // Resubmitted, it completes as the point's second attempt.
  s.task(9, 2);
  collect_shards(s.store, s.record, {s.folder});
  CHECK(s.count("SELECT count(*) FROM study_points WHERE point = 2 AND status = 'completed' AND attempt = 2") == 1);
  CHECK(s.count("SELECT count(*) FROM study_point_runs WHERE point = 2") == 2);

  // A task that ran another point than its job was submitted to run is refused.
  StudyStore(s.store).record_job(s.id, {80, "", "submit-3.sh", s.folder.path().string()}, {{0, 1}});
  CHECK(run_shard_task({s.folder, 80, 0, 2, {}}, study::PointRunControl{}).point.status == PointStatus::completed);
  const CollectReport mismatch = collect_shards(s.store, s.record, {s.folder});
  CHECK(mismatch.merged.empty());
  REQUIRE(mismatch.refused.size() == 1);
  CHECK(contains(mismatch.refused[0], "ran point 2 as task 0 of job 80, which was submitted to run point 1"));

  // A task that is not a point of the study, or a folder without its study, writes nothing.
  CHECK_THROWS_WITH_AS(s.task(9, 3), doctest::Contains("task 3: point 3: study 1 has points 1 to 2"), InputError);
  CHECK_THROWS_WITH_AS(run_shard_task({ShardFolder(dir / "nowhere"), 1, 1, 1, {}}, control),
                       doctest::Contains("is missing: a shard folder's study is written by 'pdamp study submit'"),
                       InputError);
  CHECK(!std::filesystem::exists(s.folder.unfinished(9, 3)));
}

TEST_CASE("a task writes its shard in scratch space and copies it to the folder at the end") {
  test::TempDir dir("slurm-scratch");
  ShardedStudy s(dir, "scratch", 2, "runs.sqlite");
  const auto scratch = dir / "node" / "tmp";
  const ShardTaskResult r = run_shard_task({s.folder, 3, 1, 1, scratch}, study::PointRunControl{});
  CHECK(r.point.status == PointStatus::completed);
  CHECK(std::filesystem::is_empty(scratch));
  CHECK(test::count_rows(s.folder.shard(3, 1), "SELECT count(*) FROM samples") == 101);
  // One self-contained file: a rollback journal's (bytes 18 and 19 of the header are 1, not
  // WAL's 2), and no journal beside it.
  std::ifstream in(s.folder.shard(3, 1), std::ios::binary);
  char header[20] = {};
  in.read(header, sizeof header);
  CHECK((header[18] == 1 && header[19] == 1));
  CHECK(!std::filesystem::exists(s.folder.shard(3, 1).string() + "-wal"));
}

namespace {

/// A study of two curves of three points each (points 1-3 and 4-6; `sections` on small.ini's
/// hard model) as Slurm runs it, against the same study run here point by point, as `pdamp
/// study run`'s workers run them: a task per curve, the second stopped in its first point
/// once its run has a checkpoint (as Slurm's SIGTERM stops a task); collected; points 2 and
/// 3 made to run again (their runs deleted), so that the first curve resumes from point 1's
/// final state, which the folder's study then holds, as it holds point 4's interrupted run;
/// both curves resubmitted (the second continuing point 4's run from its checkpoint) and
/// collected. Every metric that `metric_differences` compares, every sample and every run
/// are the same bits.
void check_curves_on_shards(
    const test::TempDir& dir, const std::string& sections,
    const std::function<std::int64_t(const std::filesystem::path&, const std::filesystem::path&)>& metric_differences) {
  const auto file = dir / "curves.ini";
  test::write_file(file, "[study]\nname = curves\nscenario = " + test::small() + "\nmodels = hard\n\n" + sections);
  const study::Study study = study::make_study(study::read_study_source(file), false);
  REQUIRE(study.points.size() == 6);
  const auto reference = dir / "reference.sqlite";
  {
    RunStore store(reference);
    const std::int64_t id = study::find_or_create_study(store, study);
    for (int p = 1; p <= 6; ++p) {
      REQUIRE(study::run_study_point(store, id, study, p, {}).status == PointStatus::completed);
    }
  }
  const auto db = dir / "runs.sqlite";
  RunStore store(db);
  StudyStore studies(store);
  const std::int64_t id = study::find_or_create_study(store, study);
  const StudyRecord record = *studies.study(id);
  CHECK(studies.curve_from(id, 1) == std::vector<int>{1, 2, 3});
  CHECK(studies.curve_from(id, 5) == std::vector<int>{5, 6});
  CHECK(points_to_submit(studies, id, {}) == std::vector<std::int64_t>{1, 4});
  const ShardFolder folder(db, id);
  std::filesystem::create_directories(folder.logs());
  write_folder_study(folder, store, record);
  std::vector<int> started;
  ShardTaskResult curve =
      run_shard_task({folder, 10, 0, 1, {}}, study::PointRunControl{}, [&](int point) { started.push_back(point); });
  CHECK(started == std::vector<int>{1, 2, 3});
  CHECK(curve.points_completed == 3);
  CHECK(curve.last_point == 3);
  std::atomic<bool> stop{false};
  study::PointRunControl stopped;
  stopped.stop = &stop;
  stopped.checkpoint_interval = std::chrono::milliseconds(60'000);  // and at the stop
  stopped.progress = [&](double, std::string_view phase) { stop = stop || phase != "settling"; };
  curve = run_shard_task({folder, 10, 1, 4, {}}, stopped);
  CHECK(curve.point.status == PointStatus::interrupted);
  CHECK(curve.points_completed == 0);
  CHECK(curve.last_point == 4);
  CollectReport report = collect_shards(store, record, {folder});
  REQUIRE(report.merged.size() == 2);
  CHECK(report.merged[0].points == 3);
  CHECK(report.merged[0].runs == 3);
  // The settled bed and three final states (a predicted start is its run's shift of one).
  CHECK(report.merged[0].beds_added == 4);
  CHECK(report.merged[1].points == 1);
  CHECK(report.merged[1].task.outcome == PointStatus::interrupted);
  const auto status_of = [&](int point) { return studies.point(id, point)->status; };
  CHECK(status_of(3) == PointStatus::completed);
  CHECK(status_of(4) == PointStatus::interrupted);
  CHECK(status_of(5) == PointStatus::pending);
  CHECK(test::count_rows(db, "SELECT count(*) FROM study_point_states") == 3);
  const std::int64_t interrupted_run = test::count_rows(db, "SELECT run_id FROM study_point_runs WHERE point = 4");
  CHECK(test::count_rows(
            db, "SELECT count(*) FROM run_checkpoints WHERE run_id = " + std::to_string(interrupted_run)) == 1);

  std::vector<std::int64_t> runs;
  {
    sqlite::Database d(db);
    sqlite::Statement q(d, "SELECT run_id FROM study_point_runs WHERE point IN (2, 3)");
    while (q.step()) runs.push_back(q.column_int(0));
  }
  REQUIRE(runs.size() == 2);
  store.delete_runs(runs, false);
  CHECK(points_to_submit(studies, id, {}) == std::vector<std::int64_t>{2, 4});
  CHECK(continued_points(studies, id) == std::vector<int>{1});
  write_folder_study(folder, store, record);
  CHECK(test::count_rows(folder.template_store(), "SELECT count(*) FROM study_point_states") == 1);
  CHECK(test::count_rows(folder.template_store(),
                         "SELECT count(*) FROM study_point_runs JOIN run_checkpoints USING (run_id) WHERE point = 4 "
                         "AND attempt = 0 AND run_id = " +
                             std::to_string(interrupted_run)) == 1);
  CHECK(run_shard_task({folder, 11, 0, 2, {}}, study::PointRunControl{}).points_completed == 2);
  std::vector<std::string> warnings;
  study::PointRunControl resumed;
  resumed.warn = [&](const std::string& warning) { warnings.push_back(warning); };
  CHECK(run_shard_task({folder, 11, 1, 4, {}}, resumed).points_completed == 3);
  CHECK(warnings.empty());
  // The task took the store's interrupted run over and continued it from its checkpoint.
  CHECK(test::count_rows(folder.shard(11, 1), "SELECT run_id FROM study_point_runs WHERE point = 4 AND attempt = 1") ==
        interrupted_run);
  report = collect_shards(store, record, {folder});
  REQUIRE(report.merged.size() == 2);
  CHECK(report.merged[0].points == 2);
  // Point 2's start, the store's: point 1's final state, or (start = predict) the start
  // predicted from it again, whose label names point 1's run by its id in the store, as
  // the first shard's did once collected.
  CHECK(report.merged[0].beds_shared == 1);
  CHECK(report.merged[1].points == 3);
  CHECK(report.refused.empty());
  for (int p = 1; p <= 6; ++p) CHECK(status_of(p) == PointStatus::completed);
  CHECK(metric_differences(reference, db) == 0);
  CHECK(metric_differences(db, reference) == 0);
  const auto [differing, compared] = test::sample_differences(reference, db);
  CHECK(compared > 6 * 10);
  CHECK(differing == 0);
  CHECK(test::run_differences(reference, db).first == 0);
  // Each completed point's final state is its run's, labelled by the store's run id.
  CHECK(test::count_rows(db,
                         "SELECT count(*) FROM study_point_states s JOIN initial_states i USING (state_id) "
                         "WHERE i.settle_key LIKE '% point end: run ' || s.run_id") == 6);
  const CollectReport again = collect_shards(store, record, {folder});
  CHECK(again.merged.empty());
  CHECK(again.already_collected == 4);
}

std::int64_t frf_differences(const std::filesystem::path& a, const std::filesystem::path& b) {
  return test::frf_metric_differences(a, b);
}

}  // namespace

TEST_CASE("an [frf] study on Slurm: a task per curve, a curve resumed from its last completed point, the same bits") {
  test::TempDir dir("slurm-frf");
  check_curves_on_shards(dir,
                         "[frf]\nmode = force\nhost.z0_m = 0\nparticles.count = 20\nlevels = 0.05, 0.2\n"
                         "frequencies = 15, 17, 19\nmax_cycles = 20\n",
                         frf_differences);
}

// Resumed from point 1, the first curve's point 2 is predicted from point 1's metrics, which
// the folder's study must hold beside its final state.
TEST_CASE(
    "a start = predict [frf] curve on Slurm resumed mid-curve: predicted from the copied metrics, the same bits") {
  test::TempDir dir("slurm-frf-predict");
  check_curves_on_shards(dir,
                         "[frf]\nmode = force\nhost.z0_m = 0\nparticles.count = 20\nlevels = 0.05, 0.2\n"
                         "frequencies = 15, 17, 19\nmax_cycles = 20\nstart = predict\n",
                         frf_differences);
}

// A grid of two particle counts: each count's curve is a task of its own.
TEST_CASE("an [frf] grid on Slurm: a task per curve of each key value, resumed mid-curve, the same bits") {
  test::TempDir dir("slurm-frf-grid");
  check_curves_on_shards(dir,
                         "[frf]\nmode = force\nhost.z0_m = 0\nparticles.count = 20, 10\nlevels = 0.2\n"
                         "frequencies = 15, 17, 19\nmax_cycles = 20\n",
                         frf_differences);
}

TEST_CASE("a [characterise] study on Slurm: a task per curve up the amplitudes, resumed mid-curve, the same bits") {
  test::TempDir dir("slurm-characterise");
  check_curves_on_shards(dir,
                         "[characterise]\namplitudes = 0.0005, 0.0015, 0.003\nfrequencies = 15, 20\n"
                         "amplitude_tolerance = 1e-9\nmax_cycles = 20\nmeasured_cycles = 5\n",
                         test::characterise_metric_differences);
}
