#pragma once
/// Snapshots of a run for ParaView (docs/snapshots.md): every `interval_s` of simulated
/// time, the spheres and the cavity as VTK PolyData, listed with their times in one
/// collection per run:
///   DIR/run-<id>/spheres_<frame>.vtp, cavity_<frame>.vtp, run-<id>.pvd
/// with frame = 0, 1, ... at t = frame × interval_s.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "pdamp/model/cavity.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/scenario/scenario.hpp"
#include "pdamp/sim/run.hpp"
#include "pdamp/vtk/vtk_xml.hpp"

namespace pdamp {

/// What `--snapshots EVERY_S [--snapshot-dir DIR]` asks for (pdamp run, pdamp compare).
struct SnapshotSettings {
  double interval_s = 0.0;          ///< simulated time between frames (s)
  std::filesystem::path directory;  ///< where each run's folder run-<id> goes
};

/// The most frames one run may write: with ~120 bytes a sphere a frame, Table 1's 1,246
/// spheres take 15 GB at this many.
inline constexpr std::int64_t max_snapshot_frames = 100'000;

/// The settings from the options' texts (`directory` empty: `default_directory`); throws
/// InputError if EVERY_S is not a number. check_snapshot_settings checks its value.
SnapshotSettings parse_snapshot_settings(const std::string& every_s, const std::string& directory,
                                         const std::filesystem::path& default_directory);

/// The default folder of a store's snapshots: beside it, named after it
/// (pdamp.sqlite: pdamp.snapshots).
std::filesystem::path default_snapshot_directory(const std::filesystem::path& store_file);

/// Checks, before anything is written, that a run of `scenario` can take these snapshots:
/// the interval is positive, finite and a whole multiple of the run loop's observation
/// step (so the engines run exactly as without snapshots), the frames are within
/// max_snapshot_frames, and the directory exists as a writable folder or can be created.
/// Throws InputError naming the value, why it is wrong and what is valid.
void check_snapshot_settings(const SnapshotSettings& settings, const Scenario& scenario);

/// check_snapshot_settings for a point run cycle by cycle (cycle_frames), of up to
/// `max_cycles` cycles of `period_s`: the interval positive and finite, the frames within
/// max_snapshot_frames, the directory writable. Throws InputError naming the value.
void check_cycle_snapshot_settings(const SnapshotSettings& settings, double period_s, std::int64_t max_cycles);

/// Where a run's snapshots are.
struct SnapshotFiles {
  std::filesystem::path folder;      ///< DIR/run-<id>, absolute
  std::filesystem::path collection;  ///< the .pvd in it
};
SnapshotFiles snapshot_files(const SnapshotSettings& settings, std::int64_t run_id);

/// Checks, before a run resumed from its checkpoint at observation step `checkpoint_step`
/// is taken over, that it can continue its snapshots (every `interval_s` in `files`): the
/// folder holds every frame up to the checkpoint, and the frames fit its (possibly
/// extended) duration. Throws InputError naming run `run_id`, the file and why.
void check_resumable_snapshots(const SnapshotFiles& files, double interval_s, const Scenario& scenario,
                               std::int64_t run_id, std::int64_t checkpoint_step);

/// The observations a run's frames are taken at: every `steps_per_frame`-th step of `grid`.
struct FrameGrid {
  ObservationGrid grid;
  std::int64_t steps_per_frame = 1;
  double interval_s() const { return grid.time_s(steps_per_frame); }
};

/// The run loop's: every `interval_s` (a whole multiple of its observation step, checked by
/// check_snapshot_settings).
FrameGrid run_loop_frames(double interval_s, const Scenario& scenario);

/// A point run cycle by cycle (sim/frf_point.hpp), observed only at its cycle boundaries,
/// `period_s` apart: where its engine stops anyway, so that snapshots change nothing of
/// its results. A frame every max(1, round(interval_s / period_s)) cycles.
FrameGrid cycle_frames(double interval_s, double period_s);

/// Writes one run's frames at its observations (RunControl::at_observation).
/// Frame k is taken at observation step k × steps per frame, at that step's time.
class SnapshotWriter {
 public:
  /// Creates the run's folder and an empty collection, for frames at `frames` (default:
  /// the run loop's, every settings.interval_s). Throws RuntimeFailure if the folder cannot
  /// be made or already holds files (of a run of another store).
  SnapshotWriter(const SnapshotSettings& settings, const Scenario& scenario, std::int64_t run_id);
  SnapshotWriter(const SnapshotSettings& settings, const Scenario& scenario, std::int64_t run_id,
                 const FrameGrid& frames);

  /// Continues the snapshots of a run resumed from its checkpoint at observation step
  /// `checkpoint_step` (checked by check_resumable_snapshots): keeps the frames up to the
  /// checkpoint, removes the later ones (the stopped process wrote them after it; they are
  /// written again, the same bytes) and lists the kept ones in a new collection. Throws
  /// RuntimeFailure naming a file that cannot be removed or written.
  SnapshotWriter(const SnapshotFiles& files, double interval_s, const Scenario& scenario, std::int64_t checkpoint_step);
  SnapshotWriter(const SnapshotFiles& files, const Scenario& scenario, const FrameGrid& frames,
                 std::int64_t checkpoint_step);

  /// Writes a frame if this observation is at a multiple of the interval. Throws
  /// RuntimeFailure naming the file that cannot be written.
  void at_observation(const Engine& engine, const ObservationStep& step);

  const SnapshotFiles& files() const { return files_; }
  const FrameGrid& frame_grid() const { return frames_at_; }
  std::int64_t frames() const { return frames_; }

 private:
  void write_frame(const Engine& engine, std::int64_t frame);
  /// Removes the frames from `kept` on; the data sets of those before.
  std::vector<vtk::Collection::DataSet> trim_to(std::int64_t kept) const;

  SnapshotFiles files_;
  Cavity cavity_;
  FrameGrid frames_at_;
  vtk::Collection collection_;
  std::int64_t frames_ = 0;
};

/// The spheres of `state` with what each dissipated, as PolyData: points at the centres
/// (m), arrays radius_m, velocity_m_s, spin_rad_s, dissipated_impact_J,
/// dissipated_friction_J and id (the sphere's index in the scenario), field TimeValue (s).
vtk::PolyData spheres_poly_data(const State& state, const SphereDissipation& dissipated);

/// The cavity's surface at the host's position `host_z_m` (m): its side wall as
/// `segments` quadrilaterals and each cap as one polygon, field data TimeValue (s),
/// host_z_m and host_v_m_s.
vtk::PolyData cavity_poly_data(const Cavity& cavity, const Observation& observation, int segments = 64);

}  // namespace pdamp
