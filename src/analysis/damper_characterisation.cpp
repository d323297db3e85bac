#include "pdamp/analysis/damper_characterisation.hpp"

#include <cmath>
#include <numbers>

#include "pdamp/errors.hpp"

namespace pdamp {
namespace {

double standard_deviation(const std::vector<double>& values, double mean) {
  double sum = 0.0;
  for (const double v : values) sum += (v - mean) * (v - mean);
  return std::sqrt(sum / static_cast<double>(values.size()));
}

}  // namespace

CharacterisationMetrics characterisation_metrics(const std::vector<Observation>& boundaries, double omega_rad_s,
                                                 double gravity_m_s2, double particle_mass_kg, bool settled,
                                                 int cycles_to_steady) {
  if (boundaries.size() < 2) throw RuntimeFailure("a characterisation point needs at least one whole cycle");
  const Observation &first = boundaries.front(), &last = boundaries.back();
  const auto n = static_cast<int>(boundaries.size() - 1);
  CharacterisationMetrics m;
  m.settled = settled;
  m.cycles_to_steady = cycles_to_steady;
  m.measured_cycles = n;
  const double w = omega_rad_s;
  const HarmonicCycle all = first_harmonics(first, last);
  m.amplitude_m = all.amplitude_m();
  if (gravity_m_s2 > 0.0) m.gamma = m.amplitude_m * w * w / gravity_m_s2;
  const ApparentLoad load = apparent_load(all, w);
  m.apparent_mass_kg = load.mass_kg;
  m.equivalent_damping_N_s_m = load.damping_N_s_m;
  std::vector<double> masses, dampings;
  for (std::size_t k = 1; k < boundaries.size(); ++k) {
    const ApparentLoad cycle = apparent_load(first_harmonics(boundaries[k - 1], boundaries[k]), w);
    masses.push_back(cycle.mass_kg);
    dampings.push_back(cycle.damping_N_s_m);
  }
  m.apparent_mass_spread_kg = standard_deviation(masses, m.apparent_mass_kg);
  m.equivalent_damping_spread_N_s_m = standard_deviation(dampings, m.equivalent_damping_N_s_m);
  m.impact_J_per_cycle = (last.energy.dissipated_impact_J - first.energy.dissipated_impact_J) / n;
  m.friction_J_per_cycle = (last.energy.dissipated_friction_J - first.energy.dissipated_friction_J) / n;
  if (particle_mass_kg > 0.0) {
    const double peak_kinetic_J = 0.5 * particle_mass_kg * w * w * m.amplitude_m * m.amplitude_m;
    m.loss_factor = (m.impact_J_per_cycle + m.friction_J_per_cycle) / (2.0 * std::numbers::pi * peak_kinetic_J);
  }
  return m;
}

}  // namespace pdamp
