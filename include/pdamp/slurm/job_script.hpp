#pragma once
/// A study as a Slurm job array: where its files go beside the store (ShardFolder), the
/// options of its job script, and the script itself.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pdamp::slurm {

/// A study's files on the cluster, in `STORE.shards/study-ID/` beside its store:
///   study.sqlite                  the study (no points), copied by each task into its shard
///   submit-K.sh                   the job scripts, one per submission
///   logs/JOB_TASK.log             each task's output (Slurm's %A_%a)
///   task-T.job-J.sqlite           the shard store of task T of job J (the T-th point it runs)
///   task-T.job-J.sqlite.part      the same while it is written, or left by a killed task
class ShardFolder {
 public:
  ShardFolder(const std::filesystem::path& store, std::int64_t study_id);
  explicit ShardFolder(std::filesystem::path folder) : folder_(std::move(folder)) {}

  const std::filesystem::path& path() const { return folder_; }
  std::filesystem::path template_store() const { return folder_ / "study.sqlite"; }
  std::filesystem::path logs() const { return folder_ / "logs"; }
  std::filesystem::path log(std::int64_t job, std::int64_t task) const;
  std::filesystem::path script(int submission) const;
  std::filesystem::path shard(std::int64_t job, std::int64_t task) const;
  std::filesystem::path unfinished(std::int64_t job, std::int64_t task) const;

  /// A shard file found in the folder.
  struct Found {
    std::int64_t job = 0, task = 0;
    bool finished = false;  ///< false: a .part file
    std::filesystem::path file;
  };
  /// The shard files in the folder, by job and task; other files are ignored.
  std::vector<Found> scan() const;
  /// A shard file's job and task from its name; nothing for any other name.
  static std::optional<Found> parse(const std::filesystem::path& file);

 private:
  std::filesystem::path folder_;
};

/// What `pdamp study submit` asks of Slurm, each checked when read.
struct SlurmOptions {
  std::string partition;   ///< empty: the cluster's default
  std::string account;     ///< empty: the user's default
  std::string time_limit;  ///< per task; empty: the partition's default
  int max_parallel = 0;    ///< tasks run at once (%K); 0: as many as Slurm allows
  int threads = 1;         ///< cores per task (--cpus-per-task): the soft engine's threads
  std::string scratch;     ///< a folder on the node for the shard while it is written; empty: none
  /// The tasks' --checkpoint-every (seconds, as given and checked): a resubmitted point
  /// goes on from its checkpoint.
  std::string checkpoint_every = "60";
};

/// Each option's value checked; InputError naming the option and what is valid.
std::string parse_partition(const std::string& text);
std::string parse_account(const std::string& text);
std::string parse_time_limit(const std::string& text);
std::string parse_scratch(const std::string& text);

/// The shard folder's path as a job script's #SBATCH lines take it. Throws InputError for
/// a path they cannot hold (white space, quotes, '\\', '%'), naming the character.
std::string checked_script_path(const std::filesystem::path& path);

/// Numbers (array indices, points) as Slurm's --array list: "1-3,5,7-8", sorted, each once.
std::string array_ranges(std::vector<std::int64_t> numbers);

/// The `index`-th (from 0) number of a list array_ranges writes, found without expanding
/// it. Throws InputError naming the text for anything array_ranges does not write (or a
/// number above `largest`), and for an index beyond the list.
std::int64_t nth_in_ranges(std::string_view ranges, std::int64_t index, std::int64_t largest);

/// Slurm's default MaxArraySize: array indices 0 to 1000.
inline constexpr std::int64_t default_max_array_size = 1001;

/// Points sorted, each once, and split into job arrays of at most `max_array_size` tasks
/// each (Slurm takes array indices 0 to MaxArraySize − 1).
std::vector<std::vector<std::int64_t>> array_chunks(std::vector<std::int64_t> points, std::int64_t max_array_size);

struct JobScriptRequest {
  std::int64_t study_id = 0;
  std::string study_name;
  std::filesystem::path pdamp;  ///< the executable the tasks run
  ShardFolder folder;
  std::vector<std::int64_t> points;  ///< task T of the array (from 0) runs the T-th of them, in rising order
  SlurmOptions options;
  bool curves = false;  ///< an [frf] or [characterise] study: a task runs the rest of its point's curve too
};

/// The job array's script: #SBATCH lines, then the task (`pdamp study task`), which finds
/// its point from its index in the list of points the script gives it. Throws InputError
/// for a shard folder #SBATCH lines cannot hold (checked_script_path).
std::string job_script(const JobScriptRequest& request);

}  // namespace pdamp::slurm
