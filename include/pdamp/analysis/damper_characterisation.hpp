#pragma once
/// A damper characterised (docs/characterisation.md): its container driven with prescribed
/// motion z = A sin θ, θ = ωt + φ, the particles' first-harmonic force on it over whole
/// cycles resolved into an apparent mass and an equivalent damping, F_p,1 = −m_app z'' −
/// c_eq z' (analysis/frf_response.hpp's apparent_load), with the losses per cycle and the
/// spread of the per-cycle values.

#include <optional>
#include <vector>

#include "pdamp/analysis/frf_response.hpp"
#include "pdamp/model/state.hpp"

namespace pdamp {

struct CharacterisationMetrics {
  bool settled = false;
  int cycles_to_steady = 0;  ///< cycles run before the measured ones (not settled: all but the last n)
  int measured_cycles = 0;
  double amplitude_m = 0.0;     ///< the container's first harmonic over the measured cycles (A, as measured)
  std::optional<double> gamma;  ///< A ω² / |g|; none without gravity, where Γ is undefined
  double apparent_mass_kg = 0.0, equivalent_damping_N_s_m = 0.0;  ///< over the measured cycles together
  /// The standard deviation of the measured cycles' own values: how steady the point is.
  double apparent_mass_spread_kg = 0.0, equivalent_damping_spread_N_s_m = 0.0;
  double impact_J_per_cycle = 0.0, friction_J_per_cycle = 0.0;
  /// η = D_cycle / (2π · ½ m_p (ωA)²), D_cycle the particles' losses per cycle and ½ m_p (ωA)²
  /// the bed's largest kinetic energy moving with the container: from the ledger, it equals
  /// c_eq / (m_p ω) at a steady state (the container's work per cycle is π c_eq ω A², only
  /// the force's first harmonic working against a sinusoidal velocity). 0 without particles.
  double loss_factor = 0.0;
  /// The fraction of the measured cycles' instants (64 a cycle) at which a sphere touches
  /// the floor, and the lid.
  double floor_contact_fraction = 0.0, lid_contact_fraction = 0.0;
};

/// The metrics over the cycles between successive `boundaries` (observations at whole
/// cycles, at least two); the contact fractions are left to the caller.
CharacterisationMetrics characterisation_metrics(const std::vector<Observation>& boundaries, double omega_rad_s,
                                                 double gravity_m_s2, double particle_mass_kg, bool settled,
                                                 int cycles_to_steady);

}  // namespace pdamp
