#pragma once
/// Merging a shard store into its study's store (`pdamp study collect`). A shard store is
/// the store one cluster task wrote on its own (`pdamp study task`): the study, the task's
/// point with its runs, settled bed and metrics (a curve's task: each point it ran along
/// the curve, with its final state), and the task's own `study_tasks` row. Each
/// shard is merged in one transaction, all of it or nothing, with new ids for its runs,
/// comparison and beds; a bed the store holds already (the same settings) is shared.

#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pdamp/store/run_store.hpp"
#include "pdamp/store/study_store.hpp"

namespace pdamp {

/// What merging one shard did.
struct ShardMerge {
  StudyTask task;                  ///< the shard's task as it tells: job, task, point, host, times, outcome
  bool already_collected = false;  ///< merged before: nothing added now
  bool results_added = false;      ///< its point's runs, status and metrics were added
  std::string not_added;           ///< why not (or not all of a curve's), when the shard was not collected before
  int points = 0;                  ///< points whose results were added: a curve's task runs several
  int runs = 0;                    ///< runs added
  int beds_added = 0;              ///< settled beds added
  int beds_shared = 0;             ///< settled beds the store held already, the same bits
};

/// A store file as it is (read from a snapshot, never migrated or written): its schema
/// version and its studies. For a shard folder's template, which the tasks check.
struct StoreFileStudies {
  int schema_version = 0;
  std::vector<StudyRecord> studies;
};
StoreFileStudies read_store_studies(const std::filesystem::path& file);

/// The tables a shard's rows are merged into, and those left alone: the study's
/// definition, which must be the store's (studies, study_point_values), and the store's own
/// submissions (study_jobs). Every table of the schema is in one of the two (a test checks).
std::span<const std::string_view> merged_tables();
std::span<const std::string_view> unmerged_tables();

/// Merges the shard store `shard` of `study` into `store`; a shard collected before adds
/// nothing. A point the store has completed (or is running) keeps its results: the shard's
/// are not added (ShardMerge::not_added says so), nor those of the points of its curve
/// after it, which continued from a final state the store does not hold. Throws InputError, adding nothing, for a
/// file that is not a shard of this study: not a pdamp store, another schema version or
/// other tables than the store's, another study, no single task of its own, a point the
/// study does not have, or a settled bed that differs from the store's bed of the same
/// settings.
ShardMerge merge_shard(RunStore& store, const StudyRecord& study, const std::filesystem::path& shard);

/// Copies what a shard folder's tasks start from out of `store` into `target` (the folder's
/// study, which each task copies), under the store's ids and labels, so that the tasks
/// continue from them and collect finds them the store's:
/// - the final states of the completed curve points `points` of study `study_id`: each
///   point's row, its final state with its run's row and the run's own bed, a
///   frequency-response point's metrics (which start = predict predicts from);
/// - each interrupted point that starts from the bed or from a completed point, with the
///   runs of its latest attempt (rows, samples, cycles, checkpoints, beds), its row and
///   links under attempt 0: the task's first attempt resumes them from their checkpoints
///   (or says why it cannot and runs them again).
/// Throws RuntimeFailure for a point of `points` without a final state.
void copy_end_states(RunStore& store, std::int64_t study_id, const std::vector<int>& points, RunStore& target);

}  // namespace pdamp
