#include "pdamp/study/study_runner.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/store/process_lease.hpp"
#include "pdamp/store/study_store.hpp"
#include "pdamp/study/point_runner.hpp"

namespace pdamp::study {
namespace {

/// How long stopped workers get to store their points before they are killed.
constexpr auto stop_grace = std::chrono::seconds(10);

std::string describe_exit(int status) {
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    return "signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
  }
  return "status " + std::to_string(status);
}

/// One worker process and what it has said so far.
struct Worker {
  pid_t pid = -1;
  int point = 0;
  std::array<int, 2> fds{-1, -1};      ///< its stdout (progress lines) and stderr (messages)
  std::array<std::string, 2> pending;  ///< what each has said since its last full line
};

class WorkerPool {
 public:
  WorkerPool(const StudyRunOptions& options, std::int64_t study_id)
      : options_(&options), study_id_(study_id), events_(&options.events) {}
  ~WorkerPool() {
    // Only reached with workers left if the runner itself failed: they must not outlive it.
    for (auto& w : workers_) {
      kill(w.pid, SIGKILL);
      waitpid(w.pid, nullptr, 0);
      close_fds(w);
    }
  }
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  std::size_t size() const { return workers_.size(); }

  void start(int point) {
    std::vector<std::string> args{options_->worker.executable};
    args.insert(args.end(), options_->worker.arguments.begin(), options_->worker.arguments.end());
    for (const std::string& a : {std::string("--db"), options_->db.string(), std::string("--threads"),
                                 std::to_string(options_->threads_per_worker), std::string("--report-progress"),
                                 std::to_string(study_id_), std::to_string(point)}) {
      args.push_back(a);
    }
    std::vector<char*> argv;
    argv.reserve(args.size() + 1);
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);

    int out[2], err[2];
    if (pipe2(out, O_CLOEXEC) != 0 || pipe2(err, O_CLOEXEC) != 0) {
      throw RuntimeFailure(std::string("cannot create a pipe for a worker: ") + std::strerror(errno));
    }
    const pid_t parent = getpid();
    const pid_t pid = fork();
    if (pid < 0) throw RuntimeFailure(std::string("cannot start a worker: ") + std::strerror(errno));
    if (pid == 0) {
      // The worker stops (and stores its point as interrupted) if this process dies.
      prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (getppid() != parent) _exit(128 + SIGTERM);
      dup2(out[1], STDOUT_FILENO);
      dup2(err[1], STDERR_FILENO);
      execv(argv[0], argv.data());
      const char message[] = "cannot run the worker program\n";
      [[maybe_unused]] const auto ignored = write(STDERR_FILENO, message, sizeof message - 1);
      _exit(127);
    }
    close(out[1]);
    close(err[1]);
    Worker w;
    w.pid = pid;
    w.point = point;
    w.fds[0] = out[0];
    w.fds[1] = err[0];
    for (const int fd : w.fds) fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    workers_.push_back(std::move(w));
    if (events_->started) events_->started(point);
  }

  /// Waits up to `timeout` for output and hands on what arrived.
  void poll_output(std::chrono::milliseconds timeout) {
    std::vector<pollfd> fds;
    for (const auto& w : workers_) {
      for (const int fd : w.fds) {
        if (fd >= 0) fds.push_back({fd, POLLIN, 0});
      }
    }
    if (::poll(fds.data(), fds.size(), static_cast<int>(timeout.count())) <= 0) return;  // timeout or a signal
    for (auto& w : workers_) read_output(w);
  }

  void signal_all(int number) {
    for (const auto& w : workers_) kill(w.pid, number);
  }

  /// The workers that have exited, with their wait statuses, removed from the pool.
  std::vector<std::pair<Worker, int>> reap() {
    std::vector<std::pair<Worker, int>> ended;
    for (auto it = workers_.begin(); it != workers_.end();) {
      int status = 0;
      if (waitpid(it->pid, &status, WNOHANG) != it->pid) {
        ++it;
        continue;
      }
      read_output(*it);  // what it wrote before exiting
      for (int k = 0; k < 2; ++k) {
        if (!it->pending[k].empty()) line(*it, k, it->pending[k]);
      }
      close_fds(*it);
      ended.emplace_back(std::move(*it), status);
      it = workers_.erase(it);
    }
    return ended;
  }

 private:
  static void close_fds(Worker& w) {
    for (int& fd : w.fds) {
      if (fd >= 0) close(fd);
      fd = -1;
    }
  }

  void read_output(Worker& w) {
    for (int k = 0; k < 2; ++k) {
      char buffer[4096];
      ssize_t n = 0;
      while (w.fds[k] >= 0 && (n = read(w.fds[k], buffer, sizeof buffer)) > 0) {
        w.pending[k].append(buffer, static_cast<std::size_t>(n));
      }
      if (n == 0 && w.fds[k] >= 0) {  // the worker closed it: poll no more
        close(w.fds[k]);
        w.fds[k] = -1;
      }
      for (auto end = w.pending[k].find('\n'); end != std::string::npos; end = w.pending[k].find('\n')) {
        const std::string text = w.pending[k].substr(0, end);
        w.pending[k].erase(0, end + 1);
        line(w, k, text);
      }
    }
  }

  /// A line of a worker's stdout (point_runner.hpp's progress_line) or stderr (for the user).
  void line(const Worker& w, int stream, const std::string& text) {
    std::istringstream words(text);
    std::string tag, phase;
    double fraction = 0.0;
    if (stream == 0 && words >> tag >> fraction >> phase && tag == "progress") {
      if (events_->progressed) events_->progressed(w.point, fraction, phase);
      return;
    }
    const std::string own = text.starts_with("pdamp: ") ? text.substr(7) : text;
    if (events_->message) events_->message("pdamp: point " + std::to_string(w.point) + ": " + own);
  }

  const StudyRunOptions* options_;
  std::int64_t study_id_;
  const StudyEvents* events_;
  std::vector<Worker> workers_;
};

/// Points left running by processes that are gone, or on the host taken over, are
/// interrupted (and run again); each is reported.
void reclaim_abandoned(StudyStore& studies, std::int64_t study_id, const StudyRunOptions& options) {
  for (const auto& p : studies.points(study_id)) {
    if (p.status != PointStatus::running || !p.lease) continue;
    const std::string process = std::to_string(p.lease->pid) + " on " + p.lease->host;
    std::string why;
    if (!options.take_over_host.empty() && p.lease->host == options.take_over_host) {
      why = "taken over from process " + process + " (--take-over " + options.take_over_host + ")";
    } else if (!lease_is_alive(*p.lease)) {
      why = "its process (" + process + ") ended before the point did";
    } else {
      continue;
    }
    if (studies.abandon_point(study_id, p.point, *p.lease, PointStatus::interrupted, why) && options.events.message) {
      options.events.message("pdamp: point " + std::to_string(p.point) + ": " + why + "; run again");
    }
  }
}

/// A point another process runs, and where the lease is another host's, how to take it over.
std::string running_elsewhere(const StudyPointState& p) {
  if (!p.lease) return "point " + std::to_string(p.point) + " is running in another process";
  std::string text = "point " + std::to_string(p.point) + " is running in process " + std::to_string(p.lease->pid) +
                     " on " + p.lease->host;
  if (p.lease->host != this_host_name()) {
    text += " (which cannot be checked from here; if it runs there no more: --take-over " + p.lease->host + ")";
  }
  return text;
}

class StudyRun {
 public:
  StudyRun(RunStore& store, std::int64_t study_id, const StudyRunOptions& options)
      : studies_(store), study_id_(study_id), options_(&options), previous_(studies_.previous_points(study_id)) {
    reclaim_abandoned(studies_, study_id, options);
    int done = 0;
    for (const auto& p : studies_.points(study_id)) {
      if (p.status == PointStatus::completed) {
        completed_.insert(p.point);
        ++done;
      } else if (p.status == PointStatus::running) {
        report_.problems.push_back(running_elsewhere(p));
        ++report_.elsewhere;
      } else {
        queue_.push_back(p.point);
      }
    }
    report_.completed = done;
  }

  StudyRunReport run() {
    WorkerPool pool(*options_, study_id_);
    const StudyEvents& events = options_->events;
    std::optional<std::chrono::steady_clock::time_point> stopped_at;
    while (!queue_.empty() || pool.size() > 0) {
      if (!stopped_at && options_->stop && options_->stop->load()) {
        stopped_at = std::chrono::steady_clock::now();
        pool.signal_all(SIGINT);
      }
      if (stopped_at && std::chrono::steady_clock::now() - *stopped_at > stop_grace) pool.signal_all(SIGKILL);
      while (!stopped_at && pool.size() < static_cast<std::size_t>(options_->jobs)) {
        const auto next = next_ready();
        if (next == queue_.end()) break;
        pool.start(*next);
        queue_.erase(next);
      }
      if (pool.size() == 0) break;
      pool.poll_output(std::chrono::milliseconds(250));
      for (const auto& [worker, status] : pool.reap()) settle(worker, status, stopped_at.has_value());
      if (events.tick) events.tick(static_cast<int>(queue_.size()));
    }
    report_.stopped = stopped_at.has_value();
    report_.not_started = static_cast<int>(queue_.size());
    if (!report_.stopped) {
      for (const int point : queue_) {
        report_.problems.push_back("point " + std::to_string(point) + " not run: it continues from point " +
                                   std::to_string(previous_.at(point)) + ", which did not complete");
      }
    }
    return report_;
  }

 private:
  /// The first queued point that can start: a point of a frequency-response curve waits
  /// for the point it continues from (a curve is sequential; curves run side by side).
  std::deque<int>::iterator next_ready() {
    return std::find_if(queue_.begin(), queue_.end(), [&](int point) {
      const auto it = previous_.find(point);
      return it == previous_.end() || completed_.contains(it->second);
    });
  }

  /// Counts how a worker's point ended, as the store says; a point its worker left
  /// running (a crash, or a kill after a stop) ends as failed or interrupted here.
  void settle(const Worker& worker, int status, bool stopping) {
    std::optional<StudyPointState> state = studies_.point(study_id_, worker.point);
    const std::string where = "point " + std::to_string(worker.point);
    if (state && state->status == PointStatus::running && state->lease && state->lease->pid == worker.pid) {
      const PointStatus end = stopping ? PointStatus::interrupted : PointStatus::failed;
      state->message = "its worker (process " + std::to_string(worker.pid) + ") ended with " + describe_exit(status) +
                       " before finishing the point";
      studies_.abandon_point(study_id_, worker.point, *state->lease, end, state->message);
      state->status = end;
    }
    const bool completed = state && state->status == PointStatus::completed;
    if (options_->events.ended) options_->events.ended(worker.point, completed);
    if (completed) {
      completed_.insert(worker.point);
      ++report_.completed;
    } else if (WIFEXITED(status) && WEXITSTATUS(status) == exit_point_not_claimed) {
      ++report_.elsewhere;
      report_.problems.push_back(where + " was taken by another process");
    } else if (state && state->status == PointStatus::interrupted) {
      ++report_.interrupted;
      report_.problems.push_back(where + " interrupted: " + state->message);
    } else {
      ++report_.failed;
      report_.problems.push_back(where + " failed: " +
                                 (state && !state->message.empty()
                                      ? state->message
                                      : "its worker ended with " + describe_exit(status) + " without running it"));
    }
  }

  StudyStore studies_;
  std::int64_t study_id_;
  const StudyRunOptions* options_;
  std::map<int, int> previous_;  ///< the point each continuing point starts from
  std::set<int> completed_;
  std::deque<int> queue_;
  StudyRunReport report_;
};

std::optional<FrfPointRow> frf_row(const Study& study, const StudyPoint& p) {
  if (!p.frf) return std::nullopt;
  const FrfPoint& f = *p.frf;
  const bool base = study.file.frfs.at(f.section).mode == ExcitationMode::base_motion;
  return FrfPointRow{f.curve,
                     std::string(to_string(f.model)),
                     std::string(to_string(f.direction)),
                     f.host_alone,
                     base ? "base" : "force",
                     std::stod(f.level),
                     std::stod(f.frequency_hz),
                     f.step,
                     f.previous,
                     describe_grid(f)};
}

std::optional<CharacterisePointRow> characterise_row(const StudyPoint& p) {
  if (!p.characterise) return std::nullopt;
  const CharacterisePoint& c = *p.characterise;
  return CharacterisePointRow{c.curve,
                              std::string(to_string(c.model)),
                              c.empty,
                              std::stod(c.amplitude_m),
                              c.gamma.empty() ? std::nullopt : std::optional(std::stod(c.gamma)),
                              std::stod(c.frequency_hz),
                              c.step,
                              c.previous};
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string text;
  for (const auto& l : lines) text += "\n  " + l;
  return text;
}

}  // namespace

NewStudyPoint stored_point(const Study& study, const StudyPoint& point) {
  return {point.point, point.section, point.values, frf_row(study, point), characterise_row(point)};
}

void check_same_study(const Study& stored, const Study& now, const std::string& what, const std::string& way_out) {
  const auto differences = study_differences(stored, now);
  if (!differences.empty()) throw InputError(what + join_lines(differences) + "\n" + way_out);
}

void check_same_as_stored(const StudyRecord& record, const Study& study, const std::filesystem::path& file) {
  check_same_study(stored_study(record), study,
                   "study '" + study.file.name + "' (study " + std::to_string(record.study_id) + " in '" +
                       file.string() + "') was made from another definition:",
                   "run it unchanged to resume it, or give this one another [study] name or --db");
}

std::int64_t find_or_create_study(RunStore& store, const Study& study) {
  StudyStore studies(store);
  for (int tries = 0;; ++tries) {
    if (const auto record = studies.find_study(study.file.name)) {
      check_same_as_stored(*record, study, store.file());
      return record->study_id;
    }
    std::vector<NewStudyPoint> points;
    for (const auto& p : study.points) points.push_back(stored_point(study, p));
    try {
      return studies.create_study(
          {study.file.name, std::string(to_string(study.file.models)), study.source.study_path.string(),
           study.source.study_text, study.source.scenario_path.string(), study.source.scenario_text},
          points);
    } catch (const RuntimeFailure&) {
      if (tries > 0) throw;  // else another process stored a study of this name meanwhile: compare with it
    }
  }
}

StudyRunReport run_study(RunStore& store, std::int64_t study_id, const StudyRunOptions& options) {
  return StudyRun(store, study_id, options).run();
}

}  // namespace pdamp::study
