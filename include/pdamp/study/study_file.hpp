#pragma once
/// Study files: the scenario files' INI syntax, read by the same parser (scenario/ini.hpp),
/// with
///   [study]         name (default: the file name), scenario (the base scenario file,
///                   relative to the study file), models = soft | hard | both;
///   [sweep]         scenario keys, each with a list of values or a range; the keys form a
///   [sweep.NAME]    grid (the first key varies slowest); `zip = KEY KEY ...` varies the
///                   listed keys together instead. Several sweep sections add their points;
///   [frf]           stepped-sine response curves (frf_section.cpp), whose scenario keys
///   [frf.NAME]      with several values form a grid the same way, each combination its curves;
///   [characterise]  the damper's container driven over amplitudes and frequencies.
/// A value list separates values with commas, so that a value may hold spaces
/// (`particles.diameter_m = 0.0008 0.0012, 0.001`); `start:stop:count` is a linear range and
/// `start:stop:count:log` a geometric one. Parsing checks the file's own structure and its
/// keys; every point's scenario is checked when the study is built (study.hpp).

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pdamp/analysis/frf_response.hpp"
#include "pdamp/scenario/ini.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp::study {

enum class StudyModels {
  soft,  ///< the soft model alone
  hard,  ///< the hard model alone
  both,  ///< both from one settled bed, with their comparison (as `pdamp compare`)
};
std::string_view to_string(StudyModels models);

/// One axis of a sweep's grid: one key with its values, or several zipped keys that take
/// their i-th values together.
struct SweepAxis {
  std::vector<std::string> keys;
  std::vector<std::vector<std::string>> values;  ///< values[i][k]: the i-th value of keys[k]
  std::size_t size() const { return values.size(); }
};

/// A `[sweep]` or `[sweep.NAME]` section: the grid of its axes.
struct Sweep {
  std::string section;  ///< "sweep" or "sweep.NAME"
  std::vector<SweepAxis> axes;
  /// The number of points, or `limit + 1` if there are more than `limit`.
  std::size_t points_up_to(std::size_t limit) const;
};

enum class FrfDirection { up, down, both };
std::string_view to_string(FrfDirection direction);

/// Where each point of a frequency-response curve starts.
enum class FrfStart {
  continuation,  ///< from the previous point's final state (the curve's first: the settled bed)
  bed,           ///< every point from the settled bed
  prediction,    ///< continuation with the host moved onto its predicted steady state ([frf] only)
};
/// Whether a point starts from the previous point's final state.
inline bool continues(FrfStart start) { return start != FrfStart::bed; }
std::string_view to_string(FrfStart start);

/// An `[frf]` or `[frf.NAME]` section: stepped-sine response curves (docs/studies.md).
struct FrfSection {
  std::string section;                          ///< "frf" or "frf.NAME"
  ExcitationMode mode = ExcitationMode::force;  ///< force or base_motion
  std::vector<std::string> levels;              ///< F0 (N) or Y (m), as written or expanded
  std::vector<std::string> frequencies;         ///< Hz, ascending
  FrfDirection direction = FrfDirection::up;
  bool host_alone = false;  ///< adds one curve of the host without particles
  FrfStart start = FrfStart::continuation;
  SteadyStateCriterion criterion;
  std::optional<StudyModels> models;                          ///< the section's own; default [study] models
  std::vector<std::pair<std::string, std::string>> settings;  ///< scenario keys with one value, set on every point
  /// Scenario keys with several values (and zipped keys): every combination of them has its
  /// own curves. No axes: one combination, setting nothing.
  Sweep grid;
};

/// The amplitude axis of a characterisation: the container's amplitude A (m), or
/// Γ = A (2πf)² / |g|.
enum class AmplitudeAxis { amplitude, gamma };

/// A `[characterise]` or `[characterise.NAME]` section: the damper's container driven with
/// prescribed motion over a grid of amplitude and frequency (docs/characterisation.md).
struct CharacteriseSection {
  std::string section;  ///< "characterise" or "characterise.NAME"
  AmplitudeAxis axis = AmplitudeAxis::amplitude;
  std::vector<std::string> amplitudes;      ///< A (m) or Γ, as written or expanded, ascending
  std::vector<std::string> frequencies;     ///< Hz, ascending
  FrfStart start = FrfStart::continuation;  ///< continuation runs along the amplitude axis
  bool empty = false;                       ///< the container without particles
  SteadyStateCriterion criterion;           ///< judged on the particles' force
  std::optional<StudyModels> models;
  std::vector<std::pair<std::string, std::string>> settings;  ///< scenario keys set on every point
};

/// What a study file says (its base scenario is read by study.hpp): sweeps,
/// frequency-response sections or characterisation sections, one kind only.
struct StudyFile {
  std::string name;
  std::string scenario;  ///< the base scenario file as written, relative to the study file
  StudyModels models = StudyModels::soft;
  std::vector<Sweep> sweeps;
  std::vector<FrfSection> frfs;
  std::vector<CharacteriseSection> characterisations;
};

/// Parses a study file's text. `origin` names it in messages; `default_name` is the study's
/// name unless [study] gives one. Throws InputError naming the line and what is valid.
StudyFile parse_study_file(const std::string& text, const std::string& origin, const std::string& default_name);

/// The values of one sweep key: a comma-separated list of values and ranges (see above).
/// A range's first and last values are its start and stop as written, the others are
/// printed with 15 significant digits. Throws InputError naming `what`.
std::vector<std::string> parse_sweep_values(const std::string& text, const std::string& what);

/// An `[frf]` section from its header and its lines (frf_section.cpp). Throws InputError
/// naming the line, the key and what is valid.
FrfSection parse_frf_section(const ini::Section& header, const std::vector<ini::Entry>& entries);

/// A `[characterise]` section from its header and its lines (frf_section.cpp). Throws
/// InputError naming the line, the key and what is valid.
CharacteriseSection parse_characterise_section(const ini::Section& header, const std::vector<ini::Entry>& entries);

/// Why `key` cannot be set by a study, or nothing if it can (study_file.cpp).
std::optional<std::string> unsettable_key(const std::string& key);

/// Longest range and most points a study may have even with --force: beyond them the
/// study would take memory and validation time without bound.
inline constexpr long max_range_count = 10'000;

}  // namespace pdamp::study
