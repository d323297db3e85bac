#pragma once
/// The CLI's commands, each returning the process exit code.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "pdamp/model/scenario_loader.hpp"
#include "pdamp/sim/snapshots.hpp"
#include "pdamp/store/run_store.hpp"

namespace pdamp {

struct ScenarioRequest {
  std::filesystem::path file;
  ScenarioOverrides overrides;
};

/// `terminal`: whether stderr is one (progress redrawn in place) or a log (a line now and then);
/// `checkpoint_interval`: wall time between checkpoints (0: none, RunControl);
/// `diagnose_events`: the hard model counts where its collisions come from (RunPlan).
int run_command(const ScenarioRequest& request, const std::string& model, const std::filesystem::path& db,
                const std::optional<SnapshotSettings>& snapshots, bool terminal,
                std::chrono::milliseconds checkpoint_interval, bool diagnose_events = false);
/// Continues a run from its checkpoint, to its end or to `until_s` (pdamp resume).
int resume_command(const std::string& run_id, std::optional<double> until_s, const std::filesystem::path& db,
                   bool terminal, std::chrono::milliseconds checkpoint_interval);
int list_runs_command(const std::filesystem::path& db);
int show_run_command(const std::string& run_id, const std::filesystem::path& db);
/// `force`: also runs still marked running.
int delete_runs_command(const std::vector<std::string>& run_ids, const std::filesystem::path& db, bool force);
int check_command(const ScenarioRequest& request);
int compare_command(const ScenarioRequest& request, const std::filesystem::path& db,
                    const std::optional<SnapshotSettings>& snapshots, bool terminal,
                    std::chrono::milliseconds checkpoint_interval);
/// Completes a comparison under way that was stopped or killed (pdamp resume of one of its
/// runs): each run not completed resumed from its checkpoint, or the hard run started
/// from the soft run's bed if it had not begun, then the comparison stored as pdamp
/// compare stores it. Throws InputError, changing nothing, if a run cannot be resumed.
int complete_comparison(RunStore& store, const ComparisonRuns& runs, bool terminal,
                        std::chrono::milliseconds checkpoint_interval);
/// Sets the number of threads (--threads); throws InputError unless it is 1 to 1024.
void set_thread_count(const std::string& text);

/// SIGINT and SIGTERM end a run cleanly: it keeps what it computed and is marked
/// interrupted. A second signal does the same (the run loop checks often).
void install_stop_handlers();
/// True once SIGINT or SIGTERM arrived (after install_stop_handlers).
const std::atomic<bool>* stop_flag();
/// The signal that asked a run to stop (0 if none).
int stop_signal_received();

}  // namespace pdamp
