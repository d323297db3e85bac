#pragma once
/// A study: its file and base scenario (the texts the store keeps), parsed, and expanded
/// into points, each a base scenario with some keys set. Built the same way from the files
/// (`pdamp study run`) and from the store (a worker running a point, a resumed study), so
/// a point is the same scenario wherever it runs.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pdamp/model/host.hpp"
#include "pdamp/scenario/scenario.hpp"
#include "pdamp/sim/engine_factory.hpp"
#include "pdamp/sim/snapshots.hpp"
#include "pdamp/study/study_file.hpp"

namespace pdamp::study {

/// A study's two texts and where they were read.
struct StudySource {
  std::filesystem::path study_path;
  std::string study_text;
  std::filesystem::path scenario_path;
  std::string scenario_text;
};

/// Reads a study file and the base scenario it names. Throws InputError if either is
/// missing or unreadable.
StudySource read_study_source(const std::filesystem::path& study_file);

/// Where a point of a frequency-response curve sits on it. A curve is one combination of
/// the section's grid keys, model, level and direction (or the host alone), its points in
/// the order they run.
struct FrfPoint {
  std::size_t section = 0;  ///< in StudyFile::frfs
  int curve = 0;            ///< 1, 2, ... over the study
  Model model = Model::hard;
  FrfDirection direction = FrfDirection::up;  ///< up or down
  bool host_alone = false;
  std::string level, frequency_hz;  ///< as written (F0 in N or Y in m; Hz)
  int step = 0;                     ///< 1, 2, ... along the curve
  int previous = 0;                 ///< the point whose final state this one starts from; 0: the settled bed
  /// The curve's values of the section's grid keys (FrfSection::grid), in axis order;
  /// a host-alone curve's without the [particles] keys.
  std::vector<std::pair<std::string, std::string>> grid;
};

/// "key = value, key = value" of a curve's grid values ("" without a grid).
std::string describe_grid(const FrfPoint& curve);

/// Where a point of a characterisation sits: a curve is one model and frequency, its
/// points along the amplitude axis, ascending.
struct CharacterisePoint {
  std::size_t section = 0;  ///< in StudyFile::characterisations
  int curve = 0;            ///< 1, 2, ... over the study
  Model model = Model::hard;
  bool empty = false;        ///< the container without particles
  std::string amplitude_m;   ///< A as written, or from Γ with 17 digits
  std::string gamma;         ///< Γ as written ("" for an amplitude axis)
  std::string frequency_hz;  ///< as written
  int step = 0;              ///< 1, 2, ... along the curve
  int previous = 0;          ///< the point whose final state this one starts from; 0: the settled bed
};

/// One point: the section it comes from and the scenario values it sets, in the
/// section's key order; a frequency-response or characterisation point also its place on
/// its curve.
struct StudyPoint {
  int point = 0;  ///< 1, 2, ... over the whole study, in file order
  std::string section;
  std::vector<std::pair<std::string, std::string>> values;  ///< (scenario key, value text)
  std::optional<FrfPoint> frf;
  std::optional<CharacterisePoint> characterise;
  /// The point this one starts from (0: the settled bed).
  int previous() const { return frf ? frf->previous : characterise ? characterise->previous : 0; }
};

/// Points a study may have without --force, and with it.
inline constexpr std::size_t max_points_without_force = 1000;
inline constexpr std::size_t max_points = 100'000;

struct Study {
  StudySource source;
  StudyFile file;
  std::vector<StudyPoint> points;
};

/// Parses the study text and expands its points: the sweep sections in file order, each
/// a grid whose first axis varies slowest; or the [frf] sections in file order, each its
/// curves (each combination of its grid keys, the first axis slowest, then model, then
/// level, then up before down; its host-alone curves last, one per combination of the
/// grid keys outside [particles]), each curve's points in the order they run; or the [characterise] sections, each its
/// curves (model, then frequency), each along the amplitudes, ascending (amplitudes from Γ with the base scenario's
/// gravity: none is refused). A study over max_points_without_force points needs `force`; none may exceed max_points.
/// Throws InputError.
Study make_study(StudySource source, bool force);

/// The point's scenario: the base scenario with the point's values, named
/// "<study>/<point>" (a point of an [frf] grid: "<study>/<point> (key = value, ...)"). A frequency-response point's run
/// lasts its cap of cycles (the budget checked is the worst case) with one sample per cycle, and its host starts at
/// `host_start` if given (the previous point's final state) instead of the base
/// scenario's host.z0_m and host.v0_m_s. Throws InputError (from the scenario loader) for
/// a bad value.
Scenario point_scenario(const Study& study, const StudyPoint& point, const std::optional<HostState>& host_start = {});

/// The steady-state criterion of a frequency-response or characterisation point.
const SteadyStateCriterion& point_criterion(const Study& study, const StudyPoint& point);

/// Builds every point's scenario and checks that each of the study's models can run it,
/// as `pdamp run` does before it stores anything (plan_run: the run's budget, the hard
/// model's calibration, the snapshots if asked for; an [frf] or [characterise] point's as
/// check_cycle_snapshot_settings says). Throws InputError for the first point that fails,
/// naming the point, its values, the key and what is valid.
void validate_study(const Study& study, const std::optional<SnapshotSettings>& snapshots = {});

/// What differs between a stored study and the same study read now, one line per
/// difference (empty if they would run the same points): the [study] keys, each key of
/// the sweep, [frf] and [characterise] sections (values compared as expanded, steady-state
/// keys and start resolved), and the base scenario's resolved keys. Numbers are compared
/// by value (`0.10` and `1e-1` are `0.1`).
std::vector<std::string> study_differences(const Study& stored, const Study& now);

/// "key = value, key = value" of a point.
std::string describe_values(const StudyPoint& point);

/// "hard up, curve 2, step 5 after point 11" of a frequency-response point (of a grid:
/// "hard up (particles.count = 50), curve 2, ..."), "hard 17 Hz,
/// curve 2, ..." of a characterisation point ("" for another).
std::string describe_curve(const StudyPoint& point);

}  // namespace pdamp::study
