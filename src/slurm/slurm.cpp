#include "pdamp/slurm/slurm.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/slurm/job_script.hpp"
#include "pdamp/slurm/program.hpp"

namespace pdamp::slurm {
namespace {

std::optional<std::int64_t> number(std::string_view text) {
  std::int64_t value = 0;
  const char* end = text.data() + text.size();
  if (auto [ptr, ec] = std::from_chars(text.data(), end, value); ec != std::errc() || ptr != end || text.empty()) {
    return std::nullopt;
  }
  return value;
}

std::string first_line(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  return line.empty() ? "no message" : line;
}

std::string joined(const std::vector<std::int64_t>& jobs) {
  std::string text;
  for (const auto job : jobs) text += (text.empty() ? "" : ",") + std::to_string(job);
  return text;
}

/// The tasks a task field names: "7", or a pending range "[3-5,8%2]".
std::vector<std::int64_t> tasks_named(std::string_view field) {
  if (auto single = number(field)) return {*single};
  std::vector<std::int64_t> tasks;
  if (!field.starts_with('[') || !field.ends_with(']')) return tasks;
  field = field.substr(1, field.size() - 2);
  field = field.substr(0, field.find('%'));
  std::istringstream parts{std::string(field)};
  for (std::string part; std::getline(parts, part, ',');) {
    const auto dash = part.find('-');
    const auto first = number(std::string_view(part).substr(0, dash));
    const auto last = dash == std::string::npos ? first : number(std::string_view(part).substr(dash + 1));
    if (!first || !last || *last < *first || *last - *first > 1'000'000) continue;
    for (auto t = *first; t <= *last; ++t) tasks.push_back(t);
  }
  return tasks;
}

void add(TaskStates& states, const std::vector<std::int64_t>& jobs, std::int64_t job, std::string_view task_field,
         const std::string& state) {
  if (std::find(jobs.begin(), jobs.end(), job) == jobs.end()) return;
  for (const auto task : tasks_named(task_field)) states[{job, task}] = state;
}

/// Runs one of Slurm's programs and parses its answer into task states.
SlurmReport ask(const std::vector<std::string>& argv,
                TaskStates (*parse)(std::string_view, const std::vector<std::int64_t>&),
                const std::vector<std::int64_t>& jobs) {
  if (!find_program(argv[0])) return {false, "'" + argv[0] + "' is not installed here", {}};
  try {
    const ProgramResult r = run_program(argv, std::chrono::seconds(60));
    if (r.exit_code != 0) {
      const std::string line = first_line(r.err);
      return {false, line.starts_with(argv[0] + ":") ? line : argv[0] + ": " + line, {}};
    }
    return {true, "", parse(r.out, jobs)};
  } catch (const RuntimeFailure& e) {
    return {false, e.what(), {}};
  }
}

}  // namespace

std::int64_t parse_job_id(std::string_view answer) {
  std::string_view line = answer.substr(0, answer.find('\n'));
  line = line.substr(0, line.find(';'));
  if (const auto id = number(line); id && *id > 0) return *id;
  throw RuntimeFailure("sbatch answered '" + std::string(answer.substr(0, 200)) + "', not a job id");
}

std::int64_t submit(const std::filesystem::path& script) {
  if (!find_program("sbatch")) {
    throw RuntimeFailure("sbatch is not installed here: submit from a machine of the Slurm cluster (a login node)");
  }
  const ProgramResult r = run_program({"sbatch", "--parsable", script.string()}, std::chrono::seconds(120));
  if (r.exit_code != 0) {
    std::string reason = r.err;
    while (!reason.empty() && std::isspace(static_cast<unsigned char>(reason.back()))) reason.pop_back();
    throw RuntimeFailure("sbatch refused the job script " + script.string() + ": " + reason);
  }
  return parse_job_id(r.out);
}

TaskStates parse_queue(std::string_view text, const std::vector<std::int64_t>& jobs) {
  TaskStates states;
  std::istringstream lines{std::string(text)};
  for (std::string line; std::getline(lines, line);) {
    const auto a = line.find('|'), b = line.find('|', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    if (const auto job = number(std::string_view(line).substr(0, a))) {
      add(states, jobs, *job, std::string_view(line).substr(a + 1, b - a - 1), line.substr(b + 1));
    }
  }
  return states;
}

TaskStates parse_accounting(std::string_view text, const std::vector<std::int64_t>& jobs) {
  TaskStates states;
  std::istringstream lines{std::string(text)};
  for (std::string line; std::getline(lines, line);) {
    const auto bar = line.find('|'), underscore = line.find('_');
    if (bar == std::string::npos || underscore == std::string::npos || underscore > bar) continue;
    std::string state = line.substr(bar + 1);
    state = state.substr(0, state.find(' '));  // "CANCELLED by 0"
    if (const auto job = number(std::string_view(line).substr(0, underscore))) {
      add(states, jobs, *job, std::string_view(line).substr(underscore + 1, bar - underscore - 1), state);
    }
  }
  return states;
}

SlurmReport queue_states(const std::vector<std::int64_t>& jobs, const std::string& job_name) {
  const std::vector<std::string> argv{"squeue",       "--noheader",         "--array",
                                      "--states=all", "--name=" + job_name, "--format=%F|%K|%T"};
  return ask(argv, parse_queue, jobs);
}

SlurmReport accounting_states(const std::vector<std::int64_t>& jobs) {
  const std::vector<std::string> argv{
      "sacct", "--noheader", "--parsable2", "--allocations", "--jobs=" + joined(jobs), "--format=JobID,State"};
  return ask(argv, parse_accounting, jobs);
}

std::optional<std::int64_t> parse_max_array_size(std::string_view config) {
  std::istringstream lines{std::string(config)};
  for (std::string line; std::getline(lines, line);) {
    const auto equals = line.find('=');
    if (equals == std::string::npos) continue;
    std::string_view key = std::string_view(line).substr(0, equals), value = std::string_view(line).substr(equals + 1);
    while (key.ends_with(' ')) key.remove_suffix(1);
    while (value.starts_with(' ')) value.remove_prefix(1);
    if (key == "MaxArraySize") return number(value);
  }
  return std::nullopt;
}

ArrayLimit array_limit() {
  const auto assumed = [](const std::string& why) {
    return ArrayLimit{default_max_array_size, why + ": job arrays of at most " +
                                                  std::to_string(default_max_array_size) +
                                                  " tasks assumed (Slurm's default MaxArraySize)"};
  };
  if (!find_program("scontrol")) return assumed("'scontrol' is not installed here");
  ProgramResult r;
  try {
    r = run_program({"scontrol", "show", "config"}, std::chrono::seconds(60));
  } catch (const RuntimeFailure& e) {
    return assumed(e.what());
  }
  if (r.exit_code != 0) return assumed("scontrol show config: " + first_line(r.err));
  const auto size = parse_max_array_size(r.out);
  if (!size) return assumed("scontrol show config names no MaxArraySize");
  if (*size < 1) {
    throw RuntimeFailure("the cluster takes no job arrays (MaxArraySize = " + std::to_string(*size) +
                         " in scontrol show config), and pdamp submits a study as one; nothing was submitted");
  }
  return {*size, ""};
}

bool in_flight(std::string_view state) {
  static constexpr std::string_view running[] = {"PENDING",   "RUNNING",   "CONFIGURING", "COMPLETING",
                                                 "SUSPENDED", "REQUEUED",  "REQUEUE_FED", "REQUEUE_HOLD",
                                                 "RESIZING",  "SIGNALING", "STAGE_OUT",   "STOPPED"};
  return std::find(std::begin(running), std::end(running), state) != std::end(running);
}

}  // namespace pdamp::slurm
