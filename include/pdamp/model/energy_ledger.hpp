#pragma once
/// Where the energy is, shared by both engines and stored with every sample.
/// Energy balance: E(0) + W_excitation(t) = E(t) + D(t), where E is the sum of the
/// stored energies and D the cumulative dissipation by mechanism.

#include <Eigen/Core>

#include "pdamp/model/particles.hpp"

namespace pdamp {

struct EnergyLedger {
  // Energy stored at this instant (J).
  double particle_translational_J = 0.0;
  double particle_rotational_J = 0.0;
  double host_kinetic_J = 0.0;             ///< ½ M z'² (for prescribed motion: M is the nominal mass, not counted in E)
  double spring_potential_J = 0.0;         ///< ½ K (z − y)²
  double gravitational_potential_J = 0.0;  ///< −Σ m g·x of the particles (origin: cavity bottom centre at z = 0)
  double contact_elastic_J = 0.0;          ///< elastic energy stored in soft contacts (normal + tangential)

  // Cumulative since t = 0 (J).
  double excitation_work_J = 0.0;       ///< work fed in by the excitation (base, force or prescribed motion)
  double dissipated_impact_J = 0.0;     ///< normal contact losses (dashpot, restitution)
  double dissipated_friction_J = 0.0;   ///< tangential losses (dashpot, Coulomb sliding, tangential restitution)
  double dissipated_viscous_J = 0.0;    ///< host damper C

  bool host_counts = true;  ///< false for a prescribed-motion host, whose energy is not part of E

  double stored_J() const {
    const double host = host_counts ? host_kinetic_J + spring_potential_J : 0.0;
    return particle_translational_J + particle_rotational_J + gravitational_potential_J + contact_elastic_J + host;
  }
  double dissipated_J() const { return dissipated_impact_J + dissipated_friction_J + dissipated_viscous_J; }

  /// E(0) + W − E(t) − D(t): zero for an exact engine.
  double balance_residual_J(double initial_stored_J) const {
    return initial_stored_J + excitation_work_J - stored_J() - dissipated_J();
  }
  /// |residual| / (|E(0)| + |W|): relative to the energy that entered the system.
  double balance_relative_error(double initial_stored_J) const;
};

struct ParticleEnergies {
  double translational_J = 0.0;
  double rotational_J = 0.0;
  double gravitational_J = 0.0;
};

ParticleEnergies particle_energies(const Particles& particles, const Eigen::Vector3d& gravity_m_s2);

}  // namespace pdamp
