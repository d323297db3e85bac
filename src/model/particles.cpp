#include "pdamp/model/particles.hpp"

#include "pdamp/model/energy_ledger.hpp"

namespace pdamp {

Particles::Particles(Eigen::Index n)
    : position_m(Eigen::Matrix3Xd::Zero(3, n)),
      velocity_m_s(Eigen::Matrix3Xd::Zero(3, n)),
      angular_velocity_rad_s(Eigen::Matrix3Xd::Zero(3, n)),
      radius_m(Eigen::VectorXd::Zero(n)),
      mass_kg(Eigen::VectorXd::Zero(n)) {}

ParticleEnergies particle_energies(const Particles& particles, const Eigen::Vector3d& gravity_m_s2) {
  ParticleEnergies e;
  for (Eigen::Index i = 0; i < particles.size(); ++i) {
    const double m = particles.mass_kg[i];
    e.translational_J += 0.5 * m * particles.velocity_m_s.col(i).squaredNorm();
    e.rotational_J += 0.5 * particles.moment_of_inertia(i) * particles.angular_velocity_rad_s.col(i).squaredNorm();
    e.gravitational_J -= m * gravity_m_s2.dot(particles.position_m.col(i));
  }
  return e;
}

double EnergyLedger::balance_relative_error(double initial_stored_J) const {
  const double scale = std::abs(initial_stored_J) + std::abs(excitation_work_J);
  const double residual = std::abs(balance_residual_J(initial_stored_J));
  return scale > 0 ? residual / scale : residual;
}

}  // namespace pdamp
