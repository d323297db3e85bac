#include "slurm_commands.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>

#include "commands.hpp"
#include "options.hpp"
#include "pdamp/slurm/collect.hpp"
#include "pdamp/slurm/program.hpp"
#include "pdamp/slurm/shard_task.hpp"
#include "pdamp/store/process_lease.hpp"
#include "pdamp/study/study_runner.hpp"
#include "subcommand.hpp"
#include "text_table.hpp"

namespace po = boost::program_options;

namespace pdamp {
namespace {

using namespace slurm;

std::string job_name(std::int64_t study_id) { return "pdamp-study-" + std::to_string(study_id); }

/// The Slurm options of `pdamp study submit`, each checked.
SlurmOptions slurm_options(const po::variables_map& vm) {
  SlurmOptions o;
  if (vm.count("partition")) o.partition = parse_partition(vm["partition"].as<std::string>());
  if (vm.count("account")) o.account = parse_account(vm["account"].as<std::string>());
  if (vm.count("time")) o.time_limit = parse_time_limit(vm["time"].as<std::string>());
  if (vm.count("max-parallel")) {
    o.max_parallel =
        static_cast<int>(parse_whole_number(vm["max-parallel"].as<std::string>(), 1, 100'000, "--max-parallel"));
  }
  o.threads = static_cast<int>(parse_whole_number(vm["threads"].as<std::string>(), 1, 1024, "--threads"));
  if (vm.count("scratch")) o.scratch = parse_scratch(vm["scratch"].as<std::string>());
  checkpoint_interval(vm);  // checked here, passed on as given
  o.checkpoint_every = vm["checkpoint-every"].as<std::string>();
  return o;
}

/// A stored study on the cluster: its store, its shard folders, and what Slurm says of its
/// tasks.
struct ClusterStudy {
  ClusterStudy(const std::string& id, const std::string& db_file, StoreAccess access)
      : db(db_file), open(id, db_file, access), folders(study_folders(open.studies, db_file, open.id)) {}
  ClusterStudy(const po::variables_map& vm, const std::string& command, StoreAccess access)
      : ClusterStudy(required_option(vm, "STUDY_ID", command), vm["db"].as<std::string>(), access) {}

  /// The tasks as they stand now, asking squeue (and sacct) where the study has jobs.
  std::vector<TaskView> tasks(bool ask_accounting) {
    std::vector<std::int64_t> jobs;
    for (const auto& job : open.studies.jobs(open.id)) jobs.push_back(job.job_id);
    if (!jobs.empty()) {
      queue = queue_states(jobs, job_name(open.id));
      if (ask_accounting) accounting = accounting_states(jobs);
    }
    return task_views(open.studies, open.id, folders, queue, accounting);
  }
  bool submitted() { return !open.studies.jobs(open.id).empty(); }
  ShardFolder folder() const { return ShardFolder(db, open.id); }

  std::string db;
  OpenStudy open;
  std::vector<ShardFolder> folders;
  SlurmReport queue, accounting;
};

/// The latest task of each point (a curve's task runs its point and the rest of its curve).
std::map<int, const TaskView*> latest_tasks(StudyStore& studies, std::int64_t study_id,
                                            const std::vector<TaskView>& tasks) {
  std::map<int, const TaskView*> latest;
  for (const auto& view : tasks) {  // by job, then task
    for (const int point : studies.curve_from(study_id, view.task.point)) latest[point] = &view;
  }
  return latest;
}

/// What is wrong with a point that is not completed, from its latest task.
std::string point_problem(const StudyPointState& point, const TaskView* view, const ShardFolder& folder) {
  if (!view) return "not submitted";
  const std::string task = "task " + std::to_string(view->task.task) + " of job " + std::to_string(view->task.job_id);
  const std::string log = " (log: " + folder.log(view->task.job_id, view->task.task).string() + ")";
  switch (view->standing) {
    case TaskStanding::collected:
      if (point.status == PointStatus::pending) {
        return "not reached by " + task + ", whose curve stopped before it (" + view->task.message + ")" + log;
      }
      return std::string(to_string(point.status)) + " in " + task + ": " + point.message + log;
    case TaskStanding::waiting:
      return task + " finished; its shard waits to be collected";
    case TaskStanding::in_queue:
      return task + " is " + view->slurm_state;
    case TaskStanding::unfinished:
      return task + " left an unfinished shard: it was killed while running" + log;
    case TaskStanding::missing:
      break;
  }
  return task + " left no shard" + (view->slurm_state.empty() ? "" : " (Slurm: " + view->slurm_state + ")") +
         ": it never ran, or died before it could write one" + log;
}

/// The points that are not completed, one line each, and how many are.
int report_points(StudyStore& studies, std::int64_t id, const std::vector<TaskView>& tasks, const ShardFolder& folder,
                  std::ostream& out) {
  const auto latest = latest_tasks(studies, id, tasks);
  int completed = 0;
  for (const auto& p : studies.points(id)) {
    if (p.status == PointStatus::completed) {
      ++completed;
      continue;
    }
    const auto it = latest.find(p.point);
    out << "pdamp: point " << p.point << ": "
        << printable(point_problem(p, it == latest.end() ? nullptr : it->second, folder)) << "\n";
  }
  return completed;
}

void report_collect(const CollectReport& report, std::ostream& out) {
  for (const auto& m : report.merged) {
    out << "pdamp: collected task " << m.task.task << " of job " << m.task.job_id << " (point " << m.task.point << ", "
        << printable(m.task.host)
        << "): " << (m.task.outcome ? std::string(to_string(*m.task.outcome)) : std::string("not ended"));
    if (m.results_added) {
      if (m.points > 1) out << ", " << m.points << " points";
      out << ", " << m.runs << " runs, " << m.beds_added << " beds added, " << m.beds_shared << " shared";
      if (!m.not_added.empty()) out << "; " << printable(m.not_added);
    } else {
      out << "; " << printable(m.not_added);
    }
    out << "\n";
  }
  for (const auto& line : report.refused) out << "pdamp: refused: " << printable(line) << "\n";
}

/// A new job script file, numbered after those in the folder.
std::filesystem::path new_script(const ShardFolder& folder, const std::string& text) {
  for (int k = 1;; ++k) {
    auto file = folder.script(k);  // not const: returned by move
    const int fd = open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0755);
    if (fd < 0 && errno == EEXIST) continue;
    if (fd < 0) throw RuntimeFailure("cannot write the job script '" + file.string() + "': " + std::strerror(errno));
    const bool written = write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
    close(fd);
    if (!written) throw RuntimeFailure("cannot write the job script '" + file.string() + "'");
    return file;
  }
}

std::filesystem::path this_executable() { return std::filesystem::read_symlink("/proc/self/exe"); }

/// What a dry run would submit: the study's id (stored, or the next) and its points to run.
std::pair<std::int64_t, std::vector<std::int64_t>> planned(const std::string& db, const study::Study& study) {
  std::vector<std::int64_t> all;  // of a new study: each point, or each curve's first
  for (const auto& p : study.points) {
    if (p.previous() == 0) all.push_back(p.point);
  }
  if (!std::filesystem::exists(db)) return {1, all};
  std::int64_t stored = 0;
  {
    RunStore store(db, StoreAccess::read);
    if (const auto record = StudyStore(store).find_study(study.file.name)) {
      study::check_same_as_stored(*record, study, store.file());
      stored = record->study_id;
    } else {
      return {StudyStore(store).next_study_id(), all};
    }
  }
  ClusterStudy cluster(std::to_string(stored), db, StoreAccess::read);
  return {stored, points_to_submit(cluster.open.studies, stored, cluster.tasks(false))};
}

/// Slurm's limit on a job array, with a note on stderr where it was assumed.
std::int64_t max_array_size() {
  const ArrayLimit limit = array_limit();
  if (!limit.problem.empty()) std::cerr << "pdamp: " << printable(limit.problem) << "\n";
  return limit.max_array_size;
}

/// "job 100 (array 0-4: points 1-5)".
std::string job_line(std::int64_t job, const std::vector<std::int64_t>& points) {
  return "job " + std::to_string(job) + " (array 0-" + std::to_string(points.size() - 1) + ": points " +
         array_ranges(points) + ")";
}

/// Whether the study's points run as curves, a task each from its first point to run.
bool runs_curves(const study::Study& study) {
  return !study.file.frfs.empty() || !study.file.characterisations.empty();
}

int dry_run(const std::string& db, const study::Study& study, const SlurmOptions& options) {
  const auto [id, points] = planned(db, study);
  if (points.empty()) {
    std::cerr << "pdamp: dry run: study " << id << " has no point to submit\n";
    return 0;
  }
  const auto arrays = array_chunks(points, max_array_size());
  for (const auto& chunk : arrays) {
    std::cout << job_script(
        {id, study.file.name, this_executable(), ShardFolder(db, id), chunk, options, runs_curves(study)});
  }
  std::cerr << "pdamp: dry run: " << arrays.size() << " job script" << (arrays.size() == 1 ? "" : "s") << " for "
            << points.size() << " points of study " << id << "; nothing was written or submitted\n";
  return 0;
}

/// Submits one job array for `points` and records it with the point of each task; returns
/// the job's line for the user.
std::string submit_array(OpenStudy& open, const ShardFolder& folder, const std::vector<std::int64_t>& points,
                         const SlurmOptions& options) {
  const auto script = new_script(folder, job_script({open.id, open.record.name, this_executable(), folder, points,
                                                     options, runs_curves(open.study)}));
  std::int64_t job = 0;
  try {
    job = submit(script);
  } catch (...) {
    std::filesystem::remove(script);
    throw;
  }
  std::vector<std::pair<std::int64_t, int>> tasks_of_job;
  for (std::size_t task = 0; task < points.size(); ++task) {
    tasks_of_job.emplace_back(static_cast<std::int64_t>(task), static_cast<int>(points[task]));
  }
  open.studies.record_job(open.id, {job, "", script.string(), folder.path().string()}, tasks_of_job);
  return job_line(job, points) + ", script " + printable(script.filename().string());
}

int submit_points(ClusterStudy& cluster, const SlurmOptions& options) {
  OpenStudy& open = cluster.open;
  const CollectReport collected = collect_shards(open.store, open.record, cluster.folders);
  report_collect(collected, std::cerr);
  if (!collected.refused.empty()) {
    throw RuntimeFailure(
        "the shards refused above stay in the way: move them out of the shard folder, then submit "
        "again; nothing was submitted");
  }
  const auto tasks = cluster.tasks(false);
  if (cluster.submitted() && !cluster.queue.available) {
    throw RuntimeFailure("cannot tell which of the study's tasks are still queued (" + cluster.queue.problem +
                         "); nothing was submitted");
  }
  const auto points = points_to_submit(open.studies, open.id, tasks);
  if (points.empty()) {
    std::cerr << "pdamp: study " << open.id << " has no point to submit: every point is completed or queued ('pdamp "
              << "study status " << open.id << "')\n";
    return 0;
  }
  // More points than one array may hold go as several arrays, each recorded as it is
  // submitted: a refusal part way leaves the arrays before it recorded, and says so.
  const auto arrays = array_chunks(points, max_array_size());
  const ShardFolder folder = cluster.folder();
  std::filesystem::create_directories(folder.logs());
  write_folder_study(folder, open.store, open.record);
  std::vector<std::string> submitted;
  std::size_t n_submitted = 0;
  for (const auto& chunk : arrays) {
    try {
      submitted.push_back(submit_array(open, folder, chunk, options));
      n_submitted += chunk.size();
    } catch (const RuntimeFailure& e) {
      if (submitted.empty()) throw;
      std::string done;
      for (const auto& line : submitted) done += (done.empty() ? "" : ", ") + line;
      throw RuntimeFailure(std::string(e.what()) + "; " + std::to_string(n_submitted) + " of " +
                           std::to_string(points.size()) + " points were submitted and recorded before (" + done +
                           "); 'pdamp study submit --resume " + std::to_string(open.id) + " --slurm' submits the rest");
    }
  }
  std::cout << "study " << open.id << " '" << printable(open.record.name) << "': " << points.size()
            << (runs_curves(open.study) ? " curves (each from its first point to run)" : " points") << " submitted as "
            << arrays.size() << " job array" << (arrays.size() == 1 ? "" : "s") << "\n";
  for (const auto& line : submitted) std::cout << "  " << line << "\n";
  std::cout << "  shard folder   " << printable(folder.path().string()) << "\n"
            << "then: pdamp study status " << open.id << ", pdamp study collect " << open.id << "\n";
  return 0;
}

void add_submit_options(Subcommand& command) {
  command.add_options()("slurm", "submit to Slurm (sbatch), the scheduler pdamp submits to")(
      "resume", po::value<std::string>(), "STUDY_ID: submit the stored study's points that are missing or failed")(
      "partition", po::value<std::string>(), "the partition (default: the cluster's)")(
      "account", po::value<std::string>(), "the account charged (default: yours)")(
      "time", po::value<std::string>(), "the time limit of each task, e.g. 30 or 2:00:00 (default: the partition's)")(
      "max-parallel", po::value<std::string>(), "tasks running at once (the array's %K; default: Slurm's limit)")(
      "threads", po::value<std::string>()->default_value("1"),
      "cores per task (--cpus-per-task), the soft engine's threads; results are the same bits for any number")(
      "scratch", po::value<std::string>(),
      "a folder on the compute node to write each shard in, copied to the shard folder at the end, e.g. '$TMPDIR' "
      "(default: written in the shard folder)")("force", "submit a study of more than 1000 points")(
      "dry-run", "print the job script; write and submit nothing");
  command.add(checkpoint_option());
}

/// `pdamp study task`'s progress in its log: a line each tenth of the point it runs (a
/// curve's task runs several, one after the other).
struct ProgressLines {
  void start(int p) {
    point = p;
    last = -1;
  }
  void operator()(double fraction, std::string_view phase) {
    const int tenth = static_cast<int>(fraction * 10.0);
    if (tenth == last) return;
    last = tenth;
    std::cout << "pdamp: point " << point << ": " << phase << " " << 10 * tenth << " %" << std::endl;
  }
  int point = 0, last = -1;
};

}  // namespace

int study_submit(const std::vector<std::string>& args) {
  Subcommand command(
      "pdamp study submit STUDY.ini --slurm [options]\n  pdamp study submit --resume STUDY_ID --slurm [options]",
      {"STUDY.ini"});
  add_submit_options(command);
  if (!command.parse(args)) return 0;
  const auto& vm = command.vm();
  if (!vm.count("slurm")) throw InputError("pdamp study submit: --slurm is required (the scheduler to submit to)");
  if (vm.count("resume") == vm.count("STUDY.ini")) {
    throw InputError("pdamp study submit: give a STUDY.ini or --resume STUDY_ID (one of the two)");
  }
  const SlurmOptions options = slurm_options(vm);
  const std::string db = vm["db"].as<std::string>();
  checked_script_path(ShardFolder(db, 1).path());
  if (vm.count("resume")) {
    if (vm.count("dry-run"))
      return dry_run(db, OpenStudy(vm["resume"].as<std::string>(), db, StoreAccess::read).study, options);
    ClusterStudy cluster(vm["resume"].as<std::string>(), db, StoreAccess::modify);
    check_study_files(cluster.open);
    return submit_points(cluster, options);
  }
  // Everything that can be wrong with the study is found before the store is touched.
  study::Study study =
      study::make_study(study::read_study_source(vm["STUDY.ini"].as<std::string>()), vm.count("force") > 0);
  study::validate_study(study);
  if (vm.count("dry-run")) return dry_run(db, study, options);
  if (!find_program("sbatch")) {
    throw RuntimeFailure(
        "sbatch is not installed here: submit from a machine of the Slurm cluster (a login node); "
        "nothing was written");
  }
  std::int64_t id = 0;
  {
    RunStore store(db);
    id = study::find_or_create_study(store, study);
  }
  ClusterStudy cluster(std::to_string(id), db, StoreAccess::modify);
  return submit_points(cluster, options);
}

int study_collect(const std::vector<std::string>& args) {
  Subcommand command("pdamp study collect STUDY_ID [--db FILE]", {"STUDY_ID"});
  if (!command.parse(args)) return 0;
  ClusterStudy cluster(command.vm(), "study collect", StoreAccess::modify);
  OpenStudy& open = cluster.open;
  const CollectReport report = collect_shards(open.store, open.record, cluster.folders);
  report_collect(report, std::cout);
  const int completed = report_points(open.studies, open.id, cluster.tasks(false), cluster.folder(), std::cout);
  std::cout << "study " << open.id << " '" << printable(open.record.name) << "': " << completed << " of "
            << open.study.points.size() << " points completed; " << report.merged.size() << " shards collected now, "
            << report.already_collected << " before"
            << (report.refused.empty() ? "" : ", " + std::to_string(report.refused.size()) + " refused") << "\n";
  if (cluster.submitted() && !cluster.queue.available) {
    std::cout << "pdamp: the queue was not asked (" << printable(cluster.queue.problem) << ")\n";
  }
  return report.refused.empty() ? 0 : 1;
}

int study_status(const std::vector<std::string>& args) {
  Subcommand command("pdamp study status STUDY_ID [--db FILE]", {"STUDY_ID"});
  if (!command.parse(args)) return 0;
  ClusterStudy cluster(command.vm(), "study status", StoreAccess::read);
  OpenStudy& open = cluster.open;
  const auto tasks = cluster.tasks(true);
  const auto latest = latest_tasks(open.studies, open.id, tasks);
  TextTable table({{"point", true}, {"status"}, {"job_task"}, {"slurm"}, {"shard"}, {"message", false, 80}});
  for (const auto& p : open.studies.points(open.id)) {
    const auto it = latest.find(p.point);
    const TaskView* view = it == latest.end() ? nullptr : it->second;
    table.add_row({std::to_string(p.point), std::string(to_string(p.status)),
                   view ? std::to_string(view->task.job_id) + "_" + std::to_string(view->task.task) : "-",
                   view && !view->slurm_state.empty() ? view->slurm_state : "-",
                   view ? std::string(to_string(view->standing)) : "-",
                   p.status == PointStatus::completed ? "" : point_problem(p, view, cluster.folder())});
  }
  const auto summary = open.studies.summary(open.id);
  std::cout << "study " << open.id << " '" << printable(open.record.name) << "': " << summary->completed << " of "
            << summary->n_points << " points completed, " << open.studies.jobs(open.id).size() << " jobs submitted\n";
  table.print(std::cout);
  if (cluster.submitted()) {
    if (!cluster.queue.available) std::cout << printable(cluster.queue.problem) << "; queue states unknown\n";
    if (!cluster.accounting.available) {
      std::cout << printable(cluster.accounting.problem)
                << "; tasks that left the queue are known from their shards only\n";
    }
  }
  return 0;
}

int study_task(const std::vector<std::string>& args) {
  Subcommand command("pdamp study task SHARD_FOLDER --job J --task T --points LIST [options]", {"SHARD_FOLDER"});
  command.add_options()("job", po::value<std::string>(), "the job array's id (SLURM_ARRAY_JOB_ID)")(
      "task", po::value<std::string>(), "the task's index in it (SLURM_ARRAY_TASK_ID), from 0")(
      "points", po::value<std::string>(), "the array's points, rising, e.g. 1-3,5: task T runs the T-th, from 0")(
      "threads", po::value<std::string>(), "soft-engine threads")(
      "scratch", po::value<std::string>(), "a folder to write the shard in first (node-local scratch)");
  command.add(checkpoint_option());
  if (!command.parse(args)) return 0;
  const auto& vm = command.vm();
  constexpr long largest = std::numeric_limits<std::int64_t>::max();
  ShardTaskRequest request{ShardFolder(std::filesystem::path(required_option(vm, "SHARD_FOLDER", "study task"))),
                           parse_whole_number(required_option(vm, "job", "study task"), 1, largest, "--job"),
                           parse_whole_number(required_option(vm, "task", "study task"), 0, largest, "--task"), 0,
                           vm.count("scratch") ? vm["scratch"].as<std::string>() : std::string()};
  request.point =
      nth_in_ranges(required_option(vm, "points", "study task"), request.task, std::numeric_limits<int>::max());
  if (vm.count("threads")) set_thread_count(vm["threads"].as<std::string>());
  install_stop_handlers();
  study::PointRunControl control;
  control.stop = stop_flag();
  control.checkpoint_interval = checkpoint_interval(command.vm());
  control.warn = [](const std::string& warning) { std::cerr << "pdamp: warning: " << warning << "\n"; };
  std::cout << "pdamp: task " << request.task << " of job " << request.job << " (point " << request.point << ") on "
            << printable(this_process_lease().host) << ", shard folder " << printable(request.folder.path().string())
            << std::endl;
  ProgressLines lines;
  control.progress = [&lines](double fraction, std::string_view phase) { lines(fraction, phase); };
  const ShardTaskResult result = run_shard_task(request, control, [&lines](int point) { lines.start(point); });
  if (result.last_point != request.point) {
    std::cout << "pdamp: points " << request.point << " to " << result.last_point << " of its curve run, "
              << result.points_completed << " completed" << std::endl;
  }
  std::cout << "pdamp: point " << result.last_point << " of study " << result.study_id << " "
            << to_string(result.point.status) << (result.point.message.empty() ? "" : ": " + result.point.message)
            << "; shard " << printable(result.shard.string()) << std::endl;
  switch (result.point.status) {
    case PointStatus::completed:
      return 0;
    case PointStatus::interrupted:
      return 128 + stop_signal_received();
    default:
      return 1;
  }
}

}  // namespace pdamp
