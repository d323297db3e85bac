/// `[frf]` sections of study files (study_file.hpp): their keys, checked one by one.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <set>

#include "pdamp/errors.hpp"
#include "pdamp/study/study_file.hpp"

namespace pdamp::study {
namespace {

constexpr std::array<std::pair<FrfDirection, std::string_view>, 3> direction_names{
    {{FrfDirection::up, "up"}, {FrfDirection::down, "down"}, {FrfDirection::both, "both"}}};
constexpr std::array<std::pair<FrfStart, std::string_view>, 2> start_names{
    {{FrfStart::continuation, "continue"}, {FrfStart::bed, "bed"}}};

/// Keys [frf] sets itself on every point, which a section may not set.
constexpr std::array<std::string_view, 6> keys_set_by_frf{"excitation.mode",        "excitation.force_N",
                                                          "excitation.amplitude_m", "excitation.frequency_hz",
                                                          "run.duration_s",         "run.sample_interval_s"};

constexpr std::string_view frf_keys =
    "mode, levels, frequencies, direction, host_alone, start, models, consecutive_cycles, amplitude_tolerance, "
    "phase_tolerance_rad, min_cycles, max_cycles, measured_cycles, or a scenario key section.key";

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

class FrfParser {
 public:
  explicit FrfParser(const ini::Section& header) : header_(header) { frf_.section = header.name; }

  void add(const ini::Entry& entry) {
    where_ = entry.where + ": [" + frf_.section + "] " + entry.key;
    if (const auto [it, fresh] = lines_.emplace(entry.key, entry.line); !fresh) {
      fail("is given twice (first on line " + std::to_string(it->second) + ")");
    }
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
    } else if (entry.key == "frequencies") {
      frf_.frequencies = positive_values(v, "each frequency (Hz) must be > 0");
      std::stable_sort(
          frf_.frequencies.begin(), frf_.frequencies.end(),
          [](const std::string& a, const std::string& b) { return *finite_number(a) < *finite_number(b); });
    } else if (entry.key == "direction") {
      frf_.direction = choice(direction_names, v, "up, down or both");
    } else if (entry.key == "start") {
      frf_.start = choice(start_names, v,
                          "continue (each point from the previous point's final state) or bed (every point from "
                          "the settled bed)");
    } else if (entry.key == "host_alone") {
      if (v != "true" && v != "false") fail("= '" + ini::printable(v) + "': must be true or false");
      frf_.host_alone = v == "true";
    } else if (entry.key == "models") {
      if (v != "soft" && v != "hard" && v != "both") fail("= '" + ini::printable(v) + "': must be soft, hard or both");
      frf_.models = v == "soft" ? StudyModels::soft : v == "hard" ? StudyModels::hard : StudyModels::both;
    } else if (!criterion_key(entry.key, v)) {
      scenario_key(entry.key, v);
    }
  }

  FrfSection build() const {
    for (const char* key : {"mode", "levels", "frequencies"}) {
      if (!lines_.contains(key)) {
        throw InputError(header_.where + ": [" + frf_.section + "] needs " + key +
                         " (mode = force or base; levels = F0 in N or Y in m; frequencies in Hz)");
      }
    }
    const SteadyStateCriterion& c = frf_.criterion;
    if (c.min_cycles > c.max_cycles || c.consecutive_cycles > c.max_cycles) {
      throw InputError(header_.where + ": [" + frf_.section + "] max_cycles = " + std::to_string(c.max_cycles) +
                       " is below min_cycles = " + std::to_string(c.min_cycles) + " or consecutive_cycles = " +
                       std::to_string(c.consecutive_cycles) + ": the cap must leave room to settle");
    }
    return frf_;
  }

 private:
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

  /// A steady-state key (SteadyStateCriterion, whose initializers are the defaults).
  bool criterion_key(const std::string& key, const std::string& text) {
    SteadyStateCriterion& c = frf_.criterion;
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

  void scenario_key(const std::string& key, const std::string& value) {
    if (key.find('.') == std::string::npos) fail("is not an [frf] key (valid: " + std::string(frf_keys) + ")");
    if (std::find(keys_set_by_frf.begin(), keys_set_by_frf.end(), key) != keys_set_by_frf.end()) {
      fail(
          "is set by [frf] on every point (mode, levels, frequencies, and the steady-state keys for the run's "
          "length)");
    }
    if (const auto why = unsettable_key(key)) fail("is refused: " + *why);
    if (value.find(',') != std::string::npos) {
      fail("= " + ini::printable(value) +
           ": an [frf] section sets a scenario key to one value; a grid of frequency responses is not supported "
           "(make one study per value)");
    }
    frf_.settings.emplace_back(key, value);
  }

  ini::Section header_;
  FrfSection frf_;
  std::string where_;
  std::map<std::string, int> lines_;
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

}  // namespace pdamp::study
