/// `[frf]` and `[characterise]` sections of study files (study_file.hpp): their keys, checked one by one.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <set>
#include <span>

#include "grid_builder.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/study/study_file.hpp"

namespace pdamp::study {
namespace {

constexpr std::array<std::pair<FrfDirection, std::string_view>, 3> direction_names{
    {{FrfDirection::up, "up"}, {FrfDirection::down, "down"}, {FrfDirection::both, "both"}}};
constexpr std::array<std::pair<FrfStart, std::string_view>, 3> start_names{
    {{FrfStart::continuation, "continue"}, {FrfStart::bed, "bed"}, {FrfStart::prediction, "predict"}}};

/// Keys [frf] sets itself on every point, which a section may not set.
constexpr std::array<std::string_view, 6> keys_set_by_frf{"excitation.mode",        "excitation.force_N",
                                                          "excitation.amplitude_m", "excitation.frequency_hz",
                                                          "run.duration_s",         "run.sample_interval_s"};

constexpr std::string_view frf_keys =
    "mode, levels, frequencies, direction, host_alone, start, models, consecutive_cycles, amplitude_tolerance, "
    "phase_tolerance_rad, min_cycles, max_cycles, measured_cycles, zip, or a scenario key section.key";

/// Bounds of the steady-state counts: beyond them a point's work or memory has no bound.
constexpr long max_cycle_cap = 100'000;

template <typename Value, std::size_t N>
Value named(const std::array<std::pair<Value, std::string_view>, N>& names, const std::string& text, bool& found) {
  for (const auto& [value, name] : names) {
    if (name == text) {
      found = true;
      return value;
    }
  }
  found = false;
  return names.front().first;
}

std::optional<double> finite_number(const std::string& text) {
  double x = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, x);
  if (ec != std::errc() || ptr != end || !std::isfinite(x)) return std::nullopt;
  return x;
}

/// What [frf] and [characterise] sections share: the line bookkeeping, the frequencies,
/// start, models, steady-state and scenario keys.
class SteadySectionParser {
 protected:
  SteadySectionParser(const ini::Section& header, std::span<const std::string_view> keys_set_here,
                      std::string_view valid_keys)
      : header_(header), keys_set_here_(keys_set_here), valid_keys_(valid_keys) {}

  /// Starts a line: its place for messages, and a key given twice refused.
  void begin(const ini::Entry& entry) {
    where_ = entry.where + ": [" + header_.name + "] " + entry.key;
    if (const auto [it, fresh] = lines_.emplace(entry.key, entry.line); !fresh) {
      fail("is given twice (first on line " + std::to_string(it->second) + ")");
    }
  }

  /// The keys both kinds have; false if `entry` is none of them.
  bool common_key(const ini::Entry& entry, std::vector<std::string>& frequencies, FrfStart& start,
                  std::optional<StudyModels>& models, SteadyStateCriterion& criterion) {
    const std::string& v = entry.value;
    if (entry.key == "frequencies") {
      frequencies = ascending(positive_values(v, "each frequency (Hz) must be > 0"));
    } else if (entry.key == "start") {
      start = choice(start_names, v,
                     "continue (each point from the previous point's final state), predict (the same, with the "
                     "host and the bed moved onto the predicted steady state; [frf] only) or bed (every point "
                     "from the settled bed)");
    } else if (entry.key == "models") {
      if (v != "soft" && v != "hard" && v != "both") fail("= '" + ini::printable(v) + "': must be soft, hard or both");
      models = v == "soft" ? StudyModels::soft : v == "hard" ? StudyModels::hard : StudyModels::both;
    } else {
      return criterion_key(entry.key, v, criterion);
    }
    return true;
  }

  bool flag(const std::string& text) const {
    if (text != "true" && text != "false") fail("= '" + ini::printable(text) + "': must be true or false");
    return text == "true";
  }

  void require(std::initializer_list<const char*> keys, const std::string& what) const {
    for (const char* key : keys) {
      if (!lines_.contains(key))
        throw InputError(header_.where + ": [" + header_.name + "] needs " + key + " (" + what + ")");
    }
  }

  void check_criterion(const SteadyStateCriterion& c) const {
    if (c.min_cycles > c.max_cycles || c.consecutive_cycles > c.max_cycles) {
      throw InputError(header_.where + ": [" + header_.name + "] max_cycles = " + std::to_string(c.max_cycles) +
                       " is below min_cycles = " + std::to_string(c.min_cycles) + " or consecutive_cycles = " +
                       std::to_string(c.consecutive_cycles) + ": the cap must leave room to settle");
    }
  }

  [[noreturn]] void fail(const std::string& why) const { throw InputError(where_ + " " + why); }

  template <typename Value, std::size_t N>
  Value choice(const std::array<std::pair<Value, std::string_view>, N>& names, const std::string& text,
               const std::string& valid) const {
    bool found = false;
    const Value value = named(names, text, found);
    if (!found) fail("= '" + ini::printable(text) + "': must be " + valid);
    return value;
  }

  std::vector<std::string> positive_values(const std::string& text, const std::string& why) const {
    auto values = parse_sweep_values(text, where_);
    std::set<double> seen;
    for (const auto& value : values) {
      const auto x = finite_number(value);
      if (!x || *x <= 0.0) fail("= " + ini::printable(text) + ": '" + ini::printable(value) + "': " + why);
      if (!seen.insert(*x).second) fail("= " + ini::printable(text) + ": the value " + value + " appears twice");
    }
    return values;
  }

  static std::vector<std::string> ascending(std::vector<std::string> values) {
    std::stable_sort(values.begin(), values.end(),
                     [](const std::string& a, const std::string& b) { return *finite_number(a) < *finite_number(b); });
    return values;
  }

  /// Refuses what is no scenario key this section may set: a word that is not a key of the
  /// section, a key the section sets itself, a key no study may set.
  void check_scenario_key(const std::string& key) const {
    if (key.find('.') == std::string::npos) {
      fail("is not an [" + kind() + "] key (valid: " + std::string(valid_keys_) + ")");
    }
    if (std::find(keys_set_here_.begin(), keys_set_here_.end(), key) != keys_set_here_.end()) {
      fail("is set by [" + kind() + "] on every point (from its grid, and the steady-state keys for the run's length)");
    }
    if (const auto why = unsettable_key(key)) fail("is refused: " + *why);
  }

  std::string kind() const { return header_.name.substr(0, header_.name.find('.')); }

  ini::Section header_;

 private:
  /// A steady-state key (SteadyStateCriterion, whose initializers are the defaults).
  bool criterion_key(const std::string& key, const std::string& text, SteadyStateCriterion& c) const {
    const std::map<std::string, int*> counts{{"consecutive_cycles", &c.consecutive_cycles},
                                             {"min_cycles", &c.min_cycles},
                                             {"max_cycles", &c.max_cycles},
                                             {"measured_cycles", &c.measured_cycles}};
    const std::map<std::string, double*> tolerances{{"amplitude_tolerance", &c.amplitude_tolerance},
                                                    {"phase_tolerance_rad", &c.phase_tolerance_rad}};
    if (const auto it = counts.find(key); it != counts.end()) {
      long n = 0;
      const char* end = text.data() + text.size();
      const auto [ptr, ec] = std::from_chars(text.data(), end, n);
      if (ec != std::errc() || ptr != end || n < 1 || n > max_cycle_cap) {
        fail("= '" + ini::printable(text) + "': must be a whole number of cycles from 1 to " +
             std::to_string(max_cycle_cap));
      }
      *it->second = static_cast<int>(n);
      return true;
    }
    if (const auto it = tolerances.find(key); it != tolerances.end()) {
      const auto x = finite_number(text);
      if (!x || *x <= 0.0) fail("= '" + ini::printable(text) + "': must be a number > 0");
      *it->second = *x;
      return true;
    }
    return false;
  }

  std::span<const std::string_view> keys_set_here_;
  std::string_view valid_keys_;
  std::string where_;
  std::map<std::string, int> lines_;
};

class FrfParser : SteadySectionParser {
 public:
  explicit FrfParser(const ini::Section& header)
      : SteadySectionParser(header, keys_set_by_frf, frf_keys), grid_(header.name, [](const std::string& key) {
          return std::find(keys_set_by_frf.begin(), keys_set_by_frf.end(), key) == keys_set_by_frf.end()
                     ? std::nullopt
                     : std::optional<std::string>(key + " is set by [frf] on every point");
        }) {
    frf_.section = header.name;
  }

  void add(const ini::Entry& entry) {
    begin(entry);
    const std::string& v = entry.value;
    if (entry.key == "mode") {
      if (v == "force") {
        frf_.mode = ExcitationMode::force;
      } else if (v == "base") {
        frf_.mode = ExcitationMode::base_motion;
      } else {
        fail("= '" + ini::printable(v) +
             "': must be force (F0 sin wt on the host) or base (base motion Y sin wt); free decay has no "
             "excitation frequency and prescribed motion fixes the host, so neither has a frequency response");
      }
    } else if (entry.key == "levels") {
      frf_.levels = positive_values(v, "each level (F0 in N under a force, Y in m under base motion) must be > 0");
    } else if (entry.key == "direction") {
      frf_.direction = choice(direction_names, v, "up, down or both");
    } else if (entry.key == "host_alone") {
      frf_.host_alone = flag(v);
    } else if (entry.key == "zip") {
      grid_.add(entry);
    } else if (!common_key(entry, frf_.frequencies, frf_.start, frf_.models, frf_.criterion)) {
      check_scenario_key(entry.key);
      grid_.add(entry);
    }
  }

  FrfSection build() const {
    require({"mode", "levels", "frequencies"}, "mode = force or base; levels = F0 in N or Y in m; frequencies in Hz");
    check_criterion(frf_.criterion);
    FrfSection frf = frf_;
    frf.grid.section = frf.section;
    // A key of one value is set on every point; the others are the grid's axes.
    for (auto& axis : grid_.axes()) {
      if (axis.size() > 1) {
        frf.grid.axes.push_back(std::move(axis));
        continue;
      }
      for (std::size_t k = 0; k < axis.keys.size(); ++k) frf.settings.emplace_back(axis.keys[k], axis.values[0][k]);
    }
    return frf;
  }

 private:
  FrfSection frf_;
  GridBuilder grid_;
};

/// Keys [characterise] sets itself on every point (and particles.count = 0 with empty = true).
constexpr std::array<std::string_view, 6> keys_set_by_characterise{"excitation.mode",        "excitation.force_N",
                                                                   "excitation.amplitude_m", "excitation.frequency_hz",
                                                                   "run.duration_s",         "run.sample_interval_s"};

constexpr std::string_view characterise_keys =
    "amplitudes or gammas, frequencies, start, empty, models, consecutive_cycles, amplitude_tolerance, "
    "phase_tolerance_rad, min_cycles, max_cycles, measured_cycles, or a scenario key section.key";

class CharacteriseParser : SteadySectionParser {
 public:
  explicit CharacteriseParser(const ini::Section& header)
      : SteadySectionParser(header, keys_set_by_characterise, characterise_keys) {
    c_.section = header.name;
  }

  void add(const ini::Entry& entry) {
    begin(entry);
    const std::string& v = entry.value;
    if (entry.key == "amplitudes" || entry.key == "gammas") {
      if (axis_given_) fail("and " + axis_key() + " are both given: the amplitude axis is one of them");
      axis_given_ = true;
      c_.axis = entry.key == "gammas" ? AmplitudeAxis::gamma : AmplitudeAxis::amplitude;
      c_.amplitudes = ascending(
          positive_values(v, c_.axis == AmplitudeAxis::gamma
                                 ? "each Gamma = A (2 pi f)^2 / g must be > 0"
                                 : "each amplitude (m, of the container's motion A sin 2 pi f t) must be > 0"));
      at_least_two(c_.amplitudes);
    } else if (entry.key == "empty") {
      c_.empty = flag(v);
    } else if (common_key(entry, c_.frequencies, c_.start, c_.models, c_.criterion)) {
      if (entry.key == "frequencies") at_least_two(c_.frequencies);
      if (c_.start == FrfStart::prediction) {
        fail(
            "= predict: the container's motion is prescribed, there is no host response to predict; use "
            "continue or bed");
      }
    } else {
      check_scenario_key(entry.key);
      if (v.find(',') != std::string::npos || v.find(':') != std::string::npos) {
        fail("= " + ini::printable(v) +
             ": a [characterise] section sets a scenario key to one value; a grid of characterisations is not "
             "supported (make one study per value)");
      }
      c_.settings.emplace_back(entry.key, v);
    }
  }

  CharacteriseSection build() const {
    if (!axis_given_) {
      throw InputError(header_.where + ": [" + header_.name +
                       "] needs amplitudes (m) or gammas (Gamma = A (2 pi f)^2 / g): the amplitude axis");
    }
    require({"frequencies"}, "in Hz, two or more");
    check_criterion(c_.criterion);
    return c_;
  }

 private:
  std::string axis_key() const { return c_.axis == AmplitudeAxis::gamma ? "gammas" : "amplitudes"; }

  void at_least_two(const std::vector<std::string>& values) const {
    if (values.size() < 2) {
      fail("has " + std::to_string(values.size()) +
           " value: a characterisation needs two or more on each axis (an axis of one value cannot be interpolated)");
    }
  }

  CharacteriseSection c_;
  bool axis_given_ = false;
};

}  // namespace

std::string_view to_string(FrfDirection direction) {
  for (const auto& [value, name] : direction_names) {
    if (value == direction) return name;
  }
  throw RuntimeFailure("an FRF direction out of range");
}

std::string_view to_string(FrfStart start) {
  for (const auto& [value, name] : start_names) {
    if (value == start) return name;
  }
  throw RuntimeFailure("an FRF start out of range");
}

FrfSection parse_frf_section(const ini::Section& header, const std::vector<ini::Entry>& entries) {
  FrfParser parser(header);
  for (const auto& entry : entries) parser.add(entry);
  return parser.build();
}

CharacteriseSection parse_characterise_section(const ini::Section& header, const std::vector<ini::Entry>& entries) {
  CharacteriseParser parser(header);
  for (const auto& entry : entries) parser.add(entry);
  return parser.build();
}

}  // namespace pdamp::study
