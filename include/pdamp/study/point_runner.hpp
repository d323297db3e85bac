#pragma once
/// Runs study points in this process: `pdamp study run-point`, which the study runner
/// starts once per point, and which a cluster task can run on its own.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "pdamp/sim/snapshots.hpp"
#include "pdamp/store/study_store.hpp"
#include "pdamp/study/study.hpp"

namespace pdamp::study {

/// How a worker (`pdamp study run-point --report-progress`) talks to the study runner: a
/// line on stdout for its progress, and this exit code when its point was completed or
/// taken by another process before it could claim it (EX_TEMPFAIL).
std::string progress_line(double fraction, std::string_view phase);
inline constexpr int exit_point_not_claimed = 75;

/// The study as stored: built from the stored study and base scenario texts, so a point
/// runs the scenario that was validated when the study was made, wherever it runs.
Study stored_study(const StudyRecord& record);

struct PointRunControl {
  const std::atomic<bool>* stop = nullptr;  ///< true ends the point as interrupted
  /// About twice a second: the fraction of the point done and what runs ("settling",
  /// "soft", "hard").
  std::function<void(double fraction, std::string_view phase)> progress;
  std::function<void(const std::string& warning)> warn;
  std::optional<SnapshotSettings> snapshots;  ///< each run's snapshots, checked by validate_study
  /// Wall time between its runs' checkpoints (0: none). A point an earlier attempt left
  /// continues its runs from their checkpoints (docs/checkpoints.md).
  std::chrono::milliseconds checkpoint_interval{0};
};

struct PointResult {
  PointStatus status = PointStatus::pending;  ///< pending: the point was not claimed here
  int attempt = 0;
  std::string message;
};

/// Claims the point (study_store.hpp), settles or reuses its bed, runs its model(s) into
/// the store linked to the point, and completes it with its metrics, or ends it as failed
/// or interrupted with the reason. A model's run that an earlier attempt of the point left
/// is taken over: kept if it completed (a sweep point's), resumed from its checkpoint if
/// not; one that cannot be resumed (no checkpoint, another pdamp's, failed) is reported
/// through `control.warn` and the model runs from its start. A point completed or running
/// elsewhere is left alone (status pending, with the reason in the message).
PointResult run_study_point(RunStore& store, std::int64_t study_id, const Study& study, int point,
                            const PointRunControl& control);

}  // namespace pdamp::study
