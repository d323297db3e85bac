#pragma once
/// The run store: one SQLite file holding many runs. The tables and views below are
/// pdamp's public SQL interface (documented in docs/store.md); the schema is versioned with
/// PRAGMA user_version and migrated forward on open.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "pdamp/analysis/recorder.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/model/particles.hpp"
#include "pdamp/model/restitution.hpp"
#include "pdamp/store/process_lease.hpp"
#include "pdamp/store/sqlite.hpp"

namespace pdamp {

struct ShardMerge;
struct StudyRecord;

enum class RunStatus { running, completed, failed, interrupted };
std::string_view to_string(RunStatus status);

/// A run as it begins, before its bed is settled or its engine built.
struct NewRun {
  std::string model;  ///< "soft" or "hard"
  std::string scenario_name;
  std::string scenario_text;  ///< the canonical scenario: every key, resolved
  std::uint64_t seed = 0;
  int n_particles = 0;
  double duration_s = 0.0;
};

/// What a run started from, once its bed and engine are ready.
struct RunStart {
  std::optional<double> dt_s;                    ///< time step of a time-stepped engine
  std::optional<std::int64_t> initial_state_id;  ///< the settled bed the run started from
  double solid_fraction = 0.0;                   ///< the spheres' volume over the hole's
  std::optional<HostState> bed_shift{};          ///< that bed moved rigidly by this first (z, vz)
};

/// One sample of a run as the store keeps it.
struct SampleRecord {
  Observation observation;
  double energy_balance_rel_err = 0.0;
  bool operator==(const SampleRecord&) const = default;
};

/// A settled bed kept for other runs (and the other engine) to start from.
struct StoredInitialState {
  std::int64_t state_id = 0;
  Particles particles;
  double settle_time_s = 0.0;
};

/// A bed saved under its settle key: its id, and whether this save stored it (false: another
/// process had stored the same bed first, and it stays).
struct SavedInitialState {
  std::int64_t state_id = 0;
  bool stored = false;
};

struct RunEnd {
  RunStatus status = RunStatus::completed;
  std::string message;
  double sim_time_s = 0.0;
  double wall_time_s = 0.0;
  double initial_energy_J = 0.0;
  double energy_balance_rel_err = 0.0;  ///< the largest over the run
};

/// One row of the `run_summary` view. `status` is the stored one, except that a `running`
/// run whose process is gone (its lease, on this host) is `dead`.
struct RunSummary {
  std::int64_t run_id = 0;
  std::string model, scenario_name, status, message, started_at;
  std::optional<ProcessLease> lease;  ///< of a running run
  int n_particles = 0;
  double duration_s = 0.0, sim_time_s = 0.0;
  std::optional<double> wall_time_s, energy_balance_rel_err;
  std::int64_t n_samples = 0, n_cycles = 0;
  std::optional<double> dissipated_impact_J, dissipated_friction_J, dissipated_viscous_J;
};

/// A run's cycles at a glance: the first and last frequency and the ψ peak.
struct CycleOverview {
  double first_freq_hz = 0.0, last_freq_hz = 0.0;
  double psi_peak = 0.0;
  std::optional<double> psi_peak_gamma;
  std::int64_t psi_peak_cycle = 0;
};

/// Where a run's snapshots are (pdamp run --snapshots).
struct SnapshotRecord {
  std::string folder, collection;  ///< absolute paths
  double interval_s = 0.0;
  std::int64_t frames = 0;
};

/// A run `pdamp delete` removed: its summary and how many comparisons went with it.
struct DeletedRun {
  RunSummary run;
  std::int64_t comparisons = 0;
};

/// One row of `comparisons` with its ψ bins and energies at fixed times.
struct ComparisonRecord {
  std::string scenario_name;
  std::int64_t soft_run_id = 0, hard_run_id = 0;
  std::optional<std::int64_t> initial_state_id;
  std::string hard_restitution;
  std::optional<double> envelope_max_rel_diff, envelope_rms_rel_diff;
  std::optional<double> small_amplitude_freq_soft_hz, small_amplitude_freq_hard_hz;
  std::optional<double> gamma_below_1_soft_s, gamma_below_1_hard_s;
  std::optional<double> psi_mean_abs_diff;
  double dissipated_soft_J = 0.0, dissipated_hard_J = 0.0;
  std::optional<double> dissipated_rel_diff;
  double wall_time_soft_s = 0.0, wall_time_hard_s = 0.0;
  std::optional<double> wall_time_ratio;
  std::int64_t soft_steps = 0, hard_events = 0;

  struct PsiBin {
    double gamma_low, gamma_high;
    std::optional<double> psi_soft, psi_hard;
    int cycles_soft, cycles_hard;
  };
  std::vector<PsiBin> psi_bins;
  struct Energy {
    double t_s;
    std::string model;
    double impact_J, friction_J, viscous_J;
  };
  std::vector<Energy> energy;
};

/// A `pdamp compare` under way (comparison_runs), until its comparison is stored: its
/// runs, and what both run.
struct ComparisonRuns {
  std::int64_t soft_run_id = 0;
  std::optional<std::int64_t> hard_run_id;       ///< empty until the hard run begins
  std::string scenario_name, scenario_text;      ///< the soft run's
  std::optional<std::int64_t> initial_state_id;  ///< the bed both start from, once settled
};

/// What the store holds of one run's results, in time order: the input of the comparison
/// (compare/comparison.hpp). A sample's ledger is read back with host_counts true (the
/// store keeps the energies, not whether the host's count in E).
struct RunResults {
  std::int64_t run_id = 0;
  std::vector<SampleRecord> samples;  ///< by t_s
  std::vector<CycleRecord> cycles;    ///< by cycle
  double wall_time_s = 0.0;           ///< 0 for a run that never ended
};

/// A run's latest checkpoint as the store keeps it (run_checkpoints).
struct StoredCheckpoint {
  RunCheckpoint checkpoint;
  std::string pdamp_version;
  int schema_version = 0;
};

/// What resuming a run starts from: the run as stored and its latest checkpoint.
struct ResumableRun {
  std::int64_t run_id = 0;
  std::string model, scenario_text;
  RunStatus status = RunStatus::interrupted;  ///< `running` for a dead run
  std::optional<ProcessLease> lease;          ///< a dead run's
  double duration_s = 0.0;                    ///< the run's end
  std::optional<std::int64_t> initial_state_id;
  std::optional<HostState> bed_shift{};  ///< RunStart's
  RunCheckpoint checkpoint;
};

/// `read` (the reading commands): the file must be a pdamp store, and is not written
/// (only migrated if its schema is older). `modify`: the file must be a pdamp store.
/// `write`: the file may also be missing or empty, and becomes a store.
enum class StoreAccess { read, modify, write };

struct StoreOptions {
  /// How long a read or write waits for other connections' locks before failing.
  std::chrono::milliseconds busy_limit = sqlite::default_busy_limit;
  /// Stores up to this size are checked whole on open (PRAGMA quick_check reads every
  /// page: ~0.2 s of CPU for 64 MiB, 2.3 s for 1 GB); larger ones have their run tables
  /// checked, not the samples, cycles and beds, whose damage is reported where read.
  std::uintmax_t full_check_limit_bytes = std::uintmax_t{64} << 20;
  /// Only this connection ever uses the file (a study task's shard store, possibly on a
  /// cluster file system): it is locked once for good (locking_mode EXCLUSIVE) and its WAL
  /// index kept in memory, so SQLite needs neither a -shm file nor further locks, which
  /// NFS and Lustre do not reliably provide.
  bool single_process = false;
};

/// One connection to a store: one per thread (studies run many points in parallel, from
/// threads and processes, into one file). Every write is a short transaction, retried
/// while others hold the lock (StoreOptions::busy_limit).
/// save_initial_state's rows written inside the caller's write transaction on `db`, so
/// that a bed can be stored together with what refers to it.
SavedInitialState insert_initial_state(sqlite::Database& db, const std::string& settle_key, const Particles& particles,
                                       double settle_time_s, double kinetic_J, double wall_time_s);

class RunStore {
 public:
  /// Opens or creates the store and migrates it to the current schema. The file is
  /// examined before anything is written to it. Throws InputError for a file that is not
  /// a pdamp store, is damaged or was written by a newer pdamp.
  explicit RunStore(const std::filesystem::path& file, StoreAccess access = StoreAccess::write,
                    const StoreOptions& options = {});

  static int schema_version();

  /// The run's row, `running`, created before any work so that whatever ends it is stored.
  std::int64_t begin_run(const NewRun& run);
  void start_run(std::int64_t run_id, const RunStart& start);
  /// Appends samples and cycles of a run in one transaction, with the run's checkpoint if
  /// given (replacing its last: a run keeps only its latest).
  void append_results(std::int64_t run_id, std::span<const SampleRecord> samples, std::span<const CycleRecord> cycles,
                      const RunCheckpoint* checkpoint = nullptr);
  void finish_run(std::int64_t run_id, const RunEnd& end);
  /// The restitution table a hard run used.
  void save_calibration(std::int64_t run_id, const RestitutionTable& table);

  /// Stores an engine's named totals (replacing earlier values of the same names).
  void save_statistics(std::int64_t run_id, const EngineStatistics& statistics);
  EngineStatistics statistics(std::int64_t run_id);

  /// The bed stored under `settle_key`, if any.
  std::optional<StoredInitialState> find_initial_state(const std::string& settle_key);
  /// Stores a bed under `settle_key` (or keeps the one another process stored under it
  /// meanwhile) in a transaction of its own.
  SavedInitialState save_initial_state(const std::string& settle_key, const Particles& particles, double settle_time_s,
                                       double kinetic_J, double wall_time_s);
  Particles load_initial_particles(std::int64_t state_id);

  /// Stores a comparison, and ends its runs' comparison_runs row in the same transaction.
  std::int64_t save_comparison(const ComparisonRecord& comparison);
  /// Records the runs of a comparison under way: the soft run as it begins, then its hard run.
  void save_comparison_runs(std::int64_t soft_run_id, std::optional<std::int64_t> hard_run_id = {});
  /// The comparison under way that `run_id` is a run of, if any.
  std::optional<ComparisonRuns> comparison_runs(std::int64_t run_id);
  /// A run's samples and cycles; throws InputError for a run not in the store.
  RunResults results(std::int64_t run_id);

  /// A run's latest checkpoint; empty for a run without one.
  std::optional<StoredCheckpoint> checkpoint(std::int64_t run_id);
  /// The run to resume from its checkpoint, to `until_s` if given. Throws InputError
  /// naming why it cannot be: not in the store, live in a process (its lease), failed,
  /// completed without `until_s`, `until_s` not beyond its end, no checkpoint, a
  /// checkpoint of another pdamp version or store schema (run_checkpoints.cpp).
  ResumableRun resumable_run(std::int64_t run_id, std::optional<double> until_s);
  /// Takes the run over for this process (its lease) as `running` again, to end at
  /// `duration_s` with `scenario_text`, and drops the samples and cycles recorded after its
  /// checkpoint: all in one transaction. Throws InputError if another process took it
  /// over since resumable_run read it.
  void claim_for_resume(const ResumableRun& run, double duration_s, const std::string& scenario_text);

  /// Records (or updates) where a run's snapshots are.
  void save_snapshots(std::int64_t run_id, const SnapshotRecord& snapshots);
  /// Empty for a run without snapshots.
  std::optional<SnapshotRecord> snapshots(std::int64_t run_id);

  std::vector<RunSummary> list_runs();
  std::optional<RunSummary> summary(std::int64_t run_id);
  /// Empty for a run without cycles.
  std::optional<CycleOverview> cycle_overview(std::int64_t run_id);

  /// Deletes runs and every row that refers to them (samples, cycles, statistics,
  /// calibrations, comparisons, where their snapshots are, their links to study points: a
  /// completed point that loses a run is pending again), all or none: throws InputError,
  /// deleting nothing, for an
  /// id not in the store, or for a `running` run unless `including_running`. Returns the
  /// deleted runs. Settled beds stay (other runs may start from them), and so do snapshot files.
  std::vector<DeletedRun> delete_runs(std::span<const std::int64_t> run_ids, bool including_running);

  const std::filesystem::path& file() const;

  /// Makes the file whole by itself (journal_mode DELETE: no -wal or -shm beside it), for
  /// a store that is copied or moved once written: a Slurm shard, a study's template.
  void make_self_contained();

 private:
  // The store layer's other parts share the connection; no other layer writes SQL.
  friend class StudyStore;
  friend ShardMerge merge_shard(RunStore& store, const StudyRecord& study, const std::filesystem::path& file);
  friend void copy_end_states(RunStore& store, std::int64_t study_id, const std::vector<int>& points, RunStore& target);
  sqlite::Database& database() { return *db_; }
  void migrate();
  /// Within a transaction writing a run's rows: throws RuntimeFailure if the run is no
  /// longer in the store (another process's `pdamp delete --force` took it while it ran),
  /// where its rows would fail on their foreign key, or its end be stored nowhere.
  void require_run(std::int64_t run_id);
  /// Replaces the run's checkpoint (within a transaction).
  void replace_checkpoint(std::int64_t run_id, const RunCheckpoint& checkpoint);
  std::unique_ptr<sqlite::Database> db_;
};

/// Keeps one run's samples and cycles in memory and writes them in short transactions,
/// each at least `commit_interval` of wall time after the last (or when many rows wait),
/// so that no lock is held while the engine computes and a killed run keeps all but its
/// last moments.
class RunWriter final : public RunRecorder {
 public:
  RunWriter(RunStore& store, std::int64_t run_id,
            std::chrono::milliseconds commit_interval = std::chrono::milliseconds(250));
  ~RunWriter() override;

  void record_sample(const Observation& sample, double energy_balance_rel_err) override;
  void record_cycle(const CycleRecord& cycle) override;
  void flush() override;
  void flush_with_checkpoint(const RunCheckpoint& checkpoint) override;

 private:
  void flush_if_due();
  void write(const RunCheckpoint* checkpoint);

  RunStore* store_;
  std::int64_t run_id_;
  std::chrono::milliseconds commit_interval_;
  std::chrono::steady_clock::time_point last_flush_;
  std::vector<SampleRecord> samples_;
  std::vector<CycleRecord> cycles_;
};

}  // namespace pdamp
