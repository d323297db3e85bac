#pragma once
/// One task of a study's job array (`pdamp study task`): its point run into a shard store
/// of its own, never into the study's store, which the tasks of a cluster must not share
/// (SQLite's locks over NFS and Lustre are not reliable).

#include <cstdint>
#include <filesystem>

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
  study::PointResult point;
  std::filesystem::path shard;  ///< where the finished shard is
};

/// Writes the folder's study (study.sqlite): the study's row alone, as the store holds it,
/// in one file without a journal beside it. Replaced whole (renamed into place), so that a
/// task copying it meanwhile gets the old or the new file, both the same study.
void write_folder_study(const ShardFolder& folder, const StudyRecord& study);

/// The folder's study (study.sqlite, written by `pdamp study submit`), read without
/// locks. Throws InputError if it is missing or was written by a pdamp of another schema.
StudyRecord folder_study(const ShardFolder& folder);

/// Copies the folder's study into a new shard store (in `scratch`, or in the folder as a
/// .part file), adds the task's point and the task's own row, runs the point
/// (study::run_study_point), records how the task ended, and renames the finished shard
/// into place in the folder: a shard under its final name is whole. A stop request ends
/// the point as interrupted, and the shard is still put in place. Throws InputError,
/// writing nothing, for a folder without its study or a point the study does not have.
ShardTaskResult run_shard_task(const ShardTaskRequest& request, const study::PointRunControl& control);

}  // namespace pdamp::slurm
