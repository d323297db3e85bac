#pragma once
/// Helpers shared by the tests.

#include <filesystem>
#include <string>
#include <unistd.h>

#include "pdamp/scenario/scenario_loader.hpp"

namespace pdamp::test {

inline std::filesystem::path source_dir() { return PDAMP_SOURCE_DIR; }
inline std::filesystem::path scenario_file(const std::string& name) {
  return source_dir() / "data" / "scenarios" / (name + ".ini");
}

/// A scenario from inline text (every unspecified key takes its default).
inline Scenario scenario_from(const std::string& text, const ScenarioOverrides& overrides = {}) {
  return parse_scenario(text, "test", "test scenario", overrides);
}

/// A fresh directory under the build tree's temporary folder, removed when destroyed.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() / ("pdamp-test-" + name + "-" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& file) const { return path_ / file; }

 private:
  std::filesystem::path path_;
};

}  // namespace pdamp::test
