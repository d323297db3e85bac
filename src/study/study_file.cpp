#include "pdamp/study/study_file.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "grid_builder.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/model/scenario_loader.hpp"
#include "pdamp/scenario/ini.hpp"

namespace pdamp::study {

namespace {

constexpr std::array<std::pair<StudyModels, std::string_view>, 3> model_names{
    {{StudyModels::soft, "soft"}, {StudyModels::hard, "hard"}, {StudyModels::both, "both"}}};

}  // namespace

std::string_view to_string(StudyModels models) {
  for (const auto& [value, name] : model_names) {
    if (value == models) return name;
  }
  throw RuntimeFailure("a study's models out of range");
}

std::size_t Sweep::points_up_to(std::size_t limit) const {
  std::size_t points = 1;
  for (const auto& axis : axes) {
    if (axis.size() > limit || points > limit / axis.size()) return limit + 1;
    points *= axis.size();
  }
  return points;
}

namespace {

[[noreturn]] void fail(const std::string& where, const std::string& why) { throw InputError(where + ": " + why); }

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

}  // namespace

std::optional<std::string> unsettable_key(const std::string& key) {
  if (key == "scenario.name")
    return std::string("scenario.name cannot be set by a study: the study names each point's scenario");
  const auto keys = scenario_key_names();
  if (std::find(keys.begin(), keys.end(), key) != keys.end()) return std::nullopt;
  std::string why = "'" + key + "' is not a scenario key";
  const auto closest = std::min_element(keys.begin(), keys.end(), [&](const std::string& a, const std::string& b) {
    return edit_distance(key, a) < edit_distance(key, b);
  });
  if (edit_distance(key, *closest) <= 3) why += "; did you mean " + *closest + "?";
  return why + " (run 'pdamp keys' for the list)";
}

namespace {

std::vector<std::string> split_keys(const std::string& text) {
  std::string spaced = text;
  std::replace(spaced.begin(), spaced.end(), ',', ' ');
  std::istringstream in(spaced);
  std::vector<std::string> keys;
  for (std::string k; in >> k;) keys.push_back(k);
  return keys;
}

/// A value as compared for duplicates: a single number by its value, anything else by its
/// words.
std::string comparable(const std::string& value) {
  std::istringstream in(value);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  if (words.size() == 1) {
    std::size_t used = 0;
    try {
      const double x = std::stod(words[0], &used);
      if (used == words[0].size()) {
        std::ostringstream out;
        out.precision(17);
        out << x;
        return out.str();
      }
    } catch (const std::exception&) {
      // not a number: compared as text
    }
  }
  std::string joined;
  for (const auto& w : words) joined += (joined.empty() ? "" : " ") + w;
  return joined;
}

}  // namespace

void GridBuilder::add(const ini::Entry& entry) {
  if (entry.key == "zip") {
    add_zip(entry);
    return;
  }
  if (const auto why = refused(entry.key)) fail(entry.where, "[" + section_ + "] " + *why);
  for (const auto& k : keys_) {
    if (k.key == entry.key) {
      fail(entry.where,
           "[" + section_ + "] " + entry.key + " is given twice (first on line " + std::to_string(k.line) + ")");
    }
  }
  keys_.push_back({entry.key, entry.line, entry.where,
                   parse_sweep_values(entry.value, entry.where + ": [" + section_ + "] " + entry.key)});
}

std::optional<std::string> GridBuilder::refused(const std::string& key) const {
  if (auto why = unsettable_key(key)) return why;
  return also_refused_ ? also_refused_(key) : std::nullopt;
}

std::vector<SweepAxis> GridBuilder::axes() const {
  std::vector<SweepAxis> axes;
  std::set<std::size_t> emitted;
  for (const auto& k : keys_) {
    const auto zip = zip_of(k.key);
    if (!zip) {
      axes.push_back(single_axis(k));
    } else if (emitted.insert(*zip).second) {
      axes.push_back(zipped_axis(zips_[*zip]));
    }
  }
  return axes;
}

void GridBuilder::add_zip(const ini::Entry& entry) {
  const auto keys = split_keys(entry.value);
  const std::string where = "[" + section_ + "] zip = " + entry.value;
  if (keys.size() < 2) fail(entry.where, where + ": a zip names two or more keys to vary together");
  for (const auto& key : keys) {
    if (const auto why = refused(key)) fail(entry.where, where + ": " + *why);
    if (std::count(keys.begin(), keys.end(), key) > 1) fail(entry.where, where + ": " + key + " is named twice");
    if (zip_of(key)) fail(entry.where, where + ": " + key + " is already in another zip");
  }
  zips_.push_back({keys, entry.line, entry.where});
}

std::optional<std::size_t> GridBuilder::zip_of(const std::string& key) const {
  for (std::size_t z = 0; z < zips_.size(); ++z) {
    if (std::find(zips_[z].keys.begin(), zips_[z].keys.end(), key) != zips_[z].keys.end()) return z;
  }
  return std::nullopt;
}

const GridBuilder::Key& GridBuilder::key_named(const std::string& name, const Zip& zip) const {
  for (const auto& k : keys_) {
    if (k.key == name) return k;
  }
  fail(zip.where, "[" + section_ + "] zip names " + name + ", which has no values in this section");
}

SweepAxis GridBuilder::single_axis(const Key& k) const {
  SweepAxis axis{{k.key}, {}};
  std::map<std::string, std::size_t> seen;
  for (std::size_t i = 0; i < k.values.size(); ++i) {
    if (const auto [it, fresh] = seen.emplace(comparable(k.values[i]), i); !fresh) {
      fail(k.where, "[" + section_ + "] " + k.key + ": the value '" + k.values[i] + "' appears twice (values " +
                        std::to_string(it->second + 1) + " and " + std::to_string(i + 1) + ")");
    }
    axis.values.push_back({k.values[i]});
  }
  return axis;
}

SweepAxis GridBuilder::zipped_axis(const Zip& zip) const {
  SweepAxis axis{zip.keys, {}};
  const Key& first = key_named(zip.keys.front(), zip);
  for (const auto& name : zip.keys) {
    const Key& k = key_named(name, zip);
    if (k.values.size() != first.values.size()) {
      fail(k.where, "[" + section_ + "] " + name + " has " + std::to_string(k.values.size()) + " values and " +
                        first.key + " " + std::to_string(first.values.size()) + ": zipped keys (line " +
                        std::to_string(zip.line) + ") need as many values each");
    }
  }
  std::map<std::vector<std::string>, std::size_t> seen;
  for (std::size_t i = 0; i < first.values.size(); ++i) {
    std::vector<std::string> tuple, key;
    for (const auto& name : zip.keys) {
      tuple.push_back(key_named(name, zip).values[i]);
      key.push_back(comparable(tuple.back()));
    }
    if (const auto [it, fresh] = seen.emplace(key, i); !fresh) {
      fail(zip.where, "[" + section_ + "] the zipped values " + std::to_string(it->second + 1) + " and " +
                          std::to_string(i + 1) + " are the same");
    }
    axis.values.push_back(tuple);
  }
  return axis;
}

namespace {

/// `kind` or `kind.NAME`, NAME of letters, digits, _ and -.
bool is_section_of(const std::string& section, std::string_view kind) {
  if (section == kind) return true;
  const std::size_t n = kind.size() + 1;
  if (!section.starts_with(std::string(kind) + ".") || section.size() == n) return false;
  return std::all_of(section.begin() + static_cast<std::ptrdiff_t>(n), section.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
}
bool is_sweep_section(const std::string& section) { return is_section_of(section, "sweep"); }
bool is_frf_section(const std::string& section) { return is_section_of(section, "frf"); }
bool is_characterise_section(const std::string& section) { return is_section_of(section, "characterise"); }

/// The kind of a study's section: sweep, frf or characterise (empty for [study]).
std::string section_kind(const std::string& section) {
  for (const char* kind : {"sweep", "frf", "characterise"}) {
    if (is_section_of(section, kind)) return kind;
  }
  return "";
}

StudyModels parse_models(const ini::Entry& entry) {
  for (const auto& [value, name] : model_names) {
    if (name == entry.value) return value;
  }
  fail(entry.where, "[study] models = '" + ini::printable(entry.value) +
                        "': must be soft, hard or both (both models from one settled bed, compared)");
}

/// The study file's sections: [study] and the sweeps, the frequency responses or the
/// characterisations, each once, and nothing before them.
void check_sections(const ini::Document& document) {
  std::map<std::string, int> seen;
  const ini::Section* first = nullptr;  // the first section of a kind
  for (const auto& section : document.sections) {
    const std::string kind = section_kind(section.name);
    if (section.name != "study" && kind.empty()) {
      fail(section.where, "unknown section [" + ini::printable(section.name) +
                              "]: a study file has [study] and one or more [sweep] or [sweep.NAME] sections, "
                              "[frf] or [frf.NAME] sections, or [characterise] or [characterise.NAME] sections "
                              "(NAME of letters, digits, _ and -)");
    }
    if (!kind.empty() && !first) first = &section;
    if (!kind.empty() && section_kind(first->name) != kind) {
      fail(section.where, "[" + section.name +
                              "]: a study has sections of one kind, [sweep], [frf] or "
                              "[characterise] ([" +
                              first->name +
                              "] is there too); for frequency responses over a grid of scenario keys, give "
                              "the keys several values in the [frf] section");
    }
    if (const auto [it, fresh] = seen.emplace(section.name, section.line); !fresh) {
      fail(section.where, "[" + section.name + "] appears twice (first on line " + std::to_string(it->second) + ")");
    }
  }
  if (!document.entries.empty() && document.entries.front().section.empty()) {
    const auto& entry = document.entries.front();
    fail(entry.where,
         "'" + ini::printable(entry.key) + " = " + ini::printable(entry.value) + "' comes before any [section] header");
  }
}

}  // namespace

StudyFile parse_study_file(const std::string& text, const std::string& origin, const std::string& default_name) {
  const ini::Document document = ini::parse(text, origin);
  check_sections(document);
  StudyFile study;
  study.name = default_name;
  std::map<std::string, int> given;  // [study] keys and their lines
  std::map<std::string, GridBuilder> builders;
  std::map<std::string, std::vector<ini::Entry>> frf_entries, characterise_entries;
  for (const auto& section : document.sections) {
    if (is_sweep_section(section.name)) builders.emplace(section.name, GridBuilder(section.name));
  }
  for (const auto& entry : document.entries) {
    if (is_frf_section(entry.section)) {
      frf_entries[entry.section].push_back(entry);
      continue;
    }
    if (is_characterise_section(entry.section)) {
      characterise_entries[entry.section].push_back(entry);
      continue;
    }
    if (entry.section != "study") {
      builders.at(entry.section).add(entry);
      continue;
    }
    if (const auto [it, fresh] = given.emplace(entry.key, entry.line); !fresh) {
      fail(entry.where, "[study] " + entry.key + " is given twice (first on line " + std::to_string(it->second) + ")");
    }
    if (entry.key == "name") {
      if (entry.value.empty()) fail(entry.where, "[study] name is empty");
      study.name = entry.value;
    } else if (entry.key == "scenario") {
      if (entry.value.empty()) fail(entry.where, "[study] scenario is empty: name the base scenario file");
      study.scenario = entry.value;
    } else if (entry.key == "models") {
      study.models = parse_models(entry);
    } else {
      fail(entry.where, "[study] has no key '" + ini::printable(entry.key) + "' (valid: name, scenario, models)");
    }
  }
  for (const char* key : {"scenario", "models"}) {
    if (!given.contains(key)) {
      throw InputError(origin + ": [study] " + key + " is missing" +
                       (std::string(key) == "scenario" ? " (the base scenario file, relative to the study file)"
                                                       : " (soft, hard or both)"));
    }
  }
  for (const auto& section : document.sections) {
    if (is_sweep_section(section.name)) {
      const GridBuilder& grid = builders.at(section.name);
      if (grid.empty()) fail(section.where, "[" + section.name + "] has no keys: give each key to vary its values");
      study.sweeps.push_back({section.name, grid.axes()});
    }
    if (is_frf_section(section.name)) study.frfs.push_back(parse_frf_section(section, frf_entries[section.name]));
    if (is_characterise_section(section.name)) {
      study.characterisations.push_back(parse_characterise_section(section, characterise_entries[section.name]));
    }
  }
  if (study.sweeps.empty() && study.frfs.empty() && study.characterisations.empty()) {
    throw InputError(origin +
                     ": no [sweep], [frf] or [characterise] section: a study varies at least one key, runs "
                     "frequency responses or characterises a damper");
  }
  return study;
}

}  // namespace pdamp::study
