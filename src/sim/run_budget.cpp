#include "pdamp/sim/run_budget.hpp"

#include <cmath>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/sim/run.hpp"
#include "pdamp/soft/settling.hpp"
#include "pdamp/soft/time_step.hpp"

namespace pdamp {
namespace {

/// Refuses `needed` of what `key` bounds, saying what needs that many.
void require_within(const char* key, std::int64_t bound, double needed, const std::string& what, const char* unit) {
  if (needed <= static_cast<double>(bound)) return;
  std::ostringstream msg;
  msg.precision(3);
  msg << key << " = " << bound << ": " << what << " would take " << needed << " " << unit << "; raise " << key
      << " if that is meant, or change what makes them so many";
  throw InputError(msg.str());
}

}  // namespace

void check_run_budget(Model model, const Scenario& scenario) {
  const RunSettings& run = scenario.run;
  const double samples = std::ceil(run.duration_s / run.sample_interval_s);
  std::ostringstream sampled;
  sampled << "run.duration_s = " << run.duration_s
          << " s sampled every run.sample_interval_s = " << run.sample_interval_s << " s";
  require_within("run.max_samples", run.max_samples, samples + 1.0, sampled.str(), "samples");

  const double interval = observation_interval_s(scenario);
  const double observations = samples * std::ceil(run.sample_interval_s / interval - 1e-9);
  std::ostringstream observed;
  observed << "observing the run every " << interval
           << " s (at every sample, and 256 times per period of the host or the excitation) over " << run.duration_s
           << " s";
  require_within("run.max_steps", run.max_steps, observations, observed.str(), "steps");

  if (scenario.particles.count == 0) return;
  const double dt = soft::choose_time_step_s(scenario);
  const std::string step = "in time steps of " + soft::describe_time_step(scenario);
  if (scenario.gravity_m_s2.norm() > 0.0) {
    std::ostringstream settling;
    settling << "settling the bed, for up to " << soft::settling_time_limit_s << " s of simulated time " << step << ",";
    require_within("run.max_steps", run.max_steps, soft::settling_time_limit_s / dt, settling.str(), "steps");
  }
  if (model == Model::soft) {
    std::ostringstream soft_run;
    soft_run << "the soft model's run of " << run.duration_s << " s " << step << ",";
    require_within("run.max_steps", run.max_steps, run.duration_s / dt + observations, soft_run.str(), "steps");
  }
}

}  // namespace pdamp
