#include "pdamp/study/study.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <string_view>

#include "pdamp/errors.hpp"
#include "pdamp/input_file.hpp"
#include "pdamp/model/scenario_loader.hpp"
#include "pdamp/scenario/ini.hpp"
#include "pdamp/sim/frf_point.hpp"
#include "pdamp/sim/stored_run.hpp"

namespace pdamp::study {
namespace {

std::string point_name(const Study& study, const StudyPoint& point) {
  const std::string name = study.file.name + "/" + std::to_string(point.point);
  const std::string grid = point.frf ? describe_grid(*point.frf) : "";
  return grid.empty() ? name : name + " (" + grid + ")";
}

void check_name(const std::string& name, const std::string& origin) {
  const bool printable = std::all_of(name.begin(), name.end(), [](unsigned char c) { return c >= 0x20 && c != 0x7f; });
  if (name.empty() || name.size() > 100 || !printable || name.find('#') != std::string::npos) {
    throw InputError(origin + ": the study name '" + name +
                     "' must be 1 to 100 printable characters without '#' (set it with [study] name = ...)");
  }
}

std::vector<Model> models_of(StudyModels models) {
  std::vector<Model> list;
  if (models != StudyModels::hard) list.push_back(Model::soft);
  if (models != StudyModels::soft) list.push_back(Model::hard);
  return list;
}

std::vector<FrfDirection> directions_of(FrfDirection direction) {
  if (direction == FrfDirection::both) return {FrfDirection::up, FrfDirection::down};
  return {direction};
}

using KeyValues = std::vector<std::pair<std::string, std::string>>;

/// Every combination of a grid's values, the last axis varying fastest (one, empty, for a
/// grid without axes).
std::vector<KeyValues> combinations(const Sweep& grid) {
  std::vector<KeyValues> all;
  std::vector<std::size_t> index(grid.axes.size(), 0);
  for (;;) {
    KeyValues values;
    for (std::size_t a = 0; a < grid.axes.size(); ++a) {
      const auto& axis = grid.axes[a];
      for (std::size_t k = 0; k < axis.keys.size(); ++k) values.emplace_back(axis.keys[k], axis.values[index[a]][k]);
    }
    all.push_back(std::move(values));
    std::size_t a = grid.axes.size();
    while (a > 0 && ++index[a - 1] == grid.axes[a - 1].size()) index[--a] = 0;
    if (a == 0) return all;
  }
}

/// A host-alone curve's grid values: those of the keys outside [particles], which a host
/// without particles does not depend on.
KeyValues host_alone_grid(KeyValues grid) {
  std::erase_if(grid, [](const auto& v) { return v.first.starts_with("particles."); });
  return grid;
}

/// The curves of an [frf] section: for each combination of its grid keys, each (model,
/// level, direction); then the host alone's.
std::vector<FrfPoint> frf_curves(const StudyFile& file, std::size_t section) {
  const FrfSection& frf = file.frfs[section];
  std::vector<FrfPoint> curves;
  const auto models = models_of(frf.models.value_or(file.models));
  const auto grid = combinations(frf.grid);
  for (const auto& values : grid) {
    for (const Model model : models) {
      for (const auto& level : frf.levels) {
        for (const FrfDirection direction : directions_of(frf.direction)) {
          curves.push_back({section, 0, model, direction, false, level, "", 0, 0, values});
        }
      }
    }
  }
  // The host alone is linear: one curve gives its response at every level and direction,
  // and one per combination of the keys it depends on.
  if (!frf.host_alone) return curves;
  std::set<KeyValues> alone;
  for (const auto& values : grid) {
    auto own = host_alone_grid(values);
    if (alone.insert(own).second) {
      curves.push_back(
          {section, 0, models.front(), FrfDirection::up, true, frf.levels.front(), "", 0, 0, std::move(own)});
    }
  }
  return curves;
}

/// `a * b`, or `limit + 1` if that is more than `limit`.
std::size_t times_up_to(std::size_t a, std::size_t b, std::size_t limit) {
  if (a != 0 && b > limit / a) return limit + 1;
  return std::min(a * b, limit + 1);
}

/// The points of an [frf] section, counted before its curves are made (at most
/// `limit + 1`): a grid's host-alone curves counted as one per combination.
std::size_t frf_points_up_to(const FrfSection& frf, StudyModels study_models, std::size_t limit) {
  const std::size_t combinations = frf.grid.points_up_to(limit);
  const std::size_t per_combination =
      models_of(frf.models.value_or(study_models)).size() * directions_of(frf.direction).size() * frf.levels.size();
  const std::size_t curves =
      std::min(times_up_to(combinations, per_combination, limit) + (frf.host_alone ? combinations : 0), limit + 1);
  return times_up_to(curves, frf.frequencies.size(), limit);
}

/// Refuses a study of more than max_points points before its points are made.
void check_size(const StudyFile& file, const std::string& origin) {
  std::size_t total = 0;
  for (const auto& frf : file.frfs) total += frf_points_up_to(frf, file.models, max_points);
  for (const auto& c : file.characterisations) {
    total += models_of(c.models.value_or(file.models)).size() * c.frequencies.size() * c.amplitudes.size();
  }
  for (const auto& sweep : file.sweeps) total += sweep.points_up_to(max_points);
  if (total > max_points) {
    throw InputError(origin + ": the study has more than " + std::to_string(max_points) +
                     " points, the most pdamp runs in one study; split it or use fewer values");
  }
}

void check_force(std::size_t points, bool force, const std::string& origin) {
  if (points > max_points_without_force && !force) {
    throw InputError(origin + ": the study has " + std::to_string(points) + " points, more than the " +
                     std::to_string(max_points_without_force) +
                     " allowed without --force; check the grid (a zip varies keys together instead of "
                     "combining them) or give --force");
  }
}

void expand(const Sweep& sweep, std::vector<StudyPoint>& points) {
  for (auto& values : combinations(sweep)) {
    points.push_back(
        {static_cast<int>(points.size()) + 1, sweep.section, std::move(values), std::nullopt, std::nullopt});
  }
}

std::string exact(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}

/// |g| of the base scenario with a characterisation's settings: what turns Γ into A.
double characterisation_gravity_m_s2(const StudySource& source, const CharacteriseSection& c) {
  ScenarioOverrides overrides;
  for (const auto& [key, value] : c.settings) overrides.push_back(key + "=" + value);
  const double g =
      parse_scenario(source.scenario_text, "base", source.scenario_path.string(), overrides, "set").gravity_m_s2.norm();
  if (g <= 0.0) {
    throw InputError(source.study_path.string() + ": [" + c.section +
                     "] gammas: Gamma = A (2 pi f)^2 / g needs gravity, and the scenario has |g| = 0; give "
                     "amplitudes (m) instead");
  }
  return g;
}

void expand_characterisation(const Study& study, std::size_t section, std::vector<StudyPoint>& points) {
  const CharacteriseSection& c = study.file.characterisations[section];
  const bool from_gamma = c.axis == AmplitudeAxis::gamma;
  const double g_m_s2 = from_gamma ? characterisation_gravity_m_s2(study.source, c) : 0.0;
  for (const Model model : models_of(c.models.value_or(study.file.models))) {
    for (const auto& frequency : c.frequencies) {
      const int curve = points.empty() ? 1 : points.back().characterise->curve + 1;
      const double omega_rad_s = 2.0 * std::numbers::pi * std::stod(frequency);
      for (std::size_t i = 0; i < c.amplitudes.size(); ++i) {
        CharacterisePoint place{section, curve, model, c.empty, c.amplitudes[i], "", frequency, static_cast<int>(i) + 1,
                                0};
        if (from_gamma) {
          place.gamma = c.amplitudes[i];
          place.amplitude_m = exact(std::stod(c.amplitudes[i]) * g_m_s2 / (omega_rad_s * omega_rad_s));
        }
        StudyPoint p{static_cast<int>(points.size()) + 1, c.section, c.settings, std::nullopt, place};
        p.characterise->previous = continues(c.start) && i > 0 ? p.point - 1 : 0;
        p.values.emplace_back("excitation.mode", "prescribed");
        p.values.emplace_back("excitation.amplitude_m", place.amplitude_m);
        p.values.emplace_back("excitation.frequency_hz", frequency);
        if (c.empty) {
          std::erase_if(p.values, [](const auto& v) { return v.first == "particles.count"; });
          p.values.emplace_back("particles.count", "0");
        }
        points.push_back(std::move(p));
      }
    }
  }
}

void expand(const StudyFile& file, std::size_t section, std::vector<StudyPoint>& points) {
  const FrfSection& frf = file.frfs[section];
  const bool base = frf.mode == ExcitationMode::base_motion;
  for (FrfPoint curve : frf_curves(file, section)) {
    curve.curve = points.empty() || !points.back().frf ? 1 : points.back().frf->curve + 1;
    auto frequencies = frf.frequencies;
    if (curve.direction == FrfDirection::down) std::reverse(frequencies.begin(), frequencies.end());
    for (std::size_t i = 0; i < frequencies.size(); ++i) {
      StudyPoint p{static_cast<int>(points.size()) + 1, frf.section, frf.settings, curve, std::nullopt};
      p.values.insert(p.values.end(), curve.grid.begin(), curve.grid.end());
      p.frf->frequency_hz = frequencies[i];
      p.frf->step = static_cast<int>(i) + 1;
      p.frf->previous = continues(frf.start) && i > 0 ? p.point - 1 : 0;
      p.values.emplace_back("excitation.mode", base ? "base" : "force");
      p.values.emplace_back(base ? "excitation.amplitude_m" : "excitation.force_N", curve.level);
      p.values.emplace_back("excitation.frequency_hz", frequencies[i]);
      if (curve.host_alone) {
        std::erase_if(p.values, [](const auto& v) { return v.first == "particles.count"; });
        p.values.emplace_back("particles.count", "0");
      }
      points.push_back(std::move(p));
    }
  }
}

/// Resolved `key = value` lines of a canonical scenario, keyed by "[section] key".
std::map<std::string, std::string> canonical_lines(const std::string& canonical) {
  std::map<std::string, std::string> lines;
  std::istringstream in(canonical);
  std::string section;
  for (std::string line; std::getline(in, line);) {
    if (line.starts_with('[')) {
      section = line;
    } else if (const auto eq = line.find(" = "); eq != std::string::npos) {
      lines[section + " " + line.substr(0, eq)] = line.substr(eq + 3);
    }
  }
  return lines;
}

/// Whether two words are the same number (each as the scenario loader reads it: an integer
/// exactly, beyond a double's digits too; else a double, bit for bit) or the same text.
bool same_word(std::string_view a, std::string_view b) {
  if (a == b) return true;
  const auto integer = [](std::string_view w) -> std::optional<std::string_view> {
    const std::string_view digits = w.starts_with('-') ? w.substr(1) : w;
    if (digits.empty() || !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      return std::nullopt;
    }
    const auto first = std::min(digits.find_first_not_of('0'), digits.size() - 1);
    return digits.substr(first);
  };
  if (const auto x = integer(a), y = integer(b); x && y) return *x == *y && a.starts_with('-') == b.starts_with('-');
  const auto number = [](std::string_view w) -> std::optional<double> {
    double x = 0.0;
    const auto [ptr, ec] = std::from_chars(w.data(), w.data() + w.size(), x);
    if (ec != std::errc() || ptr != w.data() + w.size()) return std::nullopt;
    return x;
  };
  const auto x = number(a), y = number(b);
  return x && y && std::bit_cast<std::uint64_t>(*x) == std::bit_cast<std::uint64_t>(*y);
}

/// The words of a text and the separators between them ("," where one holds a comma, a
/// line break, else " "), so that lists and lines keep their shape.
std::vector<std::string_view> words(std::string_view text) {
  constexpr std::string_view blanks = " \t\r\n,";
  std::vector<std::string_view> out;
  for (std::size_t i = 0; i < text.size();) {
    const bool blank = blanks.find(text[i]) != std::string_view::npos;
    const std::size_t end =
        std::min(blank ? text.find_first_not_of(blanks, i) : text.find_first_of(blanks, i), text.size());
    const std::string_view run = text.substr(i, end - i);
    out.push_back(!blank                                     ? run
                  : run.find(',') != std::string_view::npos  ? std::string_view(",")
                  : run.find('\n') != std::string_view::npos ? std::string_view("\n")
                                                             : std::string_view(" "));
    i = end;
  }
  return out;
}

/// Whether two texts say the same: word for word, numbers by value (`0.10` is `0.1`,
/// `1e-1` too), so that equal values written otherwise are no difference.
bool same_values(std::string_view a, std::string_view b) {
  const auto x = words(a), y = words(b);
  return std::equal(x.begin(), x.end(), y.begin(), y.end(), same_word);
}

void differ(std::vector<std::string>& out, const std::string& what, const std::string& now, const std::string& stored) {
  if (!same_values(now, stored)) out.push_back(what + ": '" + now + "' now, '" + stored + "' stored");
}

/// Each grid key's values (as expanded) and zip partners, keyed by "[section] key".
void add_grid_keys(const Sweep& grid, std::map<std::string, std::string>& keys) {
  for (const auto& axis : grid.axes) {
    for (std::size_t k = 0; k < axis.keys.size(); ++k) {
      std::string values;
      for (const auto& tuple : axis.values) values += (values.empty() ? "" : ", ") + tuple[k];
      if (axis.keys.size() > 1) {
        values += " (zipped with";
        for (const auto& other : axis.keys) values += other == axis.keys[k] ? "" : " " + other;
        values += ")";
      }
      keys["[" + grid.section + "] " + axis.keys[k]] = values;
    }
  }
}

std::map<std::string, std::string> sweep_keys(const StudyFile& file) {
  std::map<std::string, std::string> keys;
  for (const auto& sweep : file.sweeps) add_grid_keys(sweep, keys);
  return keys;
}

/// The keys of an [frf] or [characterise] section that set no scenario key: where its
/// points start and when they are steady, each resolved (defaults included).
void add_steady_keys(const std::string& prefix, FrfStart start, const SteadyStateCriterion& c,
                     std::map<std::string, std::string>& keys) {
  keys[prefix + "start"] = to_string(start);
  keys[prefix + "consecutive_cycles"] = std::to_string(c.consecutive_cycles);
  keys[prefix + "amplitude_tolerance"] = exact(c.amplitude_tolerance);
  keys[prefix + "phase_tolerance_rad"] = exact(c.phase_tolerance_rad);
  keys[prefix + "min_cycles"] = std::to_string(c.min_cycles);
  keys[prefix + "max_cycles"] = std::to_string(c.max_cycles);
  keys[prefix + "measured_cycles"] = std::to_string(c.measured_cycles);
}

/// Each [frf] section's settings, keyed by "[section] key".
std::map<std::string, std::string> frf_keys(const StudyFile& file) {
  std::map<std::string, std::string> keys;
  auto join = [](const std::vector<std::string>& values) {
    std::string text;
    for (const auto& v : values) text += (text.empty() ? "" : ", ") + v;
    return text;
  };
  for (const auto& f : file.frfs) {
    const std::string s = "[" + f.section + "] ";
    keys[s + "mode"] = f.mode == ExcitationMode::force ? "force" : "base";
    keys[s + "levels"] = join(f.levels);
    keys[s + "frequencies"] = join(f.frequencies);
    keys[s + "direction"] = to_string(f.direction);
    keys[s + "host_alone"] = f.host_alone ? "true" : "false";
    keys[s + "models"] = f.models ? to_string(*f.models) : "(the study's)";
    add_steady_keys(s, f.start, f.criterion, keys);
    for (const auto& [key, value] : f.settings) keys[s + key] = value;
    add_grid_keys(f.grid, keys);
  }
  return keys;
}

/// Each [characterise] section's settings, keyed by "[section] key".
std::map<std::string, std::string> characterise_keys(const StudyFile& file) {
  std::map<std::string, std::string> keys;
  auto join = [](const std::vector<std::string>& values) {
    std::string text;
    for (const auto& v : values) text += (text.empty() ? "" : ", ") + v;
    return text;
  };
  for (const auto& c : file.characterisations) {
    const std::string s = "[" + c.section + "] ";
    keys[s + (c.axis == AmplitudeAxis::gamma ? "gammas" : "amplitudes")] = join(c.amplitudes);
    keys[s + "frequencies"] = join(c.frequencies);
    keys[s + "empty"] = c.empty ? "true" : "false";
    keys[s + "models"] = c.models ? to_string(*c.models) : "(the study's)";
    add_steady_keys(s, c.start, c.criterion, keys);
    for (const auto& [key, value] : c.settings) keys[s + key] = value;
  }
  return keys;
}

void map_differences(std::vector<std::string>& out, const std::string& prefix,
                     const std::map<std::string, std::string>& now, const std::map<std::string, std::string>& stored) {
  for (const auto& [key, value] : now) {
    const auto it = stored.find(key);
    differ(out, prefix + key, value, it == stored.end() ? "(not given)" : it->second);
  }
  for (const auto& [key, value] : stored) {
    if (!now.contains(key)) differ(out, prefix + key, "(not given)", value);
  }
}

/// What a point computes: its place, its scenario and, on a curve, how it starts and
/// settles (which its scenario does not say: the run lasts max_cycles + measured_cycles).
std::vector<std::string> canonical_points(const Study& study) {
  std::vector<std::string> texts;
  for (const auto& p : study.points) {
    std::map<std::string, std::string> steady;
    if (p.frf) add_steady_keys("", study.file.frfs.at(p.frf->section).start, point_criterion(study, p), steady);
    if (p.characterise) {
      add_steady_keys("", study.file.characterisations.at(p.characterise->section).start, point_criterion(study, p),
                      steady);
    }
    std::string text = p.section + "\n" + describe_curve(p) + "\n";
    for (const auto& [key, value] : steady) text += key + " = " + value + "\n";
    texts.push_back(text + point_scenario(study, p).canonical_text);
  }
  return texts;
}

}  // namespace

StudySource read_study_source(const std::filesystem::path& study_file) {
  StudySource source;
  source.study_path = std::filesystem::absolute(study_file).lexically_normal();
  source.study_text = read_input_file({source.study_path, "study file '" + ini::printable(study_file.string()) + "'",
                                       "a study file", max_scenario_file_bytes});
  const StudyFile file = parse_study_file(source.study_text, study_file.string(), source.study_path.stem().string());
  source.scenario_path = (source.study_path.parent_path() / file.scenario).lexically_normal();
  try {
    source.scenario_text =
        read_input_file({source.scenario_path, "base scenario '" + ini::printable(source.scenario_path.string()) + "'",
                         "a scenario file", max_scenario_file_bytes, "; the path is relative to the study file"});
  } catch (const InputError& e) {
    throw InputError(study_file.string() + ": [study] scenario = " + file.scenario + ": " + e.what());
  }
  return source;
}

Study make_study(StudySource source, bool force) {
  Study study;
  const std::string origin = source.study_path.string();
  study.file = parse_study_file(source.study_text, origin, source.study_path.stem().string());
  check_name(study.file.name, origin);
  study.source = std::move(source);
  check_size(study.file, origin);
  for (const auto& sweep : study.file.sweeps) expand(sweep, study.points);
  for (std::size_t s = 0; s < study.file.frfs.size(); ++s) expand(study.file, s, study.points);
  for (std::size_t s = 0; s < study.file.characterisations.size(); ++s) expand_characterisation(study, s, study.points);
  check_force(study.points.size(), force, origin);
  return study;
}

Scenario point_scenario(const Study& study, const StudyPoint& point, const std::optional<HostState>& host_start) {
  ScenarioOverrides overrides{"scenario.name=" + point_name(study, point)};
  for (const auto& [key, value] : point.values) overrides.push_back(key + "=" + value);
  if (point.frf || point.characterise) {
    const SteadyStateCriterion& c = point_criterion(study, point);
    const double period_s = 1.0 / std::stod(point.frf ? point.frf->frequency_hz : point.characterise->frequency_hz);
    overrides.push_back("run.duration_s=" + exact((c.max_cycles + c.measured_cycles) * period_s));
    overrides.push_back("run.sample_interval_s=" + exact(period_s));
    if (host_start) {
      overrides.push_back("host.z0_m=" + exact(host_start->z_m));
      overrides.push_back("host.v0_m_s=" + exact(host_start->v_m_s));
    }
  }
  return parse_scenario(study.source.scenario_text, point_name(study, point), study.source.scenario_path.string(),
                        overrides, "swept");
}

const SteadyStateCriterion& point_criterion(const Study& study, const StudyPoint& point) {
  if (point.characterise) return study.file.characterisations.at(point.characterise->section).criterion;
  if (!point.frf) throw RuntimeFailure("point " + std::to_string(point.point) + " is not a frequency-response point");
  return study.file.frfs.at(point.frf->section).criterion;
}

std::string describe_curve(const StudyPoint& point) {
  if (const auto& c = point.characterise) {
    return std::string(to_string(c->model)) + (c->empty ? " empty" : "") + " " + c->frequency_hz + " Hz, curve " +
           std::to_string(c->curve) + ", step " + std::to_string(c->step) +
           (c->previous > 0 ? " after point " + std::to_string(c->previous) : " from the bed");
  }
  if (!point.frf) return "";
  const FrfPoint& f = *point.frf;
  const std::string grid = describe_grid(f);
  return std::string(to_string(f.model)) + (f.host_alone ? " host alone" : "") + " " +
         std::string(to_string(f.direction)) + (grid.empty() ? "" : " (" + grid + ")") + ", curve " +
         std::to_string(f.curve) + ", step " + std::to_string(f.step) +
         (f.previous > 0 ? " after point " + std::to_string(f.previous) : " from the bed");
}

namespace {

std::string describe(const KeyValues& values) {
  std::string text;
  for (const auto& [key, value] : values) text += (text.empty() ? "" : ", ") + key + " = " + value;
  return text;
}

}  // namespace

std::string describe_values(const StudyPoint& point) { return describe(point.values); }

std::string describe_grid(const FrfPoint& curve) { return describe(curve.grid); }

void validate_study(const Study& study, const std::optional<SnapshotSettings>& snapshots) {
  const std::vector<Model> models = models_of(study.file.models);
  for (const auto& point : study.points) {
    try {
      const Scenario scenario = point_scenario(study, point);
      if (point.frf || point.characterise) {
        const SteadyStateCriterion& c = point_criterion(study, point);
        if (snapshots)
          check_cycle_snapshot_settings(*snapshots, cycle_period_s(scenario), c.max_cycles + c.measured_cycles);
        plan_run(point.frf ? point.frf->model : point.characterise->model, scenario);
        continue;
      }
      for (const Model model : models) plan_run(model, scenario, snapshots);
    } catch (const InputError& e) {
      throw InputError(study.source.study_path.string() + ": point " + std::to_string(point.point) + " of " +
                       std::to_string(study.points.size()) + " ([" + point.section + "] " + describe_values(point) +
                       "): " + e.what());
    }
  }
}

std::vector<std::string> study_differences(const Study& stored, const Study& now) {
  const auto stored_points = canonical_points(stored), now_points = canonical_points(now);
  if (stored.file.name == now.file.name && stored.file.models == now.file.models &&
      std::equal(now_points.begin(), now_points.end(), stored_points.begin(), stored_points.end(), same_values)) {
    return {};
  }
  std::vector<std::string> out;
  if (now.file.name != stored.file.name) {
    out.push_back("[study] name: '" + now.file.name + "' now, '" + stored.file.name + "' stored");
  }
  differ(out, "[study] models", std::string(to_string(now.file.models)), std::string(to_string(stored.file.models)));
  map_differences(out, "", sweep_keys(now.file), sweep_keys(stored.file));
  map_differences(out, "", frf_keys(now.file), frf_keys(stored.file));
  map_differences(out, "", characterise_keys(now.file), characterise_keys(stored.file));
  const auto base = [](const Study& s) {
    return canonical_lines(
        parse_scenario(s.source.scenario_text, "base", s.source.scenario_path.string()).canonical_text);
  };
  map_differences(out, "base scenario ", base(now), base(stored));
  if (out.empty()) {
    // The same keys and values in another order: the points are numbered differently.
    auto sorted = [](StudyPoint p) {
      std::sort(p.values.begin(), p.values.end());
      return describe_values(p);
    };
    const std::size_t n = std::min(stored.points.size(), now.points.size());
    for (std::size_t i = 0; i < n && out.empty(); ++i) {
      differ(out, "point " + std::to_string(i + 1), sorted(now.points[i]), sorted(stored.points[i]));
    }
  }
  return out;
}

}  // namespace pdamp::study
