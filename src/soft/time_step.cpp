#include "pdamp/soft/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/model/host.hpp"

namespace pdamp::soft {

double hertz_contact_time_s(double effective_mass_kg, double kn_N_m1_5, double impact_speed_m_s) {
  const double max_overlap = std::pow(5.0 * effective_mass_kg * impact_speed_m_s * impact_speed_m_s / (4.0 * kn_N_m1_5), 0.4);
  return 2.9432 * max_overlap / impact_speed_m_s;
}

double max_impact_speed_m_s(const Scenario& scenario) {
  const HostModel host(scenario);
  const double host_speed = HostTrajectory(host, 0.0, host.initial_state()).speed_bound_m_s();
  return 2.0 * host_speed + std::sqrt(2.0 * scenario.gravity_m_s2.norm() * scenario.cavity.height_m);
}

double shortest_contact_time_s(const Scenario& scenario) {
  const auto& p = scenario.particles;
  const double lightest_kg = p.density_kg_m3 * std::numbers::pi / 6.0 * std::pow(p.diameter_min_m, 3);
  // A resting bed has no impacts; still, a contact must be resolved at some speed.
  const double speed = std::max(max_impact_speed_m_s(scenario), 1e-3);
  return std::min(hertz_contact_time_s(0.5 * lightest_kg, scenario.soft_particle.kn_N_m1_5, speed),
                  hertz_contact_time_s(lightest_kg, scenario.soft_wall.kn_N_m1_5, speed));
}

double choose_time_step_s(const Scenario& scenario) {
  const double contact = shortest_contact_time_s(scenario);
  if (!scenario.run.dt_s) return contact / steps_per_contact_auto;
  const double dt = *scenario.run.dt_s;
  if (dt > contact / steps_per_contact_minimum) {
    std::ostringstream msg;
    msg << "run.dt_s = " << dt << " s cannot resolve the shortest Hertz contact of this scenario (t_c = " << contact
        << " s at an impact speed of " << max_impact_speed_m_s(scenario) << " m/s); use run.dt_s <= "
        << contact / steps_per_contact_minimum << " s (t_c/10), or 'auto' (t_c/50 = " << contact / steps_per_contact_auto
        << " s)";
    throw InputError(msg.str());
  }
  return dt;
}

}  // namespace pdamp::soft
