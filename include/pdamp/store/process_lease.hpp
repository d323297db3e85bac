#pragma once
/// Which process runs something (a run, a study's point), and whether it still does: the
/// store keeps a lease with each `running` run and point, so that a process killed by
/// SIGKILL or a crash leaves a run that reads as dead, not as running for ever.

#include <cstdint>
#include <string>

namespace pdamp {

/// The process that runs a run or a point: its host, id and start time (which tells a
/// live process from a later one that reuses the id).
struct ProcessLease {
  std::string host;
  std::int64_t pid = 0;
  std::int64_t start_ticks = 0;
};

/// This process's lease: host name, process id and start time.
ProcessLease this_process_lease();

/// The name of this host, as leases give it.
std::string this_host_name();

/// False if the lease's process is known to be gone: on this host, no process with its
/// id and start time is alive (a zombie counts as gone). A lease of another host cannot
/// be checked from here and counts as alive.
bool lease_is_alive(const ProcessLease& lease);

}  // namespace pdamp
