#include "pdamp/sim/run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <optional>
#include <sstream>

#include "pdamp/analysis/cycle_analyzer.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/sim/run_checkpoint.hpp"

namespace pdamp {

CycleAnalyzer make_cycle_analyzer(const Scenario& scenario, const Particles& bed) {
  const double g_z = scenario.gravity_m_s2.z();
  const double equilibrium_z =
      scenario.host_has_infinite_mass() ? 0.0 : bed.total_mass_kg() * g_z / scenario.host.stiffness_N_m;
  return CycleAnalyzer(scenario.host.mass_kg, equilibrium_z, std::abs(g_z));
}

namespace {

/// Ends the run as failed if the engine's state is no longer finite: either engine's
/// particles enter the energies, and the host its position and speed.
void require_finite(const Observation& o) {
  const EnergyLedger& e = o.energy;
  const double values[] = {o.host.z_m, o.host.v_m_s, e.stored_J(), e.dissipated_J(), e.excitation_work_J};
  if (std::all_of(std::begin(values), std::end(values), [](double x) { return std::isfinite(x); })) return;
  std::ostringstream why;
  why << "the state stopped being finite at t = " << o.t_s << " s (host at " << o.host.z_m << " m, " << o.host.v_m_s
      << " m/s; stored energy " << e.stored_J() << " J, dissipated " << e.dissipated_J() << " J)";
  throw RuntimeFailure(why.str());
}

}  // namespace

RunOutcome run_simulation(Engine& engine, const Scenario& scenario, RunRecorder& recorder, const RunControl& control,
                          const RunLoopState* resume) {
  using clock = std::chrono::steady_clock;
  const auto wall_start = clock::now();
  auto next_progress = wall_start;
  const bool checkpoints = control.checkpoint_interval.count() > 0;
  auto next_checkpoint = wall_start + control.checkpoint_interval;
  RunOutcome outcome;
  double wall_before_s = 0.0;  // of the processes that ran it before this one
  const double duration = scenario.run.duration_s;
  const ObservationGrid grid = observation_grid(scenario);
  const std::int64_t observations_per_sample = grid.steps_per_sample;

  auto interrupted = [&] {
    outcome.status = RunStatus::interrupted;
    outcome.message = "stopped by a signal at t = " + std::to_string(outcome.sim_time_s) + " s";
  };
  auto wall_time_s = [&] { return wall_before_s + std::chrono::duration<double>(clock::now() - wall_start).count(); };
  // The checkpoint to store with the results when the run completes: its last state, or
  // the one before a last step that ends off the grid (another run, longer, never stops there).
  std::optional<RunCheckpoint> last_checkpoint;
  engine.set_stop_request(control.stop, checkpoints ? control.stop_grace : std::chrono::milliseconds{0});
  try {
    CycleAnalyzer cycles = resume ? resume->cycles : make_cycle_analyzer(scenario, engine.state().particles);
    Observation now = engine.observe();
    require_finite(now);
    auto record = [&](bool is_sample) {
      const double error = now.energy.balance_relative_error(outcome.initial_energy_J);
      outcome.energy_balance_rel_err = std::max(outcome.energy_balance_rel_err, error);
      if (const auto cycle = cycles.feed(now)) {
        recorder.record_cycle(*cycle);
        ++outcome.cycles;
      }
      if (is_sample) {
        recorder.record_sample(now, error);
        ++outcome.samples;
      }
      outcome.sim_time_s = now.t_s;
    };
    auto checkpoint = [&](std::int64_t k, std::int64_t j) {
      RunLoopState state{k, j, outcome, cycles};
      state.outcome.wall_time_s = wall_time_s();
      return save_checkpoint(state, engine, now.t_s);
    };
    std::int64_t k0 = 0, j0 = 0;
    if (resume) {
      outcome = resume->outcome;
      wall_before_s = resume->outcome.wall_time_s;
      k0 = resume->interval;
      j0 = resume->step;
    } else {
      outcome.initial_energy_J = now.energy.stored_J();
      record(true);
      if (control.at_observation) control.at_observation(engine, {0, true});
    }
    for (std::int64_t k = k0; now.t_s < duration; ++k) {
      for (std::int64_t j = k == k0 ? j0 + 1 : 1; j <= observations_per_sample && now.t_s < duration; ++j) {
        const double t = grid.time_s(k * observations_per_sample + j);
        const double target = std::min(t, duration);
        if (checkpoints && target < t) last_checkpoint = checkpoint(k, j - 1);
        engine.advance_to(target);
        now = engine.observe();
        require_finite(now);
        record(j == observations_per_sample || target == duration);
        if (control.at_observation) {
          control.at_observation(engine, {k * observations_per_sample + j, t - target <= 1e-9 * grid.step_s});
        }
        const bool stop = control.stop && control.stop->load();
        if (checkpoints && target == t && (stop || now.t_s >= duration || clock::now() >= next_checkpoint)) {
          last_checkpoint = checkpoint(k, j);
          if (now.t_s < duration) {
            recorder.flush_with_checkpoint(*last_checkpoint);
            next_checkpoint = clock::now() + control.checkpoint_interval;
          }
        }
        if (stop) {
          interrupted();
          break;
        }
        if (control.progress && clock::now() >= next_progress) {
          control.progress(now.t_s);
          next_progress = clock::now() + std::chrono::milliseconds(500);
        }
      }
      if (outcome.status == RunStatus::interrupted) break;
    }
  } catch (const Interrupted&) {
    interrupted();  // inside the engine: the last observation stands, the last checkpoint before it
    last_checkpoint.reset();
  } catch (const std::exception& e) {
    outcome.status = RunStatus::failed;
    outcome.message = e.what();
    last_checkpoint.reset();
  }
  try {
    if (last_checkpoint) {
      recorder.flush_with_checkpoint(*last_checkpoint);
    } else {
      recorder.flush();
    }
  } catch (const std::exception& e) {
    outcome.status = RunStatus::failed;
    outcome.message += (outcome.message.empty() ? "" : "; ") + std::string("results not all stored: ") + e.what();
  }
  outcome.wall_time_s = wall_time_s();
  return outcome;
}

}  // namespace pdamp
