#pragma once
/// Which process runs a point (study_store.hpp's ProcessLease), and whether it still does.

#include "pdamp/store/study_store.hpp"

namespace pdamp::study {

/// This process's lease: host name, process id and start time.
ProcessLease this_process_lease();

/// False if the lease's process is known to be gone: on this host, no process with its
/// id and start time is alive (a zombie counts as gone). A lease of another host cannot
/// be checked from here and counts as alive.
bool lease_is_alive(const ProcessLease& lease);

}  // namespace pdamp::study
