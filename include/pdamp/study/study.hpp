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

#include "pdamp/scenario/scenario.hpp"
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

/// One point: the sweep section it comes from and the values it sets, in the section's
/// key order.
struct StudyPoint {
  int point = 0;  ///< 1, 2, ... over the whole study, in file order
  std::string section;
  std::vector<std::pair<std::string, std::string>> values;  ///< (scenario key, value text)
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
/// a grid whose first axis varies slowest. A study over max_points_without_force points
/// needs `force`; none may exceed max_points. Throws InputError.
Study make_study(StudySource source, bool force);

/// The point's scenario: the base scenario with the point's values, named
/// "<study>/<point>". Throws InputError (from the scenario loader) for a bad value.
Scenario point_scenario(const Study& study, const StudyPoint& point);

/// Builds every point's scenario and checks that each of the study's models can run it,
/// as `pdamp run` does before it stores anything (plan_run: the run's budget, the hard
/// model's calibration, the snapshots if asked for). Throws InputError for the first point that fails, naming the
/// point, its values, the key and what is valid.
void validate_study(const Study& study, const std::optional<SnapshotSettings>& snapshots = {});

/// What differs between a stored study and the same study read now, one line per
/// difference (empty if they would run the same points): the [study] keys, each sweep
/// key's values (compared as expanded), and the base scenario's resolved keys.
std::vector<std::string> study_differences(const Study& stored, const Study& now);

/// "key = value, key = value" of a point.
std::string describe_values(const StudyPoint& point);

}  // namespace pdamp::study
