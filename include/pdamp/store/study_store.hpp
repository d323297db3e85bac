#pragma once
/// Studies in the run store (tables `studies`, `study_points`, `study_point_values`,
/// `study_point_runs`, `study_point_metrics`, and for studies on Slurm `study_jobs` and
/// `study_tasks`). A point is claimed by the
/// process that runs it (its lease), linked to the runs it makes, and completed with its
/// metrics in one transaction, so a point is either completed with all its metrics or it
/// is run again.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pdamp/analysis/damper_characterisation.hpp"
#include "pdamp/analysis/frf_response.hpp"
#include "pdamp/store/process_lease.hpp"
#include "pdamp/store/run_store.hpp"

namespace pdamp {

enum class PointStatus { pending, running, completed, failed, interrupted };
std::string_view to_string(PointStatus status);
PointStatus parse_point_status(std::string_view text);

struct NewStudy {
  std::string name, models, study_file, study_text, scenario_file, scenario_text;
};

/// A frequency-response point's place on its curve (a row of `study_frf_points`).
struct FrfPointRow {
  int curve = 0;
  std::string model, direction;  ///< "soft" or "hard"; "up" or "down"
  bool host_alone = false;
  std::string mode;  ///< "force" or "base"
  double level = 0.0, frequency_hz = 0.0;
  int step = 0;
  int previous_point = 0;  ///< 0: from the settled bed
  std::string grid;        ///< its curve's values of the section's grid keys, "key = value, ..."; "": no grid
};

/// A characterisation point's place on its curve (a row of `study_characterise_points`).
struct CharacterisePointRow {
  int curve = 0;
  std::string model;  ///< "soft" or "hard"
  bool empty = false;
  double amplitude_m = 0.0;
  std::optional<double> gamma_given;
  double frequency_hz = 0.0;
  int step = 0;
  int previous_point = 0;  ///< 0: from the settled bed
};

struct NewStudyPoint {
  int point = 0;
  std::string section;
  std::vector<std::pair<std::string, std::string>> values;  ///< (scenario key, value text)
  std::optional<FrfPointRow> frf;
  std::optional<CharacterisePointRow> characterise;
};

/// Where a frequency-response point ended: the next point of its curve starts there.
struct FrfEndState {
  std::int64_t run_id = 0;
  std::int64_t state_id = 0;  ///< its spheres, in initial_states
  double t_s = 0.0;
  HostState host;
};

/// What a completed frequency-response point stores (`study_frf_metrics`, `study_point_states`).
struct FrfPointResult {
  std::int64_t run_id = 0;
  ResponseMetrics metrics;
  int cycles_run = 0;
  double particle_mass_kg = 0.0, wall_time_s = 0.0;
  FrfEndState end;
};

/// What a completed characterisation point stores (`study_characterise_metrics`,
/// `study_point_states`).
struct CharacterisePointResult {
  std::int64_t run_id = 0;
  CharacterisationMetrics metrics;
  int cycles_run = 0;
  double particle_mass_kg = 0.0, gravity_m_s2 = 0.0, free_height_m = 0.0, wall_time_s = 0.0;
  FrfEndState end;
};

/// A row of the `study_characterisation` view: a point and, once completed, its metrics.
struct CharacterisePointRecord {
  int point = 0;
  std::string status;
  CharacterisePointRow place;
  std::optional<CharacterisePointResult> result;
};

/// A row of the `study_frf` view: a point of a curve and, once completed, its metrics.
struct FrfPointRecord {
  int point = 0;
  std::string status;
  FrfPointRow place;
  std::optional<FrfPointResult> result;
};

/// The study point a run was run for, where that point runs cycle by cycle (an [frf] or a
/// [characterise] point's run, which only its point can continue).
struct CurvePointRun {
  std::int64_t study_id = 0;
  int point = 0;
  std::string section;  ///< "frf" or "characterise"
};

struct StudyRecord {
  std::int64_t study_id = 0;
  std::string name, models, study_file, study_text, scenario_file, scenario_text, pdamp_version, created_at;
  int n_points = 0;
};

/// One row of the `study_summary` view.
struct StudySummary {
  std::int64_t study_id = 0;
  std::string name, models, created_at;
  int n_points = 0, completed = 0, failed = 0, interrupted = 0, running = 0, pending = 0;
};

struct StudyPointState {
  int point = 0;
  std::string section;
  PointStatus status = PointStatus::pending;
  int attempt = 0;
  std::string message;
  std::optional<ProcessLease> lease;  ///< while running
};

/// A completed point's metrics for one model (a row of `study_point_metrics`), with the
/// agreement of the two models where the study runs both.
struct PointMetrics {
  int point = 0;
  std::string model;
  std::int64_t run_id = 0;
  double dissipated_impact_J = 0.0, dissipated_friction_J = 0.0, dissipated_viscous_J = 0.0;
  std::optional<double> psi_peak, psi_peak_gamma, final_amplitude_m;
  std::int64_t cycles = 0;
  double energy_balance_rel_err = 0.0, wall_time_s = 0.0;
  std::optional<double> dissipated_rel_diff, envelope_max_rel_diff;  ///< models = both
};

/// A job array a study was submitted as (pdamp study submit).
struct StudyJob {
  std::int64_t job_id = 0;
  std::string submitted_at, script_file, shard_folder;
};

/// A task of a study's job array: the point it runs and, once its shard store is collected
/// (or, in the shard itself, once it has ended), how it went. Texts are empty until known.
struct StudyTask {
  std::int64_t job_id = 0, task = 0;
  int point = 0;
  std::string host, started_at, ended_at, message, shard_file, collected_at;
  std::optional<PointStatus> outcome;
  bool collected() const { return !collected_at.empty(); }
  /// A task known by its job, index and point alone.
  static StudyTask of(std::int64_t job_id, std::int64_t task, int point) {
    StudyTask t;
    t.job_id = job_id;
    t.task = task;
    t.point = point;
    return t;
  }
};

class StudyStore {
 public:
  explicit StudyStore(RunStore& store) : db_(&store.database()) {}
  /// The studies of any connection to a store (a shard store read as it is).
  explicit StudyStore(sqlite::Database& db) : db_(&db) {}

  /// Stores a study and its points (pending), all or nothing; returns its id.
  std::int64_t create_study(const NewStudy& study, const std::vector<NewStudyPoint>& points);
  /// Stores a study as another store holds it (its id, version and creation time), without
  /// its points: the template each task of a job array copies into its shard store.
  void copy_study(const StudyRecord& study);
  /// Adds points (pending) to a stored study: a shard's own points.
  void add_points(std::int64_t study_id, const std::vector<NewStudyPoint>& points);
  std::optional<StudyRecord> find_study(std::string_view name);
  std::optional<StudyRecord> study(std::int64_t study_id);
  /// Every stored study, by id (a shard store holds one).
  std::vector<StudyRecord> studies();
  /// The id create_study would give the next study (ids are never reused).
  std::int64_t next_study_id();
  std::vector<StudySummary> list_studies();
  std::optional<StudySummary> summary(std::int64_t study_id);
  std::vector<StudyPointState> points(std::int64_t study_id);
  std::optional<StudyPointState> point(std::int64_t study_id, int point);
  std::vector<PointMetrics> metrics(std::int64_t study_id);
  /// Each frequency-response point with its place and, if completed, its metrics.
  std::vector<FrfPointRecord> frf_points(std::int64_t study_id);
  /// A completed frequency-response point's metrics (its final state: end_state), which a
  /// predicted point starts from; nothing for another point.
  std::optional<FrfPointResult> frf_metrics(std::int64_t study_id, int point);
  /// Each characterisation point with its place and, if completed, its metrics.
  std::vector<CharacterisePointRecord> characterise_points(std::int64_t study_id);
  /// The point each frequency-response or characterisation point starts from, for those
  /// continuing another.
  std::map<int, int> previous_points(std::int64_t study_id);
  /// The points a curve's task starting at `first` runs, in order: `first`, then each
  /// point continuing from the one before, to the curve's end (`first` alone for a point
  /// no other continues from: a sweep point, or one from the bed).
  std::vector<int> curve_from(std::int64_t study_id, int first);
  /// The final state of a completed frequency-response or characterisation point.
  std::optional<FrfEndState> end_state(std::int64_t study_id, int point);

  /// Marks a pending, failed or interrupted point running under `lease` and starts its
  /// next attempt; returns the attempt, or nothing if the point is completed or running.
  std::optional<int> claim_point(std::int64_t study_id, int point, const ProcessLease& lease);
  void link_run(std::int64_t study_id, int point, int attempt, std::string_view model, std::int64_t run_id);
  /// The [frf] or [characterise] point `run_id` was run for; nothing for another run.
  std::optional<CurvePointRun> curve_point_of_run(std::int64_t run_id);
  /// The point's run of `model` linked to its latest attempt before `attempt`, if any.
  std::optional<std::int64_t> earlier_run(std::int64_t study_id, int point, int attempt, std::string_view model);
  /// Links a run of an earlier attempt of the point to `attempt` instead (it continues there).
  void move_run(std::int64_t study_id, int point, int attempt, std::int64_t run_id);
  /// Completes the point's attempt: each run's metrics, computed from its stored samples
  /// and cycles, and the comparison of the two models if there is one.
  void complete_point(std::int64_t study_id, int point, int attempt, const std::vector<std::int64_t>& run_ids,
                      std::optional<std::int64_t> comparison_id);
  /// Completes a frequency-response point's attempt with its metrics and final state: its
  /// spheres (`end_spheres`, of kinetic energy `kinetic_J`) stored as a bed in the same
  /// transaction, so that a process killed on the way leaves neither; the run's checkpoint,
  /// whose state the bed now holds, is deleted with it (`pdamp resume --until` does not extend
  /// a curve's point). `result.end.state_id` is ignored. Returns the bed's state_id.
  std::int64_t complete_frf_point(std::int64_t study_id, int point, int attempt, const FrfPointResult& result,
                                  const Particles& end_spheres, double kinetic_J);
  /// Completes a characterisation point's attempt with its metrics and final state, as
  /// complete_frf_point.
  std::int64_t complete_characterise_point(std::int64_t study_id, int point, int attempt,
                                           const CharacterisePointResult& result, const Particles& end_spheres,
                                           double kinetic_J);
  /// Ends the point's attempt as failed or interrupted with a message.
  void end_point(std::int64_t study_id, int point, int attempt, PointStatus status, const std::string& message);
  /// A point still running under `lease`, whose process is gone (or, on another host, is
  /// taken over on the user's word), ends as `status` (failed or interrupted) with a
  /// message, and so do its attempt's runs that were left running.
  /// False if the point has moved on.
  bool abandon_point(std::int64_t study_id, int point, const ProcessLease& lease, PointStatus status,
                     const std::string& message);

  /// Records a submitted job array and the point each of its tasks runs, all or nothing.
  void record_job(std::int64_t study_id, const StudyJob& job, const std::vector<std::pair<std::int64_t, int>>& tasks);
  std::vector<StudyJob> jobs(std::int64_t study_id);
  /// The study's tasks by job and task.
  std::vector<StudyTask> tasks(std::int64_t study_id);
  /// In a shard store: its task's row as the task starts (job, task, point, host), then
  /// its end with the point's status.
  void begin_task(std::int64_t study_id, const StudyTask& task);
  void end_task(std::int64_t study_id, std::int64_t job_id, std::int64_t task, PointStatus outcome,
                const std::string& message);

 private:
  void insert_points(std::int64_t study_id, const std::vector<NewStudyPoint>& points);
  /// In a transaction: the point's final state (its spheres as a bed under `label`) and its
  /// completion; its run's checkpoint is deleted. Returns the bed's state_id.
  std::int64_t store_end_and_complete(std::int64_t study_id, int point, int attempt, const std::string& label,
                                      const FrfEndState& end, const Particles& end_spheres, double kinetic_J,
                                      double wall_time_s);
  sqlite::Database& db() { return *db_; }
  sqlite::Database* db_;
};

}  // namespace pdamp
