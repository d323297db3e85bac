#pragma once
/// The duration of a Hertz contact, which both engines need: the soft engine's time step
/// resolves it, and the hard engine measures the time between a sphere's collisions
/// against it (the soft law's contact time at that impact speed).

#include <cmath>

namespace pdamp {

/// Duration of an undamped Hertz contact f = k_n δ^{3/2} between bodies of effective mass
/// m* hit at speed v (s): t_c = 2.9432 δ_max / v with δ_max = (5 m* v² / 4 k_n)^{2/5}
/// (the dashpot only shortens it).
inline double hertz_contact_time_s(double effective_mass_kg, double kn_N_m1_5, double impact_speed_m_s) {
  const double max_overlap =
      std::pow(5.0 * effective_mass_kg * impact_speed_m_s * impact_speed_m_s / (4.0 * kn_N_m1_5), 0.4);
  return 2.9432 * max_overlap / impact_speed_m_s;
}

}  // namespace pdamp
