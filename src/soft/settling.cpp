#include "pdamp/soft/settling.hpp"

#include <cmath>
#include <sstream>

#include "pdamp/errors.hpp"
#include "soft/soft_engine_class.hpp"

namespace pdamp::soft {

SettledBed settle_bed(const Scenario& scenario, const Particles& placement, const std::atomic<bool>* stop,
                      const std::function<void(double, double)>& progress) {
  const double g = scenario.gravity_m_s2.norm();
  if (g == 0.0 || placement.size() == 0) return {placement, 0.0, 0.0, 0};

  const auto n = static_cast<double>(placement.size());
  const double mean_mass = placement.total_mass_kg() / n;
  const double mean_diameter = 2.0 * placement.radius_m.mean();
  const double threshold_J = settled_energy_fraction * mean_mass * g * mean_diameter * n;
  const double fall_time_s = settling_fall_time_s(scenario);

  SoftEngineOptions options;
  options.hold_host = true;
  options.settling_drag_1_s = 1.0 / fall_time_s;
  SoftEngine engine(scenario, placement, options);
  engine.set_stop_request(stop);
  for (double t = settling_check_interval_s;; t += settling_check_interval_s) {
    try {
      engine.advance_to(t);
    } catch (const Interrupted&) {
      throw Interrupted("stopped while settling the bed");
    }
    const double kinetic = engine.particle_kinetic_J();
    if (progress) progress(t, kinetic);
    if (t >= fall_time_s && kinetic < threshold_J) {
      return {engine.state().particles, t, kinetic, *engine.observe().counters.time_steps};
    }
    if (t >= settling_time_limit_s) {
      std::ostringstream msg;
      msg << "the bed did not come to rest in " << settling_time_limit_s << " s of settling: its kinetic energy is "
          << kinetic << " J, above the threshold " << threshold_J << " J";
      throw RuntimeFailure(msg.str());
    }
  }
}

}  // namespace pdamp::soft
