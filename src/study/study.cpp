#include "pdamp/study/study.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/input_file.hpp"
#include "pdamp/scenario/ini.hpp"
#include "pdamp/scenario/scenario_loader.hpp"
#include "pdamp/sim/stored_run.hpp"

namespace pdamp::study {
namespace {

std::string point_name(const Study& study, int point) { return study.file.name + "/" + std::to_string(point); }

void check_name(const std::string& name, const std::string& origin) {
  const bool printable = std::all_of(name.begin(), name.end(), [](unsigned char c) { return c >= 0x20 && c != 0x7f; });
  if (name.empty() || name.size() > 100 || !printable || name.find('#') != std::string::npos) {
    throw InputError(origin + ": the study name '" + name +
                     "' must be 1 to 100 printable characters without '#' (set it with [study] name = ...)");
  }
}

std::size_t count_points(const StudyFile& file, bool force, const std::string& origin) {
  std::size_t total = 0;
  for (const auto& sweep : file.sweeps) total += sweep.points_up_to(max_points);
  if (total > max_points) {
    throw InputError(origin + ": the study has more than " + std::to_string(max_points) +
                     " points, the most pdamp runs in one study; split it or use fewer values");
  }
  if (total > max_points_without_force && !force) {
    throw InputError(origin + ": the study has " + std::to_string(total) + " points, more than the " +
                     std::to_string(max_points_without_force) +
                     " allowed without --force; check the grid (a zip varies keys together instead of "
                     "combining them) or give --force");
  }
  return total;
}

void expand(const Sweep& sweep, std::vector<StudyPoint>& points) {
  std::vector<std::size_t> index(sweep.axes.size(), 0);
  for (;;) {
    StudyPoint p{static_cast<int>(points.size()) + 1, sweep.section, {}};
    for (std::size_t a = 0; a < sweep.axes.size(); ++a) {
      const auto& axis = sweep.axes[a];
      for (std::size_t k = 0; k < axis.keys.size(); ++k) p.values.emplace_back(axis.keys[k], axis.values[index[a]][k]);
    }
    points.push_back(std::move(p));
    // The last axis varies fastest.
    std::size_t a = sweep.axes.size();
    while (a > 0 && ++index[a - 1] == sweep.axes[a - 1].size()) index[--a] = 0;
    if (a == 0) return;
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

void differ(std::vector<std::string>& out, const std::string& what, const std::string& now, const std::string& stored) {
  if (now != stored) out.push_back(what + ": '" + now + "' now, '" + stored + "' stored");
}

/// Each sweep key's values (as expanded) and zip partners, keyed by "[section] key".
std::map<std::string, std::string> sweep_keys(const StudyFile& file) {
  std::map<std::string, std::string> keys;
  for (const auto& sweep : file.sweeps) {
    for (const auto& axis : sweep.axes) {
      for (std::size_t k = 0; k < axis.keys.size(); ++k) {
        std::string values;
        for (const auto& tuple : axis.values) values += (values.empty() ? "" : ", ") + tuple[k];
        if (axis.keys.size() > 1) {
          values += " (zipped with";
          for (const auto& other : axis.keys) values += other == axis.keys[k] ? "" : " " + other;
          values += ")";
        }
        keys["[" + sweep.section + "] " + axis.keys[k]] = values;
      }
    }
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

std::vector<std::string> canonical_points(const Study& study) {
  std::vector<std::string> texts;
  for (const auto& p : study.points) {
    texts.push_back(p.section + "\n" + point_scenario(study, p).canonical_text);
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
  study.points.reserve(count_points(study.file, force, origin));
  for (const auto& sweep : study.file.sweeps) expand(sweep, study.points);
  return study;
}

Scenario point_scenario(const Study& study, const StudyPoint& point) {
  ScenarioOverrides overrides{"scenario.name=" + point_name(study, point.point)};
  for (const auto& [key, value] : point.values) overrides.push_back(key + "=" + value);
  return parse_scenario(study.source.scenario_text, point_name(study, point.point), study.source.scenario_path.string(),
                        overrides, "swept");
}

std::string describe_values(const StudyPoint& point) {
  std::string text;
  for (const auto& [key, value] : point.values) text += (text.empty() ? "" : ", ") + key + " = " + value;
  return text;
}

void validate_study(const Study& study, const std::optional<SnapshotSettings>& snapshots) {
  std::vector<Model> models;
  if (study.file.models != StudyModels::hard) models.push_back(Model::soft);
  if (study.file.models != StudyModels::soft) models.push_back(Model::hard);
  for (const auto& point : study.points) {
    try {
      const Scenario scenario = point_scenario(study, point);
      for (const Model model : models) plan_run(model, scenario, snapshots);
    } catch (const InputError& e) {
      throw InputError(study.source.study_path.string() + ": point " + std::to_string(point.point) + " of " +
                       std::to_string(study.points.size()) + " ([" + point.section + "] " + describe_values(point) +
                       "): " + e.what());
    }
  }
}

std::vector<std::string> study_differences(const Study& stored, const Study& now) {
  if (stored.file.models == now.file.models && canonical_points(stored) == canonical_points(now)) return {};
  std::vector<std::string> out;
  differ(out, "[study] models", std::string(to_string(now.file.models)), std::string(to_string(stored.file.models)));
  map_differences(out, "", sweep_keys(now.file), sweep_keys(stored.file));
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
