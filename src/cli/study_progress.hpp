#pragma once
/// A study's progress on stderr (progress.hpp's line): points done of the total, the
/// points running with what each does, and the time left.

#include <chrono>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>

#include "progress.hpp"

namespace pdamp {

class StudyProgress {
 public:
  /// `done` of the study's `total` points were completed before; `jobs` run at once.
  StudyProgress(std::ostream& out, bool terminal, std::string study, int total, int done, int jobs,
                Progress::Clock clock = &std::chrono::steady_clock::now);

  void started(int point);
  /// The point has done `fraction` of its work and is `phase` ("settling", "soft", "hard").
  void progressed(int point, double fraction, std::string_view phase);
  /// The point's worker has ended; `completed` points count towards the time per point.
  void ended(int point, bool completed);
  /// A line of its own, e.g. a worker's warning.
  void message(std::string_view line);
  /// Shows the line if it is due; `queued` points wait to start.
  void update(int queued);
  /// Ends the line: it stays, and what follows starts on a new line.
  void finish();

  /// "3 min 05 s left", or "" until known: the points still to run (running ones by what is
  /// left of them) at the mean wall time per point computed here, `jobs` at a time.
  std::string time_left(int queued) const;

 private:
  struct Running {
    std::chrono::steady_clock::time_point started;
    double fraction = 0.0;
    std::string phase = "starting";
    /// The point's first progress, from which its pace is measured: a point resumed from
    /// its checkpoint starts there, and what came before was computed by another process.
    std::optional<std::pair<std::chrono::steady_clock::time_point, double>> origin{};
  };
  std::string line(int queued) const;

  Progress progress_;
  Progress::Clock clock_;
  std::string study_;
  int total_, done_, not_completed_ = 0, jobs_;
  std::map<int, Running> running_;
  /// The wall time and the work (in points) of the points completed here, from their origin.
  double completed_wall_s_ = 0.0;
  double completed_work_ = 0.0;
};

}  // namespace pdamp
