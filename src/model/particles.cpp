#include "pdamp/model/particles.hpp"

#include "pdamp/model/energy_ledger.hpp"

namespace pdamp {

Particles::Particles(Eigen::Index n)
    : position_m(Eigen::Matrix3Xd::Zero(3, n)),
      velocity_m_s(Eigen::Matrix3Xd::Zero(3, n)),
      angular_velocity_rad_s(Eigen::Matrix3Xd::Zero(3, n)),
      radius_m(Eigen::VectorXd::Zero(n)),
      mass_kg(Eigen::VectorXd::Zero(n)) {}

double EnergyLedger::balance_relative_error(double initial_stored_J) const {
  const double scale = std::abs(initial_stored_J) + std::abs(excitation_work_J);
  const double residual = std::abs(balance_residual_J(initial_stored_J));
  return scale > 0 ? residual / scale : residual;
}

}  // namespace pdamp
