#pragma once
/// Where the energy is, shared by both engines and stored with every sample.
/// Energy balance: E(0) + W_excitation(t) = E(t) + D(t), where E is the sum of the
/// stored energies and D the cumulative dissipation by mechanism.

#include <Eigen/Core>
#include <cmath>

namespace pdamp {

struct EnergyLedger {
  // Energy stored at this instant (J).
  double particle_translational_J = 0.0;
  double particle_rotational_J = 0.0;
  double host_kinetic_J = 0.0;      ///< ½ M z'² (for prescribed motion: M is the nominal mass, not counted in E)
  double spring_potential_J = 0.0;  ///< ½ K (z − y)²
  double gravitational_potential_J = 0.0;  ///< −Σ m g·x of the particles (origin: cavity bottom centre at z = 0)
  double contact_elastic_J = 0.0;          ///< elastic energy stored in soft contacts (normal + tangential)

  // Cumulative since t = 0 (J).
  double excitation_work_J = 0.0;      ///< work fed in by the excitation (base, force or prescribed motion)
  double dissipated_impact_J = 0.0;    ///< normal contact losses (dashpot, restitution)
  double dissipated_friction_J = 0.0;  ///< tangential losses (dashpot, Coulomb sliding, tangential restitution)
  double dissipated_viscous_J = 0.0;   ///< host damper C

  bool host_counts = true;  ///< false for a prescribed-motion host, whose energy is not part of E

  bool operator==(const EnergyLedger&) const = default;

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

/// A sum of many terms, exact to about one rounding of the total (Neumaier's compensated
/// summation). A ledger adds up every sphere's energies, and a plain sum of 10^5 similar
/// terms can be off by 10^-12 of itself (each addition rounds to the growing total's
/// last bit), more than an engine's own error: the hard gas of 10^5 spheres conserves its
/// energy to 4·10^-16, which a plain sum reported as 1.6·10^-12.
class CompensatedSum {
 public:
  CompensatedSum& operator+=(double term) {
    const double sum = sum_ + term;
    // The part of the smaller operand that the rounded sum lost.
    compensation_ += std::abs(sum_) >= std::abs(term) ? (sum_ - sum) + term : (term - sum) + sum_;
    sum_ = sum;
    return *this;
  }
  double value() const { return sum_ + compensation_; }

 private:
  double sum_ = 0.0;
  double compensation_ = 0.0;
};

/// The particles' part of a ledger, summed sphere by sphere (both engines' observe()).
class ParticleEnergySums {
 public:
  /// Adds a sphere of mass m and moment of inertia I at x moving at v, spinning at w.
  void add(double mass_kg, double inertia_kg_m2, const Eigen::Vector3d& position_m, const Eigen::Vector3d& velocity_m_s,
           const Eigen::Vector3d& angular_velocity_rad_s, const Eigen::Vector3d& gravity_m_s2) {
    translational_J_ += 0.5 * mass_kg * velocity_m_s.squaredNorm();
    rotational_J_ += 0.5 * inertia_kg_m2 * angular_velocity_rad_s.squaredNorm();
    gravitational_J_ += -mass_kg * gravity_m_s2.dot(position_m);
  }
  double translational_J() const { return translational_J_.value(); }
  double rotational_J() const { return rotational_J_.value(); }
  void write_to(EnergyLedger& ledger) const {
    ledger.particle_translational_J = translational_J();
    ledger.particle_rotational_J = rotational_J();
    ledger.gravitational_potential_J = gravitational_J_.value();
  }

 private:
  CompensatedSum translational_J_, rotational_J_, gravitational_J_;
};

}  // namespace pdamp
