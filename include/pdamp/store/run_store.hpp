#pragma once
/// The run store: one SQLite file holding many runs. The tables and views below are
/// pdamp's public SQL interface (documented in docs/store.md); the schema is versioned with
/// PRAGMA user_version and migrated forward on open.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "pdamp/analysis/recorder.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/model/particles.hpp"
#include "pdamp/model/restitution.hpp"
#include "pdamp/store/sqlite.hpp"

namespace pdamp {

enum class RunStatus { running, completed, failed, interrupted };
std::string_view to_string(RunStatus status);

struct NewRun {
  std::string model;  ///< "soft" or "hard"
  std::string scenario_name;
  std::string scenario_text;  ///< the canonical scenario: every key, resolved
  std::uint64_t seed = 0;
  int n_particles = 0;
  double duration_s = 0.0;
  std::optional<double> dt_s;                    ///< time step of a time-stepped engine
  std::optional<std::int64_t> initial_state_id;  ///< the settled bed the run started from
  double solid_fraction = 0.0;                   ///< the spheres' volume over the hole's
};

/// A settled bed kept for other runs (and the other engine) to start from.
struct StoredInitialState {
  std::int64_t state_id = 0;
  Particles particles;
  double settle_time_s = 0.0;
};

struct RunEnd {
  RunStatus status = RunStatus::completed;
  std::string message;
  double sim_time_s = 0.0;
  double wall_time_s = 0.0;
  double initial_energy_J = 0.0;
  double energy_balance_rel_err = 0.0;  ///< the largest over the run
};

/// One row of the `run_summary` view.
struct RunSummary {
  std::int64_t run_id = 0;
  std::string model, scenario_name, status, message, started_at;
  int n_particles = 0;
  double duration_s = 0.0, sim_time_s = 0.0;
  std::optional<double> wall_time_s, energy_balance_rel_err;
  std::int64_t n_samples = 0, n_cycles = 0;
  std::optional<double> dissipated_impact_J, dissipated_friction_J, dissipated_viscous_J;
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

class RunStore {
 public:
  /// Opens or creates the store and migrates it to the current schema. Throws
  /// InputError for a file that is not a pdamp store or was written by a newer pdamp.
  explicit RunStore(const std::filesystem::path& file);

  static int schema_version();

  std::int64_t begin_run(const NewRun& run);
  void finish_run(std::int64_t run_id, const RunEnd& end);
  /// The restitution table a hard run used.
  void save_calibration(std::int64_t run_id, const RestitutionTable& table);

  /// Stores an engine's named totals (replacing earlier values of the same names).
  void save_statistics(std::int64_t run_id, const EngineStatistics& statistics);
  EngineStatistics statistics(std::int64_t run_id);

  /// The bed stored under `settle_key`, if any.
  std::optional<StoredInitialState> find_initial_state(const std::string& settle_key);
  std::int64_t save_initial_state(const std::string& settle_key, const Particles& particles, double settle_time_s,
                                  double kinetic_J, double wall_time_s);
  Particles load_initial_particles(std::int64_t state_id);

  std::int64_t save_comparison(const ComparisonRecord& comparison);

  std::vector<RunSummary> list_runs();
  std::optional<RunSummary> summary(std::int64_t run_id);

  sqlite::Database& database() { return db_; }

 private:
  void migrate();
  sqlite::Database db_;
};

/// Streams one run's samples and cycles into the store in batched transactions,
/// committed at least every `commit_interval` of wall time, so a killed run keeps all
/// but the last moments.
class RunWriter final : public RunRecorder {
 public:
  RunWriter(RunStore& store, std::int64_t run_id,
            std::chrono::milliseconds commit_interval = std::chrono::milliseconds(250));
  ~RunWriter() override;

  void record_sample(const Observation& sample, double energy_balance_rel_err) override;
  void record_cycle(const CycleRecord& cycle) override;
  void flush() override;

 private:
  void begin_batch();
  void commit_if_due();

  RunStore* store_;
  std::int64_t run_id_;
  std::chrono::milliseconds commit_interval_;
  std::chrono::steady_clock::time_point batch_started_;
  bool in_batch_ = false;
  sqlite::Statement insert_sample_;
  sqlite::Statement insert_cycle_;
};

}  // namespace pdamp
