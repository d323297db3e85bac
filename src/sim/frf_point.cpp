#include "pdamp/sim/frf_point.hpp"

#include <cmath>
#include <deque>
#include <numbers>
#include <vector>

namespace pdamp {

FrfPointOutcome run_frf_point(Engine& engine, const Scenario& scenario, const SteadyStateCriterion& criterion,
                              const std::function<void(const Observation&)>& at_boundary) {
  const auto wall_start = std::chrono::steady_clock::now();
  const FrfDrive drive = FrfDrive::of(scenario);
  const double period_s = 2.0 * std::numbers::pi / drive.omega_rad_s;
  Observation now = engine.observe();
  const double t0_s = now.t_s;
  if (at_boundary) at_boundary(now);
  int cycles = 0;
  // The last n + 1 cycle boundaries: the measured cycles if the point never settles.
  std::deque<Observation> recent{now};
  auto next_cycle = [&] {
    ++cycles;
    engine.advance_to(t0_s + cycles * period_s);
    const Observation before = now;
    now = engine.observe();
    if (at_boundary) at_boundary(now);
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

RunOutcome run_frf_simulation(Engine& engine, const Scenario& scenario, RunRecorder& recorder,
                              const RunControl& control, const SteadyStateCriterion& criterion, FrfRun& result) {
  using clock = std::chrono::steady_clock;
  const auto wall_start = clock::now();
  auto next_progress = wall_start;
  RunOutcome outcome;
  engine.set_stop_request(control.stop);
  bool first = true;
  auto at_boundary = [&](const Observation& now) {
    if (first) outcome.initial_energy_J = now.energy.stored_J();
    first = false;
    const double error = now.energy.balance_relative_error(outcome.initial_energy_J);
    if (!std::isfinite(now.host.z_m) || !std::isfinite(now.host.v_m_s) || !std::isfinite(error)) {
      throw RuntimeFailure("the state stopped being finite at t = " + std::to_string(now.t_s) + " s");
    }
    outcome.energy_balance_rel_err = std::max(outcome.energy_balance_rel_err, error);
    recorder.record_sample(now, error);
    ++outcome.samples;
    outcome.sim_time_s = now.t_s;
    if (control.progress && clock::now() >= next_progress) {
      control.progress(now.t_s);
      next_progress = clock::now() + std::chrono::milliseconds(500);
    }
  };
  try {
    result.point = run_frf_point(engine, scenario, criterion, at_boundary);
    result.final_state = engine.state();
  } catch (const Interrupted&) {
    outcome.status = RunStatus::interrupted;
    outcome.message = "stopped by a signal at t = " + std::to_string(outcome.sim_time_s) + " s";
  } catch (const std::exception& e) {
    outcome.status = RunStatus::failed;
    outcome.message = e.what();
  }
  try {
    recorder.flush();
  } catch (const std::exception& e) {
    outcome.status = RunStatus::failed;
    outcome.message += (outcome.message.empty() ? "" : "; ") + std::string("results not all stored: ") + e.what();
  }
  outcome.wall_time_s = std::chrono::duration<double>(clock::now() - wall_start).count();
  return outcome;
}

}  // namespace pdamp
