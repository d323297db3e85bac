#include "pdamp/soft/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/model/host.hpp"
#include "pdamp/soft/settling.hpp"

namespace pdamp::soft {

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

Relaxation shortest_relaxation(const Scenario& scenario) {
  Relaxation shortest{std::numeric_limits<double>::infinity(), "no dashpot"};
  auto consider = [&](double time_s, const char* what) {
    if (time_s < shortest.time_s) shortest = {time_s, what};
  };
  auto mass_over = [](double mass_kg, double damping_N_s_m) {
    return damping_N_s_m > 0.0 ? mass_kg / damping_N_s_m : std::numeric_limits<double>::infinity();
  };
  const double m = lightest_sphere_kg(scenario);
  consider(mass_over(0.5 * m, scenario.soft_particle.cn_N_s_m), "the sphere-sphere normal dashpot soft.cn_N_s_m");
  consider(mass_over(m, scenario.soft_wall.cn_N_s_m), "the sphere-wall normal dashpot soft_wall.cn_N_s_m");
  consider(mass_over(m / 7.0, scenario.soft_particle.cs_N_s_m), "the sphere-sphere tangential dashpot soft.cs_N_s_m");
  consider(mass_over(2.0 * m / 7.0, scenario.soft_wall.cs_N_s_m),
           "the sphere-wall tangential dashpot soft_wall.cs_N_s_m");
  if (!scenario.host_has_infinite_mass()) {
    consider(mass_over(scenario.host.mass_kg, scenario.host.damping_N_s_m), "the host's damper host.damping_N_s_m");
  }
  if (scenario.gravity_m_s2.norm() > 0.0) {
    consider(settling_fall_time_s(scenario), "the settling drag (from cavity.height_m and gravity.g_m_s2)");
  }
  return shortest;
}

namespace {

/// The three criteria and the step each allows, automatic and at most.
struct Criteria {
  double contact_s, tangential_s;
  Relaxation relaxation;
  explicit Criteria(const Scenario& scenario)
      : contact_s(shortest_contact_time_s(scenario)),
        tangential_s(shortest_tangential_period_s(scenario)),
        relaxation(shortest_relaxation(scenario)) {}
  double automatic_s() const {
    return std::min(std::min(contact_s / steps_per_contact_auto, tangential_s / steps_per_tangential_period_auto),
                    relaxation.time_s / steps_per_relaxation_auto);
  }
  double limit_s() const {
    return std::min({contact_s / steps_per_contact_minimum, tangential_s / steps_per_tangential_period_minimum,
                     relaxation.time_s / steps_per_relaxation_minimum});
  }
};

}  // namespace

double choose_time_step_s(const Scenario& scenario) {
  const Criteria c(scenario);
  const double automatic = c.automatic_s();
  if (!scenario.run.dt_s) return automatic;
  const double dt = *scenario.run.dt_s;
  const double limit = c.limit_s();
  if (dt > limit) {
    std::ostringstream msg;
    msg << "run.dt_s = " << dt
        << " s is too long: the shortest Hertz contact of this scenario lasts t_c = " << c.contact_s
        << " s (impact speed " << max_impact_speed_m_s(scenario) << " m/s), a sticking contact's "
        << "tangential spring oscillates with period T_s = " << c.tangential_s << " s, and " << c.relaxation.what
        << " relaxes in tau = m/c = " << c.relaxation.time_s << " s; use run.dt_s <= " << limit
        << " s (min(t_c/10, T_s/4, tau/2)), or 'auto' (" << automatic << " s)";
    throw InputError(msg.str());
  }
  return dt;
}

std::string describe_time_step(const Scenario& scenario) {
  const Criteria c(scenario);
  std::ostringstream out;
  out << choose_time_step_s(scenario) << " s (";
  if (scenario.run.dt_s) {
    out << "given; at most " << c.limit_s();
  } else {
    const double automatic = c.automatic_s();
    out << "automatic: "
        << (automatic == c.relaxation.time_s / steps_per_relaxation_auto ? "tau/10"
            : automatic == c.contact_s / steps_per_contact_auto          ? "t_c/50"
                                                                         : "T_s/8");
  }
  out << "); shortest Hertz contact t_c = " << c.contact_s << " s at the fastest impact, "
      << max_impact_speed_m_s(scenario) << " m/s; tangential spring period T_s = " << c.tangential_s
      << " s; shortest dashpot relaxation tau = m/c = " << c.relaxation.time_s << " s, " << c.relaxation.what;
  return out.str();
}

}  // namespace pdamp::soft
