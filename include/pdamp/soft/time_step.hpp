#pragma once
/// The soft engine's time step. A Hertz contact f = k_n δ^{3/2} between bodies of
/// effective mass m* hit at speed v lasts t_c = 2.9432 δ_max / v with
/// δ_max = (5 m* v² / 4 k_n)^{2/5} (the dashpot only shortens it). The step must resolve
/// the shortest contact the scenario can produce: the lightest pair, the stiffest law,
/// the fastest impact.
///
/// Fastest impact: a sphere launched at the host's top speed meeting a cap that moves the
/// other way at that speed, plus a fall through the whole cavity:
///   v_max = 2 V_host + sqrt(2 |g| H),
/// with V_host the bound on the host's speed from its initial condition and excitation
/// (HostTrajectory::speed_bound_m_s).
///
/// The tangential spring must be resolved too. A sticking contact makes the contact
/// points oscillate with period T_s = 2π sqrt(m_t / k_s), where m_t, the effective mass
/// of the points' relative motion with both spheres free to turn, is m/7 for a pair of
/// equal spheres (2m/7 against a wall). The paper's k_s is stiff: for its 0.88 mm lead
/// spheres T_s = 7.4 µs, shorter than t_c/10 — its own Δt = 2.5 µs is past velocity
/// Verlet's stability limit T_s/π for such a pair.
///
/// `auto` picks Δt = min(t_c(v_max)/50, T_s/8); a given Δt above t_c(v_max)/10 or T_s/4
/// is refused.

#include "pdamp/scenario/scenario.hpp"

namespace pdamp::soft {

constexpr double steps_per_contact_auto = 50.0;
constexpr double steps_per_contact_minimum = 10.0;
constexpr double steps_per_tangential_period_auto = 8.0;
constexpr double steps_per_tangential_period_minimum = 4.0;

/// Duration of an undamped Hertz contact (s).
double hertz_contact_time_s(double effective_mass_kg, double kn_N_m1_5, double impact_speed_m_s);

/// The fastest impact the scenario can produce (m/s), see above.
double max_impact_speed_m_s(const Scenario& scenario);

/// The shortest contact time over sphere–sphere and sphere–wall pairs at that speed (s).
double shortest_contact_time_s(const Scenario& scenario);

/// The shortest tangential-spring period over sphere–sphere and sphere–wall contacts (s);
/// infinite without tangential springs.
double shortest_tangential_period_s(const Scenario& scenario);

/// The time step to use: run.dt_s, or automatic. Throws InputError naming run.dt_s if a
/// given step cannot resolve the contacts.
double choose_time_step_s(const Scenario& scenario);

}  // namespace pdamp::soft
