#include "pdamp/soft/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/model/host.hpp"

namespace pdamp::soft {

double hertz_contact_time_s(double effective_mass_kg, double kn_N_m1_5, double impact_speed_m_s) {
  const double max_overlap =
      std::pow(5.0 * effective_mass_kg * impact_speed_m_s * impact_speed_m_s / (4.0 * kn_N_m1_5), 0.4);
  return 2.9432 * max_overlap / impact_speed_m_s;
}

double max_impact_speed_m_s(const Scenario& scenario) {
  const HostModel host(scenario);
  const double host_speed = HostTrajectory(host, 0.0, host.initial_state()).speed_bound_m_s();
  return 2.0 * host_speed + std::sqrt(2.0 * scenario.gravity_m_s2.norm() * scenario.cavity.height_m);
}

namespace {

double lightest_sphere_kg(const Scenario& scenario) {
  const auto& p = scenario.particles;
  return p.density_kg_m3 * std::numbers::pi / 6.0 * std::pow(p.diameter_min_m, 3);
}

double tangential_period_s(double effective_mass_kg, double ks_N_m) {
  return ks_N_m > 0.0 ? 2.0 * std::numbers::pi * std::sqrt(effective_mass_kg / ks_N_m)
                      : std::numeric_limits<double>::infinity();
}

}  // namespace

double shortest_tangential_period_s(const Scenario& scenario) {
  const double m = lightest_sphere_kg(scenario);
  return std::min(tangential_period_s(m / 7.0, scenario.soft_particle.ks_N_m),
                  tangential_period_s(2.0 * m / 7.0, scenario.soft_wall.ks_N_m));
}

double shortest_contact_time_s(const Scenario& scenario) {
  const double lightest_kg = lightest_sphere_kg(scenario);
  // A resting bed has no impacts; still, a contact must be resolved at some speed.
  const double speed = std::max(max_impact_speed_m_s(scenario), 1e-3);
  return std::min(hertz_contact_time_s(0.5 * lightest_kg, scenario.soft_particle.kn_N_m1_5, speed),
                  hertz_contact_time_s(lightest_kg, scenario.soft_wall.kn_N_m1_5, speed));
}

double choose_time_step_s(const Scenario& scenario) {
  const double contact = shortest_contact_time_s(scenario);
  const double tangential = shortest_tangential_period_s(scenario);
  const double automatic = std::min(contact / steps_per_contact_auto, tangential / steps_per_tangential_period_auto);
  if (!scenario.run.dt_s) return automatic;
  const double dt = *scenario.run.dt_s;
  const double limit = std::min(contact / steps_per_contact_minimum, tangential / steps_per_tangential_period_minimum);
  if (dt > limit) {
    std::ostringstream msg;
    msg << "run.dt_s = " << dt << " s is too long: the shortest Hertz contact of this scenario lasts t_c = " << contact
        << " s (impact speed " << max_impact_speed_m_s(scenario) << " m/s) and a sticking contact's tangential "
        << "spring oscillates with period T_s = " << tangential << " s; use run.dt_s <= " << limit
        << " s (min(t_c/10, T_s/4)), or 'auto' (" << automatic << " s)";
    throw InputError(msg.str());
  }
  return dt;
}

}  // namespace pdamp::soft
