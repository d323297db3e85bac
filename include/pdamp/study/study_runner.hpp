#pragma once
/// Runs a study's points side by side, each in a worker process (`pdamp study run-point`)
/// writing into the one WAL store. Processes rather than threads: a worker that crashes
/// takes only its point down, a stop request reaches every worker as a signal that ends
/// its point as interrupted, each worker's soft engine has its own thread count, and a
/// point runs the same way when a cluster task starts it on its own.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "pdamp/store/run_store.hpp"
#include "pdamp/store/study_store.hpp"
#include "pdamp/study/study.hpp"

namespace pdamp::study {

/// The program a worker runs: `executable arguments... --db FILE --threads N
/// --report-progress STUDY_ID POINT`.
struct WorkerCommand {
  std::string executable;
  std::vector<std::string> arguments;
};

/// What a study run tells its caller as it goes (the CLI shows it as progress); any may
/// be empty.
struct StudyEvents {
  std::function<void(int point)> started;
  /// The point has done `fraction` of its work and is `phase` ("settling", "soft", "hard").
  std::function<void(int point, double fraction, std::string_view phase)> progressed;
  /// The point's worker has ended, with the point completed or not.
  std::function<void(int point, bool completed)> ended;
  /// A line for the user, e.g. a worker's warning.
  std::function<void(const std::string& line)> message;
  /// About four times a second; `queued` points wait to start.
  std::function<void(int queued)> tick;
};

struct StudyRunOptions {
  int jobs = 1;                ///< points run at once
  int threads_per_worker = 1;  ///< the soft engine's threads in each worker
  std::filesystem::path db;
  WorkerCommand worker;
  const std::atomic<bool>* stop = nullptr;  ///< true: the workers are told to stop, and no point starts
  /// Another host whose processes the user says run none of the study's points any more:
  /// points left running under its leases (which cannot be checked from here) are
  /// interrupted and run again. Empty: none.
  std::string take_over_host;
  StudyEvents events;
};

struct StudyRunReport {
  int completed = 0;    ///< points completed, in this run or before
  int failed = 0;       ///< points that failed in this run
  int interrupted = 0;  ///< points stopped in this run
  int elsewhere = 0;    ///< points that another live process is running
  int not_started = 0;  ///< points left pending by a stop
  bool stopped = false;
  std::vector<std::string> problems;  ///< one line per point that did not complete
};

/// A point as the store records it: its values and, on a curve, its place there.
NewStudyPoint stored_point(const Study& study, const StudyPoint& point);

/// Throws InputError, `what`, every difference (study_differences) a line, then `way_out`,
/// if `now` would run other points than `stored`.
void check_same_study(const Study& stored, const Study& now, const std::string& what, const std::string& way_out);

/// Throws InputError naming every difference if the study stored under `study`'s name in
/// the store `file` (`record`) would run other points: one definition per name in a store.
void check_same_as_stored(const StudyRecord& record, const Study& study, const std::filesystem::path& file);

/// Finds the study of this name in the store, or stores it with its points. Throws
/// InputError, writing nothing, if a stored study of this name would run other points,
/// naming every difference. Returns the study's id.
std::int64_t find_or_create_study(RunStore& store, const Study& study);

/// Runs every point of the stored study that is not completed, `jobs` at a time. Points
/// left running by a process that is gone (study_store.hpp's lease) are run again. Returns
/// when no point is left to run, or, after a stop request, when the workers have stopped.
StudyRunReport run_study(RunStore& store, std::int64_t study_id, const StudyRunOptions& options);

}  // namespace pdamp::study
