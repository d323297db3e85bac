#include "pdamp/slurm/shard_task.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "pdamp/errors.hpp"
#include "pdamp/store/process_lease.hpp"
#include "pdamp/store/shard_merge.hpp"
#include "pdamp/store/study_store.hpp"

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

/// The task's point in the shard store at `work`: run, and its end recorded.
study::PointResult run_in_shard(const std::filesystem::path& work, const study::Study& study, const StudyRecord& record,
                                const ShardTaskRequest& r, const study::PointRunControl& control) {
  StoreOptions options;
  options.single_process = true;
  RunStore store(work, StoreAccess::modify, options);
  StudyStore studies(store);
  const study::StudyPoint& point = study.points.at(static_cast<std::size_t>(r.point - 1));
  studies.add_points(record.study_id, {{point.point, point.section, point.values, std::nullopt, std::nullopt}});
  StudyTask task = StudyTask::of(r.job, r.task, point.point);
  task.host = this_process_lease().host;
  studies.begin_task(record.study_id, task);
  study::PointResult result = study::run_study_point(store, record.study_id, study, point.point, control);
  studies.end_task(record.study_id, r.job, r.task, result.status, result.message);
  store.make_self_contained();
  return result;
}

}  // namespace

void write_folder_study(const ShardFolder& folder, const StudyRecord& study) {
  const std::filesystem::path part = folder.template_store().string() + ".part";
  remove_store(part);
  {
    StoreOptions options;
    options.single_process = true;
    RunStore store(part, StoreAccess::write, options);
    StudyStore(store).copy_study(study);
    store.make_self_contained();
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

ShardTaskResult run_shard_task(const ShardTaskRequest& r, const study::PointRunControl& control) {
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
  ShardTaskResult result{record.study_id, run_in_shard(work, study, record, r, control), final_file};
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
