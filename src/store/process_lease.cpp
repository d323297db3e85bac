#include "pdamp/store/process_lease.hpp"

#include <unistd.h>

#include <climits>
#include <fstream>
#include <optional>
#include <sstream>

namespace pdamp {

std::string this_host_name() {
  char name[HOST_NAME_MAX + 1] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "unknown";
  return name;
}

namespace {

struct ProcessStat {
  char state = '?';
  std::int64_t start_ticks = 0;
};

/// State and start time of a process from /proc/PID/stat (fields 3 and 22; the command
/// name in field 2 may hold spaces and parentheses, so fields are counted after its last ')').
std::optional<ProcessStat> read_stat(std::int64_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(in, line)) return std::nullopt;
  const auto close = line.rfind(')');
  if (close == std::string::npos) return std::nullopt;
  std::istringstream fields(line.substr(close + 1));
  ProcessStat stat;
  fields >> stat.state;
  std::string skipped;
  for (int field = 4; field < 22; ++field) fields >> skipped;
  fields >> stat.start_ticks;
  if (!fields) return std::nullopt;
  return stat;
}

}  // namespace

ProcessLease this_process_lease() {
  const auto pid = static_cast<std::int64_t>(getpid());
  const auto stat = read_stat(pid);
  return {this_host_name(), pid, stat ? stat->start_ticks : 0};
}

bool lease_is_alive(const ProcessLease& lease) {
  if (lease.host != this_host_name()) return true;
  const auto stat = read_stat(lease.pid);
  return stat && stat->state != 'Z' && stat->state != 'X' && stat->start_ticks == lease.start_ticks;
}

}  // namespace pdamp
