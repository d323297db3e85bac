#include "pdamp/slurm/job_script.hpp"

#include <algorithm>
#include <charconv>
#include <regex>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/version.hpp"

namespace pdamp::slurm {
namespace {

constexpr std::string_view shard_prefix = "task-", shard_middle = ".job-", shard_suffix = ".sqlite",
                           part_suffix = ".part";

std::optional<std::int64_t> whole_number(std::string_view text) {
  std::int64_t value = 0;
  const char* end = text.data() + text.size();
  if (text.empty() || text.front() == '-' || text.front() == '+') return std::nullopt;
  if (auto [ptr, ec] = std::from_chars(text.data(), end, value); ec != std::errc() || ptr != end) return std::nullopt;
  return value;
}

/// The text in single quotes for bash.
std::string shell_quoted(const std::string& text) {
  std::string quoted = "'";
  for (const char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string checked(const std::string& text, const std::string& what, const std::regex& valid,
                    const std::string& expected) {
  if (!std::regex_match(text, valid)) throw InputError(what + " '" + text + "': " + expected);
  return text;
}

/// The numbers sorted, each once: the order of a job array's points.
std::vector<std::int64_t> rising(std::vector<std::int64_t> numbers) {
  std::sort(numbers.begin(), numbers.end());
  numbers.erase(std::unique(numbers.begin(), numbers.end()), numbers.end());
  return numbers;
}

}  // namespace

ShardFolder::ShardFolder(const std::filesystem::path& store, std::int64_t study_id)
    : folder_(std::filesystem::absolute(store).lexically_normal().string() + ".shards/study-" +
              std::to_string(study_id)) {}

std::filesystem::path ShardFolder::log(std::int64_t job, std::int64_t task) const {
  return logs() / (std::to_string(job) + "_" + std::to_string(task) + ".log");
}

std::filesystem::path ShardFolder::script(int submission) const {
  return folder_ / ("submit-" + std::to_string(submission) + ".sh");
}

std::filesystem::path ShardFolder::shard(std::int64_t job, std::int64_t task) const {
  return folder_ / (std::string(shard_prefix) + std::to_string(task) + std::string(shard_middle) + std::to_string(job) +
                    std::string(shard_suffix));
}

std::filesystem::path ShardFolder::unfinished(std::int64_t job, std::int64_t task) const {
  return shard(job, task).string() + std::string(part_suffix);
}

std::optional<ShardFolder::Found> ShardFolder::parse(const std::filesystem::path& file) {
  const std::string filename = file.filename().string();
  std::string_view name = filename;
  Found found{0, 0, true, file};
  if (name.ends_with(part_suffix)) {
    found.finished = false;
    name.remove_suffix(part_suffix.size());
  }
  if (!name.starts_with(shard_prefix) || !name.ends_with(shard_suffix)) return std::nullopt;
  name = name.substr(shard_prefix.size(), name.size() - shard_prefix.size() - shard_suffix.size());
  const auto middle = name.find(shard_middle);
  if (middle == std::string_view::npos) return std::nullopt;
  const auto task = whole_number(name.substr(0, middle)), job = whole_number(name.substr(middle + shard_middle.size()));
  if (!task || !job) return std::nullopt;
  found.task = *task;
  found.job = *job;
  return found;
}

std::vector<ShardFolder::Found> ShardFolder::scan() const {
  std::vector<Found> found;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(folder_, error)) {
    if (auto shard = parse(entry.path()); shard && entry.is_regular_file(error)) found.push_back(*shard);
  }
  std::sort(found.begin(), found.end(), [](const Found& a, const Found& b) {
    return std::tie(a.job, a.task, a.finished) < std::tie(b.job, b.task, b.finished);
  });
  return found;
}

// #SBATCH lines are split at white space and scanned for '%' patterns.
std::string checked_script_path(const std::filesystem::path& path) {
  std::string text = path.string();
  const auto bad = std::find_if(text.begin(), text.end(), [](unsigned char c) {
    return c <= ' ' || c == 0x7f || c == '%' || c == '"' || c == '\'' || c == '\\';
  });
  if (bad != text.end()) {
    throw InputError("the shard folder '" + text + "' holds a character (" +
                     (*bad == ' ' ? std::string("a space") : "'" + std::string(1, *bad) + "'") +
                     ") that a job script's #SBATCH lines cannot hold; give the store (--db) a path without white "
                     "space, quotes, '\\' or '%'");
  }
  return text;
}

std::string parse_partition(const std::string& text) {
  static const std::regex valid("[A-Za-z0-9_.-]{1,64}(,[A-Za-z0-9_.-]{1,64}){0,15}");
  return checked(text, "--partition", valid,
                 "a partition name (letters, digits, '_', '.', '-'), or several, comma-separated");
}

std::string parse_account(const std::string& text) {
  static const std::regex valid("[A-Za-z0-9_.-]{1,64}");
  return checked(text, "--account", valid, "an account name (letters, digits, '_', '.', '-')");
}

std::string parse_time_limit(const std::string& text) {
  static const std::regex valid(
      "[0-9]{1,6}(:[0-9]{1,2}){0,2}|[0-9]{1,4}-[0-9]{1,2}(:[0-9]{1,2}){0,2}|UNLIMITED|INFINITE", std::regex::icase);
  return checked(text, "--time", valid,
                 "a time limit per task as Slurm takes it: MINUTES, MINUTES:SECONDS, HOURS:MINUTES:SECONDS, "
                 "DAYS-HOURS, DAYS-HOURS:MINUTES, DAYS-HOURS:MINUTES:SECONDS, or UNLIMITED");
}

std::string parse_scratch(const std::string& text) {
  static const std::regex valid("[A-Za-z0-9_./${}:-]{1,256}");
  return checked(text, "--scratch", valid,
                 "a folder on the compute node, e.g. '$TMPDIR' or /tmp (letters, digits, '_', '.', '/', '-', ':' "
                 "and $NAME or ${NAME} for the task's environment variables)");
}

std::string array_ranges(std::vector<std::int64_t> numbers) {
  numbers = rising(std::move(numbers));
  std::string text;
  for (std::size_t i = 0; i < numbers.size();) {
    std::size_t j = i;
    while (j + 1 < numbers.size() && numbers[j + 1] == numbers[j] + 1) ++j;
    if (!text.empty()) text += ',';
    text += std::to_string(numbers[i]);
    if (j > i) text.append("-").append(std::to_string(numbers[j]));
    i = j + 1;
  }
  return text;
}

std::int64_t nth_in_ranges(std::string_view ranges, std::int64_t index, std::int64_t largest) {
  const auto refuse = [&](const std::string& why) -> std::int64_t {
    throw InputError("the list of points '" + std::string(ranges.substr(0, 200)) + "': " + why);
  };
  if (ranges.empty()) return refuse("no point");
  if (index < 0) return refuse("no task " + std::to_string(index) + " (tasks run from 0)");
  std::int64_t count = 0, previous = 0;
  std::optional<std::int64_t> found;  // the whole list is checked, also past the task's point
  for (std::string_view rest = ranges;;) {
    const auto comma = rest.find(',');
    const std::string_view part = rest.substr(0, comma);
    const auto dash = part.find('-');
    const auto first = whole_number(part.substr(0, dash));
    const auto last = dash == std::string_view::npos ? first : whole_number(part.substr(dash + 1));
    if (!first || !last || *first < 1 || *last < *first || *last > largest) {
      return refuse("'" + std::string(part.substr(0, 40)) + "' is not a point or a range FIRST-LAST of points 1 to " +
                    std::to_string(largest));
    }
    if (*first <= previous) return refuse("the points must rise");
    if (!found && index < count + (*last - *first + 1)) found = *first + (index - count);
    count += *last - *first + 1;
    previous = *last;
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
  if (found) return *found;
  return refuse("it has " + std::to_string(count) + " points, so no task " + std::to_string(index) +
                " (tasks run from 0)");
}

std::vector<std::vector<std::int64_t>> array_chunks(std::vector<std::int64_t> points, std::int64_t max_array_size) {
  points = rising(std::move(points));
  std::vector<std::vector<std::int64_t>> chunks;
  for (std::size_t i = 0; i < points.size(); i += static_cast<std::size_t>(max_array_size)) {
    const auto end = std::min(points.size(), i + static_cast<std::size_t>(max_array_size));
    chunks.emplace_back(points.begin() + static_cast<std::ptrdiff_t>(i),
                        points.begin() + static_cast<std::ptrdiff_t>(end));
  }
  return chunks;
}

std::string job_script(const JobScriptRequest& r) {
  const SlurmOptions& o = r.options;
  std::ostringstream s;
  const std::size_t n_points = rising(r.points).size();
  s << "#!/bin/bash\n"
    << "# pdamp study " << r.study_id << ": " << n_points
    << (r.curves ? " curves as a job array, one task per curve (task T runs the T-th of --points, from 0,\n"
                   "# then the rest of its curve).\n"
                 : " points as a job array, one task per point (task T runs the T-th of --points, from 0).\n")
    << "# Written by 'pdamp study submit' (pdamp " << version_string << "), which records the job in the\n"
    << "# study's store. Each task writes its own shard store in " << checked_script_path(r.folder.path()) << ";\n"
    << "# 'pdamp study collect " << r.study_id << "' merges them into the store.\n"
    << "#SBATCH --job-name=pdamp-study-" << r.study_id << "\n"
    << "#SBATCH --array=0-" << n_points - 1 << (o.max_parallel > 0 ? "%" + std::to_string(o.max_parallel) : "") << "\n"
    << "#SBATCH --ntasks=1\n"
    << "#SBATCH --cpus-per-task=" << o.threads << "\n"
    << "#SBATCH --output=" << checked_script_path(r.folder.logs()) << "/%A_%a.log\n";
  if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
  if (!o.account.empty()) s << "#SBATCH --account=" << o.account << "\n";
  if (!o.time_limit.empty()) s << "#SBATCH --time=" << o.time_limit << "\n";
  s << "exec " << shell_quoted(r.pdamp.string()) << " study task " << shell_quoted(r.folder.path().string())
    << " --job \"$SLURM_ARRAY_JOB_ID\" --task \"$SLURM_ARRAY_TASK_ID\" --points " << array_ranges(r.points)
    << " --threads \"${SLURM_CPUS_PER_TASK:-1}\" --checkpoint-every " << shell_quoted(o.checkpoint_every);
  if (!o.scratch.empty()) s << " --scratch \"" << o.scratch << "\"";
  s << "\n";
  return s.str();
}

}  // namespace pdamp::slurm
