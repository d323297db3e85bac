/// The run store's checkpoints (docs/checkpoints.md): each run's latest, and taking a run
/// over to resume it from there.
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/store/run_store.hpp"
#include "pdamp/version.hpp"

namespace pdamp {
namespace {

std::string run_named(std::int64_t run_id) { return "run " + std::to_string(run_id); }

std::string seconds(double t_s) {
  std::ostringstream text;
  text << t_s << " s";
  return text.str();
}

RunStatus parse_run_status(const std::string& text) {
  for (const RunStatus status : {RunStatus::running, RunStatus::completed, RunStatus::failed, RunStatus::interrupted}) {
    if (to_string(status) == text) return status;
  }
  throw RuntimeFailure("a run's status '" + text + "' is not one pdamp writes");
}

/// Throws InputError if the run cannot go on to `until_s` from what it is.
void require_resumable(const ResumableRun& run, const std::optional<RunSummary>& summary,
                       std::optional<double> until_s) {
  const std::string name = run_named(run.run_id);
  if (summary && summary->status == "running") {
    throw InputError(name + " is live" +
                     (run.lease ? " in process " + std::to_string(run.lease->pid) + " on " + run.lease->host
                                : std::string(" (its process is not recorded)")) +
                     ": it is still running there (stop it with SIGINT or SIGTERM, then resume it)");
  }
  if (run.status == RunStatus::failed) {
    throw InputError(name + " failed (" + summary->message +
                     "): resuming it from its checkpoint would fail again; start a new run");
  }
  if (run.status == RunStatus::completed && !until_s) {
    throw InputError(name + " is completed (it ran to " + seconds(run.duration_s) +
                     "); give --until T, beyond its end, to extend it");
  }
  if (until_s && !(*until_s > run.duration_s)) {
    throw InputError("--until " + seconds(*until_s) + " must be beyond the end of " + name + " (" +
                     seconds(run.duration_s) + ")");
  }
}

}  // namespace

void RunStore::replace_checkpoint(std::int64_t run_id, const RunCheckpoint& checkpoint) {
  sqlite::Statement replace(*db_,
                            "INSERT OR REPLACE INTO run_checkpoints (run_id, t_s, samples, cycles, pdamp_version, "
                            "schema_version, written_at, state) VALUES (?, ?, ?, ?, ?, ?, "
                            "strftime('%Y-%m-%dT%H:%M:%fZ', 'now'), ?)");
  replace.bind(1, run_id)
      .bind(2, checkpoint.t_s)
      .bind(3, checkpoint.samples)
      .bind(4, checkpoint.cycles)
      .bind(5, std::string_view(version_string))
      .bind(6, schema_version())
      .bind(7, std::span<const std::byte>(checkpoint.state));
  replace.run();
  // What `pdamp runs` shows of a run killed after it.
  sqlite::Statement reached(*db_, "UPDATE runs SET sim_time_s = ? WHERE run_id = ?");
  reached.bind(1, checkpoint.t_s).bind(2, run_id).run();
}

std::optional<StoredCheckpoint> RunStore::checkpoint(std::int64_t run_id) {
  sqlite::Statement query(*db_,
                          "SELECT t_s, samples, cycles, state, pdamp_version, schema_version FROM run_checkpoints "
                          "WHERE run_id = ?");
  query.bind(1, run_id);
  if (!query.step()) return std::nullopt;
  return StoredCheckpoint{{query.column_double(0), query.column_int(1), query.column_int(2), query.column_blob(3)},
                          query.column_text(4),
                          static_cast<int>(query.column_int(5))};
}

ResumableRun RunStore::resumable_run(std::int64_t run_id, std::optional<double> until_s) {
  const std::string name = run_named(run_id);
  sqlite::Statement query(*db_,
                          "SELECT model, scenario_text, status, duration_s, initial_state_id, lease_host, lease_pid, "
                          "lease_start, bed_shift_z_m, bed_shift_v_m_s FROM runs WHERE run_id = ?");
  query.bind(1, run_id);
  if (!query.step()) throw InputError(name + " is not in '" + file().string() + "' (see pdamp runs)");
  ResumableRun run;
  run.run_id = run_id;
  run.model = query.column_text(0);
  run.scenario_text = query.column_text(1);
  run.status = parse_run_status(query.column_text(2));
  run.duration_s = query.column_double(3);
  if (!query.is_null(4)) run.initial_state_id = query.column_int(4);
  if (!query.is_null(5)) run.lease = ProcessLease{query.column_text(5), query.column_int(6), query.column_int(7)};
  if (!query.is_null(8)) run.bed_shift = HostState{query.column_double(8), query.column_double(9)};
  require_resumable(run, summary(run_id), until_s);
  auto stored = checkpoint(run_id);
  if (!stored) {
    throw InputError(name + " has no checkpoint (it stopped before its first, ran with --checkpoint-every 0, or " +
                     "is a completed point of a study's curve, which keeps its end state instead): it cannot be " +
                     "resumed; start a new run");
  }
  if (stored->pdamp_version != version_string || stored->schema_version != schema_version()) {
    throw InputError(name + "'s checkpoint was written by pdamp " + stored->pdamp_version + " (store schema " +
                     std::to_string(stored->schema_version) + "); this is pdamp " + version_string + " (schema " +
                     std::to_string(schema_version()) + "), which restores only its own: resume it with pdamp " +
                     stored->pdamp_version);
  }
  run.checkpoint = std::move(stored->checkpoint);
  return run;
}

void RunStore::claim_for_resume(const ResumableRun& run, double duration_s, const std::string& scenario_text) {
  sqlite::write_transaction(*db_, [&] {
    const ProcessLease me = this_process_lease();
    sqlite::Statement claim(*db_,
                            "UPDATE runs SET status = 'running', message = '', ended_at = NULL, duration_s = ?, "
                            "scenario_text = ?, sim_time_s = ?, lease_host = ?, lease_pid = ?, lease_start = ? "
                            "WHERE run_id = ? AND status = ? AND lease_host IS ? AND lease_pid IS ? AND "
                            "lease_start IS ?");
    claim.bind(1, duration_s).bind(2, scenario_text).bind(3, run.checkpoint.t_s);
    claim.bind(4, me.host).bind(5, me.pid).bind(6, me.start_ticks).bind(7, run.run_id).bind(8, to_string(run.status));
    const auto lease = run.lease.value_or(ProcessLease{});
    if (run.lease) {
      claim.bind(9, lease.host).bind(10, lease.pid).bind(11, lease.start_ticks);
    } else {
      claim.bind_null(9).bind_null(10).bind_null(11);
    }
    claim.run();
    if (db_->changes() != 1) {
      throw InputError(run_named(run.run_id) + " was taken over by another process meanwhile; see pdamp show " +
                       std::to_string(run.run_id));
    }
    sqlite::Statement drop_samples(*db_, "DELETE FROM samples WHERE run_id = ? AND t_s > ?");
    drop_samples.bind(1, run.run_id).bind(2, run.checkpoint.t_s).run();
    sqlite::Statement drop_cycles(*db_, "DELETE FROM cycles WHERE run_id = ? AND cycle > ?");
    drop_cycles.bind(1, run.run_id).bind(2, run.checkpoint.cycles).run();
    sqlite::Statement count(*db_,
                            "SELECT (SELECT count(*) FROM samples WHERE run_id = ?1), "
                            "(SELECT count(*) FROM cycles WHERE run_id = ?1)");
    count.bind(1, run.run_id);
    count.step();
    if (count.column_int(0) != run.checkpoint.samples || count.column_int(1) != run.checkpoint.cycles) {
      throw RuntimeFailure(run_named(run.run_id) + " holds " + std::to_string(count.column_int(0)) + " samples and " +
                           std::to_string(count.column_int(1)) + " cycles up to its checkpoint, which recorded " +
                           std::to_string(run.checkpoint.samples) + " and " + std::to_string(run.checkpoint.cycles) +
                           ": the store and the checkpoint disagree, nothing was changed");
    }
  });
}

}  // namespace pdamp
