/// libFuzzer target for the scenario loader and the checks a run makes before it starts
/// (tools/fuzz.sh runs it; .ci/run for a fixed budget). The input is a scenario file's
/// text, optionally followed by a NUL and --set overrides separated by NULs (a file with a
/// NUL is refused, so the separator cannot hide a case). Whatever the bytes, the loader
/// gives a scenario or an InputError; a scenario's canonical text loads back to the same
/// scenario; the run budget, the time step and, for small fills, the placement finish
/// without crashing, hanging or allocating without bound (-timeout, -rss_limit_mb).

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "pdamp/errors.hpp"
#include "pdamp/model/placement.hpp"
#include "pdamp/model/scenario_loader.hpp"
#include "pdamp/sim/run_budget.hpp"
#include "pdamp/soft/time_step.hpp"

namespace {

/// Fills small enough to place within the fuzzer's time per input.
constexpr int largest_fill_placed = 2000;

void check(const pdamp::Scenario& s) {
  using namespace pdamp;
  if (parse_scenario(s.canonical_text, s.name, "canonical text").canonical_text != s.canonical_text) std::abort();
  for (const Model model : {Model::soft, Model::hard}) {
    try {
      check_run_budget(model, s);
    } catch (const InputError&) {
      return;
    }
  }
  if (s.particles.count > 0) (void)soft::describe_time_step(s);
  if (s.particles.count <= largest_fill_placed) {
    if (place_particles(s.particles, s.cavity, 0.0).size() != s.particles.count) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  const auto end_of_text = std::min(input.find('\0'), input.size());
  pdamp::ScenarioOverrides overrides;
  for (std::size_t start = end_of_text + 1; start <= input.size() && end_of_text < input.size();) {
    const auto end = std::min(input.find('\0', start), input.size());
    overrides.emplace_back(input.substr(start, end - start));
    start = end + 1;
  }
  try {
    check(pdamp::parse_scenario(std::string(input.substr(0, end_of_text)), "fuzz", "fuzz input", overrides));
  } catch (const pdamp::InputError&) {
    // Refused with a message: what the loader is for.
  }
  return 0;
}
