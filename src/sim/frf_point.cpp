#include "pdamp/sim/frf_point.hpp"

#include <deque>
#include <numbers>
#include <vector>

namespace pdamp {

FrfPointOutcome run_frf_point(Engine& engine, const Scenario& scenario, const SteadyStateCriterion& criterion) {
  const auto wall_start = std::chrono::steady_clock::now();
  const FrfDrive drive = FrfDrive::of(scenario);
  const double period_s = 2.0 * std::numbers::pi / drive.omega_rad_s;
  Observation now = engine.observe();
  const double t0_s = now.t_s;
  int cycles = 0;
  // The last n + 1 cycle boundaries: the measured cycles if the point never settles.
  std::deque<Observation> recent{now};
  auto next_cycle = [&] {
    ++cycles;
    engine.advance_to(t0_s + cycles * period_s);
    const Observation before = now;
    now = engine.observe();
    recent.push_back(now);
    if (recent.size() > static_cast<std::size_t>(criterion.measured_cycles) + 1) recent.pop_front();
    return first_harmonics(before, now);
  };
  SteadyStateDetector detector(criterion);
  bool settled = false;
  while (!settled && cycles < criterion.max_cycles) settled = detector.add(next_cycle());
  FrfPointOutcome outcome;
  std::vector<Observation> measured;
  if (settled) {
    measured.push_back(now);
    const int cycles_to_steady = cycles;
    for (int k = 0; k < criterion.measured_cycles; ++k) {
      next_cycle();
      measured.push_back(now);
    }
    outcome.metrics = response_metrics(measured, drive, true, cycles_to_steady);
  } else {
    measured.assign(recent.begin(), recent.end());
    outcome.metrics = response_metrics(measured, drive, false, cycles - static_cast<int>(measured.size()) + 1);
  }
  outcome.cycles_run = cycles;
  outcome.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return outcome;
}

}  // namespace pdamp
