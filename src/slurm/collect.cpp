#include "pdamp/slurm/collect.hpp"

#include <algorithm>
#include <map>
#include <set>

#include "pdamp/errors.hpp"

namespace pdamp::slurm {
namespace {

using TaskKey = std::pair<std::int64_t, std::int64_t>;

/// The shard files of the folders by (job, task): a finished one over a .part.
std::map<TaskKey, ShardFolder::Found> shard_files(const std::vector<ShardFolder>& folders) {
  std::map<TaskKey, ShardFolder::Found> files;
  for (const auto& folder : folders) {
    for (auto& found : folder.scan()) {
      auto& slot = files[{found.job, found.task}];
      if (slot.file.empty() || found.finished) slot = found;
    }
  }
  return files;
}

}  // namespace

std::vector<ShardFolder> study_folders(StudyStore& studies, const std::filesystem::path& store, std::int64_t study_id) {
  std::vector<ShardFolder> folders;
  std::set<std::filesystem::path> seen;
  for (const auto& job : studies.jobs(study_id)) {
    if (seen.insert(job.shard_folder).second) folders.emplace_back(std::filesystem::path(job.shard_folder));
  }
  const ShardFolder beside(store, study_id);
  if (seen.insert(beside.path()).second) folders.push_back(beside);
  return folders;
}

CollectReport collect_shards(RunStore& store, const StudyRecord& study, const std::vector<ShardFolder>& folders) {
  StudyStore studies(store);
  std::set<TaskKey> collected;
  for (const auto& task : studies.tasks(study.study_id)) {
    if (task.collected()) collected.insert({task.job_id, task.task});
  }
  CollectReport report;
  for (const auto& [key, found] : shard_files(folders)) {
    if (!found.finished) continue;
    if (collected.contains(key)) {
      ++report.already_collected;
      continue;
    }
    try {
      ShardMerge merge = merge_shard(store, study, found.file);
      if (merge.already_collected) {
        ++report.already_collected;
      } else {
        report.merged.push_back(std::move(merge));
      }
    } catch (const InputError& e) {
      report.refused.emplace_back(e.what());
    }
  }
  return report;
}

std::string_view to_string(TaskStanding standing) {
  switch (standing) {
    case TaskStanding::collected:
      return "collected";
    case TaskStanding::waiting:
      return "shard waiting";
    case TaskStanding::in_queue:
      return "in the queue";
    case TaskStanding::unfinished:
      return "unfinished shard";
    case TaskStanding::missing:
      break;
  }
  return "missing";
}

std::vector<TaskView> task_views(StudyStore& studies, std::int64_t study_id, const std::vector<ShardFolder>& folders,
                                 const SlurmReport& queue, const SlurmReport& accounting) {
  auto files = shard_files(folders);
  std::vector<TaskView> views;
  for (auto& task : studies.tasks(study_id)) views.push_back({std::move(task), TaskStanding::missing, "", {}});
  for (const auto& [key, found] : files) {  // shards of tasks the store does not know (a lost submission)
    // The key by name: clang before 16 cannot capture a structured binding.
    const bool known = std::any_of(views.begin(), views.end(), [&job_task = key](const TaskView& v) {
      return v.task.job_id == job_task.first && v.task.task == job_task.second;
    });
    if (!known)
      views.push_back(
          {StudyTask::of(key.first, key.second, static_cast<int>(key.second)), TaskStanding::missing, "", {}});
  }
  for (auto& view : views) {
    const TaskKey key{view.task.job_id, view.task.task};
    if (const auto it = queue.states.find(key); it != queue.states.end()) {
      view.slurm_state = it->second;
    } else if (const auto acct = accounting.states.find(key); acct != accounting.states.end()) {
      view.slurm_state = acct->second;
    }
    const auto file = files.find(key);
    if (file != files.end()) view.file = file->second.file;
    if (view.task.collected()) {
      view.standing = TaskStanding::collected;
    } else if (file != files.end() && file->second.finished) {
      view.standing = TaskStanding::waiting;
    } else if (in_flight(view.slurm_state)) {
      view.standing = TaskStanding::in_queue;
    } else if (file != files.end()) {
      view.standing = TaskStanding::unfinished;
    }
  }
  std::sort(views.begin(), views.end(), [](const TaskView& a, const TaskView& b) {
    return std::tie(a.task.job_id, a.task.task) < std::tie(b.task.job_id, b.task.task);
  });
  return views;
}

std::vector<std::int64_t> points_to_submit(StudyStore& studies, std::int64_t study_id,
                                           const std::vector<TaskView>& tasks) {
  std::set<int> busy;
  for (const auto& view : tasks) {
    if (view.standing != TaskStanding::in_queue && view.standing != TaskStanding::waiting) continue;
    for (const int point : studies.curve_from(study_id, view.task.point)) busy.insert(point);
  }
  std::set<int> completed;
  const auto points = studies.points(study_id);
  for (const auto& p : points) {
    if (p.status == PointStatus::completed) completed.insert(p.point);
  }
  const auto previous = studies.previous_points(study_id);
  std::vector<std::int64_t> starts;
  for (const auto& p : points) {
    if (p.status == PointStatus::completed || p.status == PointStatus::running || busy.contains(p.point)) continue;
    // A point continuing one not completed runs in the task of the curve before it.
    const auto from = previous.find(p.point);
    if (from == previous.end() || completed.contains(from->second)) starts.push_back(p.point);
  }
  return starts;
}

}  // namespace pdamp::slurm
