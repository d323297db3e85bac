#include "pdamp/sim/frf_point.hpp"

#include <cmath>
#include <deque>
#include <numbers>
#include <vector>

#include "pdamp/errors.hpp"
#include "pdamp/model/cavity.hpp"
#include "pdamp/sim/run_checkpoint.hpp"

namespace pdamp {

SteadyCycles run_to_steady_state(Engine& engine, double omega_rad_s, const SteadyStateCriterion& criterion,
                                 SteadyWatch watch, CycleLog& log, const CycleHooks& hooks) {
  const auto wall_start = std::chrono::steady_clock::now();
  const double period_s = 2.0 * std::numbers::pi / omega_rad_s;
  const std::size_t logged = log.boundaries.size();  // of a point resumed: its cycles so far
  auto boundary = [&] {
    log.boundaries.push_back(engine.observe());
    if (hooks.at_boundary) hooks.at_boundary(log.boundaries.back());
    return log.boundaries.back();
  };
  Observation now = logged > 0 ? log.boundaries.front() : boundary();
  const double t0_s = now.t_s;
  int cycles = 0;
  // The last n + 1 cycle boundaries: the measured cycles if the point never settles.
  std::deque<Observation> recent{now};
  auto next_cycle = [&] {
    ++cycles;
    const Observation before = now;
    if (static_cast<std::size_t>(cycles) < logged) {
      now = log.boundaries[static_cast<std::size_t>(cycles)];
    } else {
      const double t_end_s = t0_s + cycles * period_s;
      if (hooks.advance_cycle) {
        hooks.advance_cycle(engine, t_end_s);
      } else {
        engine.advance_to(t_end_s);
      }
      now = boundary();
    }
    recent.push_back(now);
    if (recent.size() > static_cast<std::size_t>(criterion.measured_cycles) + 1) recent.pop_front();
    return first_harmonics(before, now);
  };
  SteadyStateDetector detector(criterion, watch);
  bool settled = false;
  while (!settled && cycles < criterion.max_cycles) settled = detector.add(next_cycle());
  SteadyCycles run;
  run.settled = settled;
  if (settled) {
    run.measured.push_back(now);
    run.cycles_to_steady = cycles;
    for (int k = 0; k < criterion.measured_cycles; ++k) {
      next_cycle();
      run.measured.push_back(now);
    }
  } else {
    run.measured.assign(recent.begin(), recent.end());
    run.cycles_to_steady = cycles - static_cast<int>(run.measured.size()) + 1;
  }
  run.cycles_run = cycles;
  run.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return run;
}

FrfPointOutcome run_frf_point(Engine& engine, const Scenario& scenario, const SteadyStateCriterion& criterion,
                              const std::function<void(const Observation&)>& at_boundary, CycleLog* log) {
  const FrfDrive drive = FrfDrive::of(scenario);
  CycleLog own;
  const SteadyCycles run = run_to_steady_state(engine, drive.omega_rad_s, criterion, SteadyWatch::displacement,
                                               log ? *log : own, {at_boundary, {}});
  return {response_metrics(run.measured, drive, run.settled, run.cycles_to_steady), run.cycles_run, run.wall_time_s};
}

namespace {

/// A point's cycles as a stored run: one sample per boundary, its energy balance checked,
/// the control's stop, progress and checkpoints; `body` runs the point with the boundary
/// hook and the cycle log given (from `resume`'s if resumed).
template <typename Body>
RunOutcome run_cycles_simulation(Engine& engine, RunRecorder& recorder, const RunControl& control,
                                 const CycleLoopState* resume, Body&& body) {
  using clock = std::chrono::steady_clock;
  const auto wall_start = clock::now();
  auto next_progress = wall_start;
  auto next_checkpoint = wall_start + control.checkpoint_interval;
  const bool checkpoints = control.checkpoint_interval.count() > 0;
  CycleLoopState state = resume ? *resume : CycleLoopState{};
  RunOutcome& outcome = state.outcome;
  const double wall_before_s = outcome.wall_time_s;  // of the processes that ran it before this one
  auto wall_time_s = [&] { return wall_before_s + std::chrono::duration<double>(clock::now() - wall_start).count(); };
  engine.set_stop_request(control.stop, checkpoints ? control.stop_grace : std::chrono::milliseconds{0});
  auto at_boundary = [&](const Observation& now) {
    if (outcome.samples == 0) outcome.initial_energy_J = now.energy.stored_J();
    const double error = now.energy.balance_relative_error(outcome.initial_energy_J);
    if (!std::isfinite(now.host.z_m) || !std::isfinite(now.host.v_m_s) || !std::isfinite(error)) {
      throw RuntimeFailure("the state stopped being finite at t = " + std::to_string(now.t_s) + " s");
    }
    outcome.energy_balance_rel_err = std::max(outcome.energy_balance_rel_err, error);
    recorder.record_sample(now, error);
    ++outcome.samples;
    outcome.sim_time_s = now.t_s;
    // The loop observes the engine at its cycle boundaries only: observation step k is the
    // end of cycle k (snapshots: cycle_frames).
    if (control.at_observation) control.at_observation(engine, {outcome.samples - 1, true});
    const bool stop = control.stop && control.stop->load();
    if (checkpoints && (stop || clock::now() >= next_checkpoint)) {
      CycleLoopState saved{outcome, state.log};
      saved.outcome.wall_time_s = wall_time_s();
      recorder.flush_with_checkpoint(save_checkpoint(saved, engine, now.t_s));
      next_checkpoint = clock::now() + control.checkpoint_interval;
    }
    if (stop) throw Interrupted("stopped");  // the message is the run loop's, below
    if (control.progress && clock::now() >= next_progress) {
      control.progress(now.t_s);
      next_progress = clock::now() + std::chrono::milliseconds(500);
    }
  };
  try {
    body(std::function<void(const Observation&)>(at_boundary), state.log);
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
  outcome.wall_time_s = wall_time_s();
  return outcome;
}

/// Whether a sphere touches the floor, and the lid: within a thousandth of its radius of
/// it (a soft contact overlaps, a hard sphere at rest sits at the wall to rounding; one in
/// flight that close meets the wall within microseconds, far below 1/64 of a cycle).
struct WallTouch {
  bool floor = false, lid = false;
};
WallTouch wall_touch(const State& state, const Cavity& cavity) {
  WallTouch touch;
  const Particles& p = state.particles;
  const double z_host_m = state.observation.host.z_m;
  for (Eigen::Index i = 0; i < p.size() && !(touch.floor && touch.lid); ++i) {
    const Eigen::Vector3d centre = p.position_m.col(i);
    const double slack_m = 1e-3 * p.radius_m[i];
    touch.floor = touch.floor || cavity.bottom(centre, p.radius_m[i], z_host_m).gap_m <= slack_m;
    touch.lid = touch.lid || cavity.top(centre, p.radius_m[i], z_host_m).gap_m <= slack_m;
  }
  return touch;
}

}  // namespace

double cycle_period_s(const Scenario& scenario) {
  return 2.0 * std::numbers::pi / scenario.excitation.angular_frequency_rad_s();
}

RunOutcome run_frf_simulation(Engine& engine, const Scenario& scenario, RunRecorder& recorder,
                              const RunControl& control, const SteadyStateCriterion& criterion, FrfRun& result,
                              const CycleLoopState* resume) {
  return run_cycles_simulation(engine, recorder, control, resume,
                               [&](const std::function<void(const Observation&)>& hook, CycleLog& log) {
                                 result.point = run_frf_point(engine, scenario, criterion, hook, &log);
                                 result.final_state = engine.state();
                               });
}

CharacterisationPointOutcome run_characterisation_point(Engine& engine, const Scenario& scenario,
                                                        const SteadyStateCriterion& criterion,
                                                        const std::function<void(const Observation&)>& at_boundary,
                                                        CycleLog* log) {
  const ExcitationSettings& e = scenario.excitation;
  if (e.mode != ExcitationMode::prescribed_motion) {
    throw InputError("a characterisation point needs excitation.mode = prescribed");
  }
  const double omega_rad_s = e.angular_frequency_rad_s(), period_s = cycle_period_s(scenario);
  const Cavity cavity(scenario.cavity);
  // Each cycle's instants touching the floor and the lid; the measured cycles are the last.
  CycleLog own;
  CycleLog& cycles = log ? *log : own;
  std::vector<WallTouches>& touches = cycles.touches;
  CycleHooks hooks{at_boundary, [&](Engine& engine_, double t_end_s) {
                     const double t_start_s = t_end_s - period_s;
                     WallTouches count;
                     for (int k = 1; k <= contact_instants_per_cycle; ++k) {
                       engine_.advance_to(k == contact_instants_per_cycle
                                              ? t_end_s
                                              : t_start_s + period_s * k / contact_instants_per_cycle);
                       const WallTouch touch = wall_touch(engine_.state(), cavity);
                       count.floor += touch.floor ? 1 : 0;
                       count.lid += touch.lid ? 1 : 0;
                     }
                     touches.push_back(count);
                   }};
  const SteadyCycles run = run_to_steady_state(engine, omega_rad_s, criterion, SteadyWatch::load, cycles, hooks);
  const double particle_mass_kg = engine.state().particles.total_mass_kg();
  CharacterisationPointOutcome outcome{characterisation_metrics(run.measured, omega_rad_s, scenario.gravity_m_s2.norm(),
                                                                particle_mass_kg, run.settled, run.cycles_to_steady),
                                       run.cycles_run, run.wall_time_s};
  const auto n = static_cast<std::size_t>(outcome.metrics.measured_cycles);
  int floor = 0, lid = 0;
  for (std::size_t k = touches.size() - n; k < touches.size(); ++k) {
    floor += touches[k].floor;
    lid += touches[k].lid;
  }
  const double instants = static_cast<double>(n) * contact_instants_per_cycle;
  outcome.metrics.floor_contact_fraction = floor / instants;
  outcome.metrics.lid_contact_fraction = lid / instants;
  return outcome;
}

RunOutcome run_characterisation_simulation(Engine& engine, const Scenario& scenario, RunRecorder& recorder,
                                           const RunControl& control, const SteadyStateCriterion& criterion,
                                           CharacterisationRun& result, const CycleLoopState* resume) {
  return run_cycles_simulation(engine, recorder, control, resume,
                               [&](const std::function<void(const Observation&)>& hook, CycleLog& log) {
                                 result.point = run_characterisation_point(engine, scenario, criterion, hook, &log);
                                 result.final_state = engine.state();
                               });
}

}  // namespace pdamp
