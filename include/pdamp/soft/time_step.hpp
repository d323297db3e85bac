#pragma once
/// The soft engine's time step. A Hertz contact f = k_n δ^{3/2} between bodies of
/// effective mass m* hit at speed v lasts t_c = 2.9432 δ_max / v with
/// δ_max = (5 m* v² / 4 k_n)^{2/5} (hertz_contact_time_s; the dashpot only shortens it). The step must resolve
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
/// And the dashpots. Velocity Verlet on a damped oscillator m x'' = −k x − c x', with the
/// dashpot on the half-step velocity as the engine applies it, carries (x_n, v_{n−½}) to
/// (x_{n+1}, v_{n+½}) by a matrix whose eigenvalues solve
///   λ² − (2 − γ − Ω²) λ + (1 − γ) = 0,   Ω = ω Δt,  γ = c Δt / m = Δt / τ.
/// Both lie inside the unit circle iff γ < 2 and Ω² + 2γ < 4 (Jury's conditions): without
/// the dashpot the familiar Ω < 2 (Δt < T/π); without the spring γ < 2, beyond which each
/// step reverses the relative velocity and amplifies it (the scheme's 1 − γ for e^{−γ}).
/// The relaxation times τ = m/c taken: the normal dashpot c_n on m* (m/2 for a pair of the
/// lightest spheres, m against a wall), the tangential c_s on m_t (m/7, 2m/7), the host's
/// damper C on M (unless its motion is prescribed) and the settling drag (τ = t_fall,
/// settling.hpp).
///
/// `auto` picks Δt = min(t_c(v_max)/50, T_s/8, τ_min/10); a given Δt above
/// min(t_c(v_max)/10, T_s/4, τ_min/2) is refused. At τ/10 the explicit 1 − γ is within
/// 0.5 % of e^{−γ}. At the refusal limit the tangential oscillator has Ω ≤ π/2 and γ ≤ ½,
/// so Ω² + 2γ ≤ 3.47 < 4; the normal one, whose stiffness at the deepest overlap
/// (3/2) k_n δ_max^{1/2} gives ω t_c = 4.03, has Ω ≤ 0.40: every contact stays stable.
/// For the paper's laws the dashpots bind nowhere (γ ≤ 0.04 at the automatic step).

#include <string>

#include "pdamp/model/hertz_contact.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp::soft {

constexpr double steps_per_contact_auto = 50.0;
constexpr double steps_per_contact_minimum = 10.0;
constexpr double steps_per_tangential_period_auto = 8.0;
constexpr double steps_per_tangential_period_minimum = 4.0;
constexpr double steps_per_relaxation_auto = 10.0;
constexpr double steps_per_relaxation_minimum = 2.0;

/// The fastest impact the scenario can produce (m/s), see above.
double max_impact_speed_m_s(const Scenario& scenario);

/// The shortest contact time over sphere–sphere and sphere–wall pairs at that speed (s).
double shortest_contact_time_s(const Scenario& scenario);

/// The shortest tangential-spring period over sphere–sphere and sphere–wall contacts (s);
/// infinite without tangential springs.
double shortest_tangential_period_s(const Scenario& scenario);

/// A dashpot's relaxation time τ = m/c and what it is.
struct Relaxation {
  double time_s;
  std::string what;  ///< e.g. "the sphere-sphere normal dashpot soft.cn_N_s_m"
};

/// The shortest relaxation time over the dashpots listed above (time_s infinite without any).
Relaxation shortest_relaxation(const Scenario& scenario);

/// The time step to use: run.dt_s, or automatic. Throws InputError naming run.dt_s if a
/// given step cannot resolve the contacts.
double choose_time_step_s(const Scenario& scenario);

/// The time step and what sets it, in words (for `pdamp check` and messages).
std::string describe_time_step(const Scenario& scenario);

}  // namespace pdamp::soft
