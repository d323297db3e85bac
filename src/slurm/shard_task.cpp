#include "pdamp/slurm/shard_task.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <set>

#include "pdamp/errors.hpp"
#include "pdamp/store/process_lease.hpp"
#include "pdamp/store/shard_merge.hpp"
#include "pdamp/store/study_store.hpp"
#include "pdamp/study/study_runner.hpp"

namespace pdamp::slurm {
namespace {

/// Writes a file's (or a folder's) data to disk, so that a rename after it never exposes a
/// shard whose content is not there yet.
void sync(const std::filesystem::path& path) {
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0 || fsync(fd) != 0) {
    const std::string reason = std::strerror(errno);
    if (fd >= 0) close(fd);
    throw RuntimeFailure("cannot write '" + path.string() + "' to disk: " + reason);
  }
  close(fd);
}

/// Removes a store file with what SQLite may have left beside it.
void remove_store(const std::filesystem::path& file) {
  for (const char* suffix : {"", "-wal", "-shm", "-journal"}) std::filesystem::remove(file.string() + suffix);
}

void copy_whole(const std::filesystem::path& from, const std::filesystem::path& to) {
  std::error_code error;
  std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing, error);
  if (error) throw RuntimeFailure("cannot copy '" + from.string() + "' to '" + to.string() + "': " + error.message());
}

/// The task's points in the shard store at `work`: its point and (a curve's task) the rest
/// of its curve after it, each from the one before, until one does not complete; the
/// task's end recorded with the last point's status.
ShardTaskResult run_in_shard(const std::filesystem::path& work, const study::Study& study, const StudyRecord& record,
                             const ShardTaskRequest& r, const study::PointRunControl& control,
                             const std::function<void(int point)>& point_started) {
  StoreOptions options;
  options.single_process = true;
  RunStore store(work, StoreAccess::modify, options);
  StudyStore studies(store);
  const auto stored = [&](int point) {
    return study::stored_point(study, study.points.at(static_cast<std::size_t>(point - 1)));
  };
  const int first = static_cast<int>(r.point);
  // The folder's study holds the point if the store had completed it (it is not run again)
  // or had it interrupted with runs to continue.
  if (!studies.point(record.study_id, first)) studies.add_points(record.study_id, {stored(first)});
  std::vector<NewStudyPoint> rest;
  std::vector<int> points{first};  // the curve from `first`, as the study defines it
  for (const auto& p : study.points) {
    if (p.previous() != 0 && p.previous() == points.back()) points.push_back(p.point);
  }
  for (std::size_t i = 1; i < points.size(); ++i) {
    // A point the folder's study holds is a final state copied from the store: the curve
    // was completed from there on before.
    if (studies.point(record.study_id, points[i])) {
      points.resize(i);
      break;
    }
    rest.push_back(stored(points[i]));
  }
  studies.add_points(record.study_id, rest);
  StudyTask task = StudyTask::of(r.job, r.task, first);
  task.host = this_process_lease().host;
  studies.begin_task(record.study_id, task);
  ShardTaskResult result{record.study_id, {}, {}, 0, first};
  for (const int point : points) {
    result.last_point = point;
    if (point_started) point_started(point);
    result.point = study::run_study_point(store, record.study_id, study, point, control);
    if (result.point.status != PointStatus::completed) break;
    ++result.points_completed;
  }
  studies.end_task(record.study_id, r.job, r.task, result.point.status,
                   points.size() > 1 && result.point.status != PointStatus::completed
                       ? "point " + std::to_string(result.last_point) + ": " + result.point.message
                       : result.point.message);
  store.make_self_contained();
  return result;
}

}  // namespace

std::vector<int> continued_points(StudyStore& studies, std::int64_t study_id) {
  std::set<int> completed;
  for (const auto& p : studies.points(study_id)) {
    if (p.status == PointStatus::completed) completed.insert(p.point);
  }
  std::set<int> continued;
  for (const auto& [point, previous] : studies.previous_points(study_id)) {
    if (!completed.contains(point) && completed.contains(previous)) continued.insert(previous);
  }
  return {continued.begin(), continued.end()};
}

void write_folder_study(const ShardFolder& folder, RunStore& store, const StudyRecord& study) {
  const std::filesystem::path part = folder.template_store().string() + ".part";
  remove_store(part);
  {
    StoreOptions options;
    options.single_process = true;
    RunStore folder_store(part, StoreAccess::write, options);
    StudyStore(folder_store).copy_study(study);
    StudyStore studies(store);
    copy_end_states(store, study.study_id, continued_points(studies, study.study_id), folder_store);
    folder_store.make_self_contained();
  }
  sync(part);
  std::filesystem::rename(part, folder.template_store());
}

StudyRecord folder_study(const ShardFolder& folder) {
  const auto file = folder.template_store();
  if (!std::filesystem::is_regular_file(file)) {
    throw InputError("'" + file.string() + "' is missing: a shard folder's study is written by 'pdamp study submit'");
  }
  const auto [version, studies] = read_store_studies(file);
  if (version != RunStore::schema_version()) {
    throw InputError("'" + file.string() + "' has schema version " + std::to_string(version) + ", this pdamp " +
                     std::to_string(RunStore::schema_version()) +
                     ": the job script must run the pdamp that submitted it");
  }
  if (studies.size() != 1) throw InputError("'" + file.string() + "' does not hold one study");
  return studies.front();
}

ShardTaskResult run_shard_task(const ShardTaskRequest& r, const study::PointRunControl& control,
                               const std::function<void(int point)>& point_started) {
  const StudyRecord record = folder_study(r.folder);
  const study::Study study = study::stored_study(record);
  if (r.point < 1 || static_cast<std::size_t>(r.point) > study.points.size()) {
    throw InputError("task " + std::to_string(r.task) + ": point " + std::to_string(r.point) + ": study " +
                     std::to_string(record.study_id) + " has points 1 to " + std::to_string(study.points.size()));
  }
  const auto final_file = r.folder.shard(r.job, r.task), part = r.folder.unfinished(r.job, r.task);
  const auto work = r.scratch.empty() ? part : r.scratch / ("pdamp-" + final_file.filename().string());
  if (!r.scratch.empty()) std::filesystem::create_directories(r.scratch);
  remove_store(work);  // a requeued task starts afresh
  copy_whole(r.folder.template_store(), work);
  ShardTaskResult result = run_in_shard(work, study, record, r, control, point_started);
  result.shard = final_file;
  if (work != part) {
    copy_whole(work, part);
    remove_store(work);
  }
  sync(part);
  std::filesystem::rename(part, final_file);
  sync(r.folder.path());
  return result;
}

}  // namespace pdamp::slurm
