#pragma once
/// One task of a study's job array (`pdamp study task`): its point run into a shard store
/// of its own, never into the study's store, which the tasks of a cluster must not share
/// (SQLite's locks over NFS and Lustre are not reliable).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <vector>

#include "pdamp/slurm/job_script.hpp"
#include "pdamp/study/point_runner.hpp"

namespace pdamp::slurm {

struct ShardTaskRequest {
  ShardFolder folder;
  std::int64_t job = 0, task = 0;  ///< the job array and the task's index in it
  std::int64_t point = 0;          ///< the point the task runs
  std::filesystem::path scratch;   ///< a folder to write the shard in first; empty: the shard folder
};

struct ShardTaskResult {
  std::int64_t study_id = 0;
  study::PointResult point;     ///< the last point the task ran
  std::filesystem::path shard;  ///< where the finished shard is
  int points_completed = 0;     ///< a curve's task runs its point and the rest of its curve
  int last_point = 0;
};

/// The completed points of a study's curves that a point not completed continues from:
/// the final states a resubmitted curve starts from.
std::vector<int> continued_points(StudyStore& studies, std::int64_t study_id);

/// Writes the folder's study (study.sqlite): the study's row as `store` holds it, the
/// final states of its continued_points and its interrupted points' runs to continue
/// (store/shard_merge.hpp's copy_end_states), in one file without a journal beside it.
/// Replaced whole (renamed into place), so that a task copying it meanwhile gets the old or
/// the new file, both the same study; a point completed stays completed, so the new file
/// holds every final state a task queued before may need.
void write_folder_study(const ShardFolder& folder, RunStore& store, const StudyRecord& study);

/// The folder's study (study.sqlite, written by `pdamp study submit`), read without
/// locks. Throws InputError if it is missing or was written by a pdamp of another schema.
StudyRecord folder_study(const ShardFolder& folder);

/// Copies the folder's study into a new shard store (in `scratch`, or in the folder as a
/// .part file), adds the task's point and the task's own row, runs the point
/// (study::run_study_point) and, for a point of an [frf] or [characterise] curve, the rest
/// of its curve after it in order, each from the one before's final state (the first from
/// the folder's copy of the store's final state, or from the bed), until one does not
/// complete or the curve ends; records how the task ended, and renames the finished shard
/// into place in the folder: a shard under its final name is whole. A stop request ends
/// the point as interrupted, and the shard is still put in place. Throws InputError,
/// writing nothing, for a folder without its study or a point the study does not have.
/// `point_started` is told each point before it runs.
ShardTaskResult run_shard_task(const ShardTaskRequest& request, const study::PointRunControl& control,
                               const std::function<void(int point)>& point_started = {});

}  // namespace pdamp::slurm
