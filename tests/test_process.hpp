#pragma once
/// Starting the built executables from tests: arguments in, exit code and output back.

#include <doctest/doctest.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "pdamp/store/sqlite.hpp"
#include "test_support.hpp"

extern char** environ;

namespace pdamp::test {

/// The argument vector of a program for exec and posix_spawn: the executable, then `args`.
class Argv {
 public:
  Argv(const std::string& executable, const std::vector<std::string>& args) : words_{executable} {
    words_.insert(words_.end(), args.begin(), args.end());
    for (auto& word : words_) pointers_.push_back(word.data());
    pointers_.push_back(nullptr);
  }
  const char* program() const { return words_.front().c_str(); }
  char** get() { return pointers_.data(); }

 private:
  std::vector<std::string> words_;
  std::vector<char*> pointers_;
};

/// Whether a started process leads a process group of its own, which
/// Process::signal_group() then reaches with all its children.
enum class Group { inherited, own };

/// An executable (pdamp unless named) started with arguments, its stdout and stderr
/// captured in `<stem>.out` and `<stem>.err` of a directory.
class Process {
 public:
  Process(const std::vector<std::string>& args, const TempDir& dir, const std::string& stem = "pdamp",
          Group group = Group::inherited)
      : Process(PDAMP_EXECUTABLE, args, dir, stem, group) {}
  Process(const std::string& executable, const std::vector<std::string>& args, const TempDir& dir,
          const std::string& stem = "pdamp", Group group = Group::inherited)
      : out_(dir / (stem + ".out")), err_(dir / (stem + ".err")) {
    Argv argv(executable, args);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    if (group == Group::own) {
      posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
      posix_spawnattr_setpgroup(&attributes, 0);
    }
    REQUIRE(posix_spawn(&pid_, argv.program(), &actions, &attributes, argv.get(), environ) == 0);
    posix_spawnattr_destroy(&attributes);
    posix_spawn_file_actions_destroy(&actions);
  }
  /// Waits for the exit and returns the exit code (128 + signal if killed).
  int wait() {
    int status = 0;
    rusage usage{};
    wait4(pid_, &status, 0, &usage);
    peak_memory_kB_ = usage.ru_maxrss;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  /// The exit code if the process ends within `limit`; otherwise kills it and returns -1.
  int wait_at_most(std::chrono::duration<double> limit) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      rusage usage{};
      if (wait4(pid_, &status, WNOHANG, &usage) == pid_) {
        peak_memory_kB_ = usage.ru_maxrss;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    signal(SIGKILL);
    wait();
    return -1;
  }
  /// Whether the process has ended (it stays to be waited for).
  bool has_exited() const {
    siginfo_t info{};
    return waitid(P_PID, static_cast<id_t>(pid_), &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid == pid_;
  }
  /// The largest resident set the process had (kB), once it has been waited for.
  long peak_memory_kB() const { return peak_memory_kB_; }
  void signal(int number) const { kill(pid_, number); }
  void signal_group(int number) const { kill(-pid_, number); }
  /// SIGKILL to the process and its children (Group::own); waits for it, then up to 10 s
  /// until no child is left but as a zombie, and returns its exit code. The signal reaches
  /// each process in its own time: a study worker still exiting when the test goes on
  /// would hold its point's lease, and a resume would find the point running.
  int kill_group() {
    signal_group(SIGKILL);
    const int code = wait();
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (group_has_living_member() && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return code;
  }
  std::string out() const { return slurp(out_); }
  std::string err() const { return slurp(err_); }

 private:
  static std::string slurp(const std::filesystem::path& file) {
    std::ifstream in(file);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  }
  /// Whether a process of the group this one leads lives (zombies do not).
  bool group_has_living_member() const {
    for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
      std::ifstream stat(entry.path() / "stat");
      std::string line;
      if (!std::getline(stat, line)) continue;  // not a process, or gone
      // pid (comm) state ppid pgrp ...; comm may hold spaces and parentheses.
      std::istringstream rest(line.substr(line.rfind(')') + 1));
      char state = 0;
      long ppid = 0, pgrp = 0;
      if (rest >> state >> ppid >> pgrp && pgrp == pid_ && state != 'Z' && state != 'X') return true;
    }
    return false;
  }
  pid_t pid_ = 0;
  long peak_memory_kB_ = 0;
  std::filesystem::path out_, err_;
};

struct Result {
  int code;
  std::string out, err;
};

/// Runs an executable (pdamp unless named) to its end.
inline Result pdamp_cli(const std::vector<std::string>& args, const TempDir& dir,
                        const std::string& executable = PDAMP_EXECUTABLE) {
  Process p(executable, args, dir);
  const int code = p.wait();
  return {code, p.out(), p.err()};
}

/// tools/check_snapshots.py (VTK's reader) on run `run_id`'s snapshots, recorded in the
/// store `db`, against its stored samples; fails with its report (also if python3-vtk9 is
/// missing).
inline void check_stored_snapshots(const std::filesystem::path& db, std::int64_t run_id, const TempDir& dir) {
  std::string collection;
  {
    sqlite::Database d(db, sqlite::Access::read_only);
    sqlite::Statement q(d, "SELECT collection FROM run_snapshots WHERE run_id = " + std::to_string(run_id));
    REQUIRE(q.step());
    collection = q.column_text(0);
  }
  const Result r = pdamp_cli({(source_dir() / "tools" / "check_snapshots.py").string(), collection, "--db", db.string(),
                              "--run", std::to_string(run_id)},
                             dir, "/usr/bin/python3");
  INFO(r.out << r.err);
  CHECK(r.code == 0);
}

/// The first column of the first row of a query on a store file.
inline std::int64_t count_rows(const std::filesystem::path& db, const std::string& sql) {
  sqlite::Database d(db);
  sqlite::Statement q(d, sql);
  q.step();
  return q.column_int(0);
}

/// The cells of one column of the table `pdamp study show` prints: of the rows after its
/// header line, whose columns are two or more blanks apart (a name or cell may hold one).
inline std::vector<std::string> shown_column(const std::string& out, const std::string& column) {
  const auto cells_of = [](const std::string& line) {
    std::vector<std::string> cells;
    for (std::size_t i = line.find_first_not_of(' '); i < line.size();) {
      const std::size_t end = std::min(line.find("  ", i), line.size());
      cells.push_back(line.substr(i, end - i));
      i = line.find_first_not_of(' ', end);
    }
    return cells;
  };
  std::istringstream in(out);
  std::vector<std::string> header, cells;
  for (std::string line; std::getline(in, line);) {
    const auto row = cells_of(line);
    if (header.empty() && !row.empty() && row.front() == "point") {
      header = row;
    } else if (!header.empty() && row.size() == header.size()) {
      cells.push_back(
          row.at(static_cast<std::size_t>(std::find(header.begin(), header.end(), column) - header.begin())));
    }
  }
  return cells;
}

/// `pdamp study run FILE --jobs N` into its own store (DIR/jobsN.sqlite) for each N; each
/// must succeed. The stores by N.
inline std::map<int, std::filesystem::path> run_study_per_jobs(const std::filesystem::path& file, const TempDir& dir,
                                                               std::initializer_list<int> jobs) {
  std::map<int, std::filesystem::path> stores;
  for (const int n : jobs) {
    stores[n] = dir / ("jobs" + std::to_string(n) + ".sqlite");
    const Result r =
        pdamp_cli({"study", "run", file.string(), "--db", stores[n].string(), "--jobs", std::to_string(n)}, dir);
    INFO(r.err);
    REQUIRE(r.code == 0);
  }
  return stores;
}

/// Whether the count `ready_sql` on `store` is not 0, once the store has the view `view`;
/// false while the store is missing, being created or locked.
inline bool store_is_ready(const std::filesystem::path& store, const std::string& view, const std::string& ready_sql) {
  if (!std::filesystem::exists(store)) return false;
  try {
    sqlite::Database d(store, sqlite::Access::read_only, std::chrono::milliseconds(50));
    const auto count = [&](const std::string& sql) {
      sqlite::Statement q(d, sql);
      q.step();
      return q.column_int(0);
    };
    return count("SELECT count(*) FROM sqlite_schema WHERE name = '" + view + "'") && count(ready_sql);
  } catch (const std::exception&) {
    return false;
  }
}

/// Runs `p` and its children (started with Group::own) in slices of 5 ms, stopped (SIGSTOP)
/// while `ready` is asked, until it answers true (they are left stopped), `p` ends or 60 s
/// pass; whether it answered true. So a state that lasts a few milliseconds of the
/// process's own time is seen however busy the machine, and it is still the state when the
/// caller acts: polling a running process missed such states. Wall time passes while it is
/// stopped, so its wall-time checkpoints come more often. A store read that meets a writer
/// stopped inside an update of the WAL index waits in SQLite (up to about 10 s) and fails:
/// `ready` should answer false then, and the process runs another slice.
inline bool stop_when(const Process& p, const std::function<bool()>& ready) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!p.has_exited() && std::chrono::steady_clock::now() < give_up) {
    p.signal_group(SIGCONT);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    p.signal_group(SIGSTOP);
    if (ready()) return true;
  }
  return false;
}

/// `pdamp study run FILE --jobs 2 [extra...]` into `store`, killed with its workers by
/// SIGKILL once the store has the view `view` and the count `ready_sql` is not 0 (stop_when;
/// a point's last checkpoint before its completion is such a state).
inline void kill_study_when(const std::filesystem::path& file, const std::filesystem::path& store, const TempDir& dir,
                            const std::string& view, const std::string& ready_sql,
                            const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args{"study", "run", file.string(), "--db", store.string(), "--jobs", "2"};
  args.insert(args.end(), extra.begin(), extra.end());
  Process study(args, dir, "study", Group::own);
  const bool ready = stop_when(study, [&] { return store_is_ready(store, view, ready_sql); });
  INFO("the store reached the state to kill the study in: " << ready);
  CHECK(study.kill_group() == 128 + SIGKILL);
}

/// kill_study_when at least `completed` points are completed.
inline void kill_study_mid_run(const std::filesystem::path& file, const std::filesystem::path& store,
                               const TempDir& dir, const std::string& view, int completed) {
  kill_study_when(file, store, dir, view,
                  "SELECT count(*) >= " + std::to_string(completed) + " FROM study_points WHERE status = 'completed'");
}

/// Counts the runs that are not completed but have a checkpoint: a point left so continues them.
inline constexpr const char* checkpointed_unfinished_runs =
    "SELECT count(*) FROM run_checkpoints JOIN runs USING (run_id) WHERE status <> 'completed'";

/// The ids of the runs of `db` that are not completed but have a checkpoint, as an SQL
/// list, e.g. "(3, 7)".
inline std::string unfinished_checkpointed_run_ids(const std::filesystem::path& db) {
  sqlite::Database d(db);
  sqlite::Statement q(d, "SELECT run_id FROM run_checkpoints JOIN runs USING (run_id) WHERE status <> 'completed'");
  std::string list;
  // Appended piece by piece: GCC 12's LTO warns (-Wstringop-overflow, a false positive) on
  // operator+ here.
  while (q.step()) list.append(list.empty() ? "" : ", ").append(std::to_string(q.column_int(0)));
  return list.insert(0, "(").append(")");
}

/// How many of the runs `ids` (an SQL list) are completed and linked to their point's
/// latest attempt, which then completed: each such run was continued by its point.
inline std::int64_t runs_continued_by_their_points(const std::filesystem::path& db, const std::string& ids) {
  return count_rows(db,
                    "SELECT count(*) FROM runs r JOIN study_point_runs l USING (run_id) JOIN study_points p ON "
                    "p.study_id = l.study_id AND p.point = l.point AND p.attempt = l.attempt WHERE r.run_id IN " +
                        ids + " AND r.status = 'completed' AND p.status = 'completed'");
}

/// A study of curves: `study submit --slurm --dry-run` prints its job script, a task per
/// curve, and writes no store `db`.
inline void check_curve_study_submit(const std::filesystem::path& file, const std::filesystem::path& db,
                                     const TempDir& dir) {
  const Result slurm = pdamp_cli({"study", "submit", file.string(), "--slurm", "--dry-run", "--db", db.string()}, dir);
  INFO(slurm.err);
  CHECK(slurm.code == 0);
  CHECK(slurm.out.find("curves as a job array, one task per curve") != std::string::npos);
  CHECK(!std::filesystem::exists(db));
}

/// `pdamp study resume 1 --jobs 2 [extra...]` of the killed study in `killed`: each run
/// that had a checkpoint is completed by its point.
inline void resume_continuing_checkpoints(const std::filesystem::path& killed, const TempDir& dir,
                                          const std::vector<std::string>& extra = {}) {
  const std::string checkpointed = unfinished_checkpointed_run_ids(killed);
  std::vector<std::string> args{"study", "resume", "1", "--db", killed.string(), "--jobs", "2"};
  args.insert(args.end(), extra.begin(), extra.end());
  const Result resumed = pdamp_cli(args, dir);
  INFO(resumed.err);
  REQUIRE(resumed.code == 0);
  INFO("runs with a checkpoint before the resume: " << checkpointed);
  CHECK(checkpointed != "()");
  CHECK(runs_continued_by_their_points(killed, checkpointed) ==
        count_rows(killed, "SELECT count(*) FROM runs WHERE run_id IN " + checkpointed));
}

/// `pdamp study run FILE --snapshots EVERY_S --snapshot-dir DIR/frames` into `db`; the
/// test stops there, with pdamp's stderr, if it fails.
inline void run_study_with_snapshots(const std::filesystem::path& file, const std::filesystem::path& db,
                                     const std::string& every_s, const TempDir& dir) {
  const Result r = pdamp_cli({"study", "run", file.string(), "--db", db.string(), "--snapshots", every_s,
                              "--snapshot-dir", (dir / "frames").string()},
                             dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
}

/// The study FILE run into `killed` with `--snapshots EVERY_S --snapshot-dir DIR/killed` and
/// checkpoints every 0.01 s, killed once a run of it has a checkpoint (kill_study_when; the
/// study has the view `view`) and resumed with the same snapshots: each run that had a
/// checkpoint is completed by its point (resume_continuing_checkpoints).
inline void kill_and_resume_with_snapshots(const std::filesystem::path& file, const std::filesystem::path& killed,
                                           const std::string& view, const std::string& every_s, const TempDir& dir) {
  const std::vector<std::string> snapshots{"--snapshots", every_s, "--snapshot-dir", (dir / "killed").string()};
  std::vector<std::string> killed_run{"--checkpoint-every", "0.01"};
  killed_run.insert(killed_run.end(), snapshots.begin(), snapshots.end());
  kill_study_when(file, killed, dir, view, "SELECT (" + std::string(checkpointed_unfinished_runs) + ") > 0",
                  killed_run);
  resume_continuing_checkpoints(killed, dir, snapshots);
}

}  // namespace pdamp::test
