#pragma once
/// Asking Slurm: submitting a job script (sbatch), and the states of a study's array tasks
/// from the queue (squeue) and from accounting (sacct, absent on clusters without
/// slurmdbd).

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace pdamp::slurm {

/// Submits a job script with `sbatch --parsable`; returns the job id. Throws
/// RuntimeFailure with sbatch's own message if it refuses.
std::int64_t submit(const std::filesystem::path& script);
/// The job id in sbatch --parsable's answer ("JOB" or "JOB;CLUSTER"); RuntimeFailure else.
std::int64_t parse_job_id(std::string_view answer);

/// (job, array task) → Slurm's state of the task (PENDING, RUNNING, COMPLETED, ...).
using TaskStates = std::map<std::pair<std::int64_t, std::int64_t>, std::string>;

/// What one of Slurm's programs told about a study's tasks.
struct SlurmReport {
  bool available = false;  ///< false: the program is missing or failed; `problem` says why
  std::string problem;
  TaskStates states;
};

/// The queue's states of the tasks of `jobs` (squeue keeps finished tasks for MinJobAge,
/// 300 s by default). `job_name` narrows the query to the study's jobs.
SlurmReport queue_states(const std::vector<std::int64_t>& jobs, const std::string& job_name);
/// The accounting's states of the tasks of `jobs` (sacct), for good.
SlurmReport accounting_states(const std::vector<std::int64_t>& jobs);

/// Parses lines "JOB|TASK|STATE" (squeue -o '%F|%K|%T') or "JOB_TASK|STATE" (sacct -P -o
/// JobID,State) into the states of the tasks of `jobs`; a pending range "JOB_[3-8%2]" names
/// each of its tasks.
TaskStates parse_queue(std::string_view text, const std::vector<std::int64_t>& jobs);
TaskStates parse_accounting(std::string_view text, const std::vector<std::int64_t>& jobs);

/// The cluster's limit on a job array (MaxArraySize: indices 0 to it − 1).
struct ArrayLimit {
  std::int64_t max_array_size = 0;
  std::string problem;  ///< why scontrol did not tell, and Slurm's default was assumed; empty if it did
};
/// MaxArraySize from `scontrol show config`; Slurm's default (1001) with the reason where
/// scontrol is missing or does not answer. Throws RuntimeFailure if the cluster has job
/// arrays turned off (MaxArraySize 0).
ArrayLimit array_limit();
/// The MaxArraySize line of `scontrol show config`'s answer ("MaxArraySize = 1001"), or
/// nothing if it has none.
std::optional<std::int64_t> parse_max_array_size(std::string_view config);

/// Whether a state means the task may still run (queued, running, or being requeued).
bool in_flight(std::string_view state);

}  // namespace pdamp::slurm
