#pragma once
/// The duration of a Hertz contact, which both engines need: the soft engine's time step
/// resolves it, and the hard engine measures the time between a sphere's collisions
/// against it (the soft law's contact time at that impact speed) and rests a sphere that
/// would land again within it.

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

/// The speed below which a body leaving its support, pressed back onto it at `pressing_m_s2`,
/// lands again within `window` Hertz contact times of that speed: the soft law would hold it
/// in one enduring contact. Its flight lasts 2 v / a, and t_c(v) = t_c(1 m/s) v^{-1/5}, so
/// 2 v / a = window t_c(v) at v = (window t_c(1 m/s) a / 2)^{5/6}.
inline double hertz_enduring_speed_m_s(double effective_mass_kg, double kn_N_m1_5, double pressing_m_s2,
                                       double window) {
  if (!(pressing_m_s2 > 0.0) || !(window > 0.0)) return 0.0;
  const double contact_time_at_1_m_s = hertz_contact_time_s(effective_mass_kg, kn_N_m1_5, 1.0);
  return std::pow(0.5 * window * contact_time_at_1_m_s * pressing_m_s2, 5.0 / 6.0);
}

}  // namespace pdamp
