#include "pdamp/sim/snapshots.hpp"

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <system_error>

#include "pdamp/errors.hpp"

namespace pdamp {
namespace {

/// How many observation steps apart the frames are (the interval is checked to be a
/// whole multiple of the step).
std::int64_t steps_per_frame(double interval_s, const Scenario& scenario) {
  return std::llround(interval_s / observation_grid(scenario).step_s);
}

std::string describe(double value) {
  std::ostringstream text;
  text.precision(6);
  text << value;
  return text.str();
}

void require_multiple_of_observation_step(double interval_s, const Scenario& scenario) {
  const ObservationGrid grid = observation_grid(scenario);
  const double multiple = interval_s / grid.step_s;
  const double nearest = std::round(multiple);
  if (nearest >= 1.0 && std::abs(nearest * grid.step_s - interval_s) <= 1e-9 * interval_s) return;
  const double below = std::max(1.0, std::floor(multiple)), above = std::max(1.0, std::ceil(multiple));
  throw InputError(
      "--snapshots " + describe(interval_s) + ": frames are taken where the run loop observes the engine, " + "every " +
      describe(grid.step_s) + " s (run.sample_interval_s = " + describe(scenario.run.sample_interval_s) + " s in " +
      std::to_string(grid.steps_per_sample) + (grid.steps_per_sample == 1 ? " step" : " steps") +
      "), so that the engines run as they do without snapshots; give a whole multiple of it, e.g. " +
      describe(below * grid.step_s) + (above != below ? " or " + describe(above * grid.step_s) : "") + " s");
}

void require_positive_interval(double interval_s) {
  if (!std::isfinite(interval_s) || interval_s <= 0.0) {
    throw InputError("--snapshots " + describe(interval_s) +
                     ": must be a positive, finite number of seconds of simulated time between frames");
  }
}

void require_frames_within_budget(double interval_s, const Scenario& scenario) {
  const double frames = std::floor(scenario.run.duration_s / interval_s + 1e-9) + 1.0;
  if (frames <= static_cast<double>(max_snapshot_frames)) return;
  std::ostringstream why;
  why << "--snapshots " << describe(interval_s) << ": run.duration_s = " << scenario.run.duration_s << " s would take "
      << static_cast<long long>(frames) << " frames, more than the " << max_snapshot_frames
      << " a run may write (docs/snapshots.md); give an interval of at least "
      << describe(scenario.run.duration_s / static_cast<double>(max_snapshot_frames - 1)) << " s";
  throw InputError(why.str());
}

/// The directory exists as a folder this process can write into, or its nearest existing
/// ancestor does (so that it can be created).
void require_writable_directory(const std::filesystem::path& directory) {
  namespace fs = std::filesystem;
  const fs::path absolute = fs::absolute(directory);
  fs::path existing = absolute;
  std::error_code ec;
  while (!fs::exists(existing, ec) && existing.has_relative_path()) existing = existing.parent_path();
  const std::string named = "--snapshot-dir '" + directory.string() + "'";
  if (!fs::is_directory(existing, ec)) {
    throw InputError(named + " cannot be " + (existing == absolute ? "used" : "created") + ": '" + existing.string() +
                     "' is not a folder; give a folder that exists or can be created");
  }
  if (access(existing.c_str(), W_OK | X_OK) != 0) {
    throw InputError(named + " cannot be " + (existing == absolute ? "written" : "created") + ": '" +
                     existing.string() + "' is not writable; give a folder this user can write");
  }
}

/// Makes the run's folder, which must be new or empty.
SnapshotFiles prepared(SnapshotFiles files) {
  std::error_code ec;
  std::filesystem::create_directories(files.folder, ec);
  if (ec) throw RuntimeFailure("snapshot folder '" + files.folder.string() + "' cannot be created: " + ec.message());
  if (!std::filesystem::is_empty(files.folder, ec) || ec) {
    throw RuntimeFailure("snapshot folder '" + files.folder.string() +
                         "' already holds files (of a run of another store?); give another --snapshot-dir");
  }
  return files;
}

std::string frame_file(const char* what, std::int64_t frame) {
  char name[40];
  std::snprintf(name, sizeof name, "%s_%06lld.vtp", what, static_cast<long long>(frame));
  return name;
}

vtk::DataArray field(const std::string& name, double value) { return {name, 1, std::vector<double>{value}}; }

/// The columns of a 3 × N matrix, each x, y, z, one after another.
std::vector<double> interleaved(const Eigen::Matrix3Xd& columns) {
  return {columns.data(), columns.data() + columns.size()};
}

std::vector<double> values(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

}  // namespace

SnapshotSettings parse_snapshot_settings(const std::string& every_s, const std::string& directory,
                                         const std::filesystem::path& default_directory) {
  SnapshotSettings settings;
  const char* end = every_s.data() + every_s.size();
  if (auto [ptr, ec] = std::from_chars(every_s.data(), end, settings.interval_s); ec != std::errc() || ptr != end) {
    throw InputError("--snapshots '" + every_s + "': must be a number of seconds of simulated time between frames");
  }
  settings.directory = directory.empty() ? default_directory : std::filesystem::path(directory);
  return settings;
}

std::filesystem::path default_snapshot_directory(const std::filesystem::path& store_file) {
  return std::filesystem::path(store_file).replace_extension(".snapshots");
}

void check_snapshot_settings(const SnapshotSettings& settings, const Scenario& scenario) {
  require_positive_interval(settings.interval_s);
  require_multiple_of_observation_step(settings.interval_s, scenario);
  require_frames_within_budget(settings.interval_s, scenario);
  require_writable_directory(settings.directory);
}

void check_cycle_snapshot_settings(const SnapshotSettings& settings, double period_s, std::int64_t max_cycles) {
  require_positive_interval(settings.interval_s);
  const FrameGrid frames = cycle_frames(settings.interval_s, period_s);
  const std::int64_t count = max_cycles / frames.steps_per_frame + 1;
  if (count > max_snapshot_frames) {
    throw InputError("--snapshots " + describe(settings.interval_s) + ": a point of up to " +
                     std::to_string(max_cycles) + " cycles of " + describe(period_s) + " s, a frame every " +
                     std::to_string(frames.steps_per_frame) + ", would take " + std::to_string(count) +
                     " frames, more than the " + std::to_string(max_snapshot_frames) +
                     " a run may write (docs/snapshots.md); give a longer interval");
  }
  require_writable_directory(settings.directory);
}

SnapshotFiles snapshot_files(const SnapshotSettings& settings, std::int64_t run_id) {
  const std::string run = "run-" + std::to_string(run_id);
  const std::filesystem::path folder = std::filesystem::absolute(settings.directory) / run;
  return {folder, folder / (run + ".pvd")};
}

void check_resumable_snapshots(const SnapshotFiles& files, double interval_s, const Scenario& scenario,
                               std::int64_t run_id, std::int64_t checkpoint_step) {
  const std::string whose = "run " + std::to_string(run_id) + "'s snapshots (every " + describe(interval_s) +
                            " s in '" + files.folder.string() + "')";
  try {
    check_snapshot_settings({interval_s, files.folder.parent_path()}, scenario);
  } catch (const InputError& e) {
    throw InputError(whose + ": " + e.what());
  }
  std::error_code ec;
  if (!std::filesystem::is_directory(files.folder, ec)) {
    throw InputError(whose +
                     " cannot be continued: the folder is gone; a resumed run continues its snapshots where "
                     "they are (docs/checkpoints.md)");
  }
  const std::int64_t kept = checkpoint_step / steps_per_frame(interval_s, scenario) + 1;
  for (std::int64_t frame = 0; frame < kept; ++frame) {
    for (const char* what : {"spheres", "cavity"}) {
      const std::filesystem::path file = files.folder / frame_file(what, frame);
      if (!std::filesystem::is_regular_file(file, ec)) {
        throw InputError(whose + " cannot be continued: '" + file.string() +
                         "', a frame before its checkpoint, is gone");
      }
    }
  }
}

FrameGrid run_loop_frames(double interval_s, const Scenario& scenario) {
  return {observation_grid(scenario), steps_per_frame(interval_s, scenario)};
}

FrameGrid cycle_frames(double interval_s, double period_s) {
  return {{1, period_s, period_s}, std::max<std::int64_t>(1, std::llround(interval_s / period_s))};
}

SnapshotWriter::SnapshotWriter(const SnapshotSettings& settings, const Scenario& scenario, std::int64_t run_id)
    : SnapshotWriter(settings, scenario, run_id, run_loop_frames(settings.interval_s, scenario)) {}

SnapshotWriter::SnapshotWriter(const SnapshotSettings& settings, const Scenario& scenario, std::int64_t run_id,
                               const FrameGrid& frames)
    : files_(prepared(snapshot_files(settings, run_id))),
      cavity_(scenario.cavity),
      frames_at_(frames),
      collection_(files_.collection) {}

SnapshotWriter::SnapshotWriter(const SnapshotFiles& files, double interval_s, const Scenario& scenario,
                               std::int64_t checkpoint_step)
    : SnapshotWriter(files, scenario, run_loop_frames(interval_s, scenario), checkpoint_step) {}

SnapshotWriter::SnapshotWriter(const SnapshotFiles& files, const Scenario& scenario, const FrameGrid& frames,
                               std::int64_t checkpoint_step)
    : files_(files),
      cavity_(scenario.cavity),
      frames_at_(frames),
      collection_(files_.collection, trim_to(checkpoint_step / frames.steps_per_frame + 1)),
      frames_(checkpoint_step / frames.steps_per_frame + 1) {}

std::vector<vtk::Collection::DataSet> SnapshotWriter::trim_to(std::int64_t kept) const {
  // Frames are written in order, spheres first: those after the checkpoint run on from it.
  for (std::int64_t frame = kept;; ++frame) {
    bool any = false;
    for (const char* what : {"spheres", "cavity"}) {
      const std::filesystem::path file = files_.folder / frame_file(what, frame);
      std::error_code ec;
      any = std::filesystem::remove(file, ec) || any;
      if (ec) throw RuntimeFailure("snapshot file '" + file.string() + "' cannot be removed: " + ec.message());
    }
    if (!any) break;
  }
  std::vector<vtk::Collection::DataSet> data_sets;
  for (std::int64_t frame = 0; frame < kept; ++frame) {
    const double t_s = frames_at_.grid.time_s(frame * frames_at_.steps_per_frame);
    data_sets.push_back({t_s, 0, frame_file("spheres", frame)});
    data_sets.push_back({t_s, 1, frame_file("cavity", frame)});
  }
  return data_sets;
}

void SnapshotWriter::at_observation(const Engine& engine, const ObservationStep& step) {
  const std::int64_t every = frames_at_.steps_per_frame;
  if (step.on_grid && step.index % every == 0) write_frame(engine, step.index / every);
}

void SnapshotWriter::write_frame(const Engine& engine, std::int64_t frame) {
  const State state = engine.state();
  const std::string spheres = frame_file("spheres", frame), cavity = frame_file("cavity", frame);
  vtk::write_poly_data(files_.folder / spheres, spheres_poly_data(state, engine.dissipation_by_sphere()));
  vtk::write_poly_data(files_.folder / cavity, cavity_poly_data(cavity_, state.observation));
  collection_.add({state.observation.t_s, 0, spheres});
  collection_.add({state.observation.t_s, 1, cavity});
  ++frames_;
}

vtk::PolyData spheres_poly_data(const State& state, const SphereDissipation& dissipated) {
  const Particles& p = state.particles;
  const auto n = static_cast<std::int64_t>(p.size());
  vtk::PolyData data;
  data.points = interleaved(p.position_m);
  std::vector<std::int64_t> ids(static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i) ids[static_cast<std::size_t>(i)] = i;
  data.verts.connectivity = ids;
  data.verts.offsets.resize(ids.size());
  for (std::int64_t i = 0; i < n; ++i) data.verts.offsets[static_cast<std::size_t>(i)] = i + 1;
  data.point_data = {{"radius_m", 1, values(p.radius_m)},
                     {"velocity_m_s", 3, interleaved(p.velocity_m_s)},
                     {"spin_rad_s", 3, interleaved(p.angular_velocity_rad_s)},
                     {"dissipated_impact_J", 1, values(dissipated.impact_J)},
                     {"dissipated_friction_J", 1, values(dissipated.friction_J)},
                     {"id", 1, std::move(ids)}};
  data.field_data = {field("TimeValue", state.observation.t_s)};
  return data;
}

vtk::PolyData cavity_poly_data(const Cavity& cavity, const Observation& observation, int segments) {
  // Points: the bottom rim 0 .. segments − 1, then the top rim.
  vtk::PolyData data;
  const double bottom = observation.host.z_m, top = bottom + cavity.height_m();
  for (const double z : {bottom, top}) {
    for (int k = 0; k < segments; ++k) {
      const double angle = 2.0 * std::numbers::pi * k / segments;
      data.points.insert(data.points.end(),
                         {cavity.radius_m() * std::cos(angle), cavity.radius_m() * std::sin(angle), z});
    }
  }
  std::vector<std::int64_t>& corners = data.polys.connectivity;
  auto end_polygon = [&] { data.polys.offsets.push_back(static_cast<std::int64_t>(corners.size())); };
  for (int k = 0; k < segments; ++k) {
    const int next = (k + 1) % segments;
    corners.insert(corners.end(), {k, next, segments + next, segments + k});
    end_polygon();
  }
  for (int k = segments - 1; k >= 0; --k) corners.push_back(k);  // the bottom cap, facing down
  end_polygon();
  for (int k = 0; k < segments; ++k) corners.push_back(segments + k);  // the top cap, facing up
  end_polygon();
  data.field_data = {field("TimeValue", observation.t_s), field("host_z_m", observation.host.z_m),
                     field("host_v_m_s", observation.host.v_m_s)};
  return data;
}

}  // namespace pdamp
