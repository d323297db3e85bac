#pragma once
/// A grid of scenario keys from a section's lines: each key with its values (a list and/or
/// ranges, parse_sweep_values), `zip = KEY KEY ...` lines naming keys that vary together.
/// A [sweep] section is such a grid; so are the scenario keys of an [frf] section
/// (frf_section.cpp). Every mistake is refused with its line.

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "pdamp/scenario/ini.hpp"
#include "pdamp/study/study_file.hpp"

namespace pdamp::study {

class GridBuilder {
 public:
  /// `also_refused` says why a scenario key may not be in this grid, or nothing if it may.
  explicit GridBuilder(std::string section,
                       std::function<std::optional<std::string>(const std::string&)> also_refused = {})
      : section_(std::move(section)), also_refused_(std::move(also_refused)) {}

  /// A key's line (its values), or a `zip` line. Throws InputError naming the line: a key
  /// that is not a scenario key or is given twice, a bad value list, a bad zip.
  void add(const ini::Entry& entry);

  /// Whether no key was given.
  bool empty() const { return keys_.empty(); }

  /// The axes, in the order of their keys' lines (a zip's at its first key's line), each
  /// key's values checked for duplicates and zipped keys for equal counts. Throws
  /// InputError naming the line.
  std::vector<SweepAxis> axes() const;

 private:
  struct Key {
    std::string key;
    int line;
    std::string where;
    std::vector<std::string> values;
  };
  struct Zip {
    std::vector<std::string> keys;
    int line;
    std::string where;
  };

  void add_zip(const ini::Entry& entry);
  std::optional<std::size_t> zip_of(const std::string& key) const;
  const Key& key_named(const std::string& name, const Zip& zip) const;
  SweepAxis single_axis(const Key& k) const;
  SweepAxis zipped_axis(const Zip& zip) const;

  /// Why a key may be a scenario key and still not be in the grid, or nothing.
  std::optional<std::string> refused(const std::string& key) const;

  std::string section_;
  std::function<std::optional<std::string>(const std::string&)> also_refused_;
  std::vector<Key> keys_;
  std::vector<Zip> zips_;
};

}  // namespace pdamp::study
