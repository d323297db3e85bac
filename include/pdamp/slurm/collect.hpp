#pragma once
/// A study on Slurm as it stands: its tasks from the store, the shard folder and Slurm, and
/// collecting the finished shards into the study's store (`pdamp study collect`).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pdamp/slurm/job_script.hpp"
#include "pdamp/slurm/slurm.hpp"
#include "pdamp/store/shard_merge.hpp"
#include "pdamp/store/study_store.hpp"

namespace pdamp::slurm {

/// The study's shard folders: those its jobs were submitted with, else the one beside the
/// store.
std::vector<ShardFolder> study_folders(StudyStore& studies, const std::filesystem::path& store, std::int64_t study_id);

struct CollectReport {
  std::vector<ShardMerge> merged;    ///< shards merged now (with or without their results)
  int already_collected = 0;         ///< finished shards collected before
  std::vector<std::string> refused;  ///< one line per shard refused, nothing added from it
};

/// Merges every finished shard in the folders that was not collected before, one
/// transaction each (store/shard_merge.hpp). A refused shard is reported, not merged.
CollectReport collect_shards(RunStore& store, const StudyRecord& study, const std::vector<ShardFolder>& folders);

/// Where a task stands.
enum class TaskStanding {
  collected,   ///< its shard is merged: StudyTask::outcome tells how its point ended
  waiting,     ///< its shard is finished, not yet collected
  in_queue,    ///< Slurm has it pending or running
  unfinished,  ///< only a .part shard: the task was killed while running (or still runs)
  missing,     ///< no shard and not in the queue: it never ran, or died before its shard
};
std::string_view to_string(TaskStanding standing);

struct TaskView {
  StudyTask task;
  TaskStanding standing = TaskStanding::missing;
  std::string slurm_state;     ///< the queue's or the accounting's state; empty if neither knows
  std::filesystem::path file;  ///< its shard (or .part) file, if any
};

/// Every task of the study's jobs, and any shard found for a task the store does not know.
std::vector<TaskView> task_views(StudyStore& studies, std::int64_t study_id, const std::vector<ShardFolder>& folders,
                                 const SlurmReport& queue, const SlurmReport& accounting);

/// The points to submit: not completed (nor running in a local `pdamp study run`), and
/// without a task in the queue or a shard waiting to be collected (a curve's task counts
/// for the rest of its curve). Of a curve, only the first such point, whose task runs the
/// rest: one continuing the bed or a completed point.
std::vector<std::int64_t> points_to_submit(StudyStore& studies, std::int64_t study_id,
                                           const std::vector<TaskView>& tasks);

}  // namespace pdamp::slurm
