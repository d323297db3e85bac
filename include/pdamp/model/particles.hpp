#pragma once
/// Particle state shared by both engines and returned in every State snapshot.
/// Vectors are stored as 3×N column-major matrices: one particle's x, y, z are adjacent,
/// which suits the random access of contact loops; scalars are plain arrays.

#include <Eigen/Core>

namespace pdamp {

struct Particles {
  Eigen::Matrix3Xd position_m;    ///< lab frame, origin at the cavity's bottom centre when z_host = 0
  Eigen::Matrix3Xd velocity_m_s;  ///< lab frame
  Eigen::Matrix3Xd angular_velocity_rad_s;
  Eigen::VectorXd radius_m;
  Eigen::VectorXd mass_kg;

  Particles() = default;
  explicit Particles(Eigen::Index n);

  Eigen::Index size() const { return radius_m.size(); }
  double total_mass_kg() const { return mass_kg.sum(); }
  double max_radius_m() const { return size() > 0 ? radius_m.maxCoeff() : 0.0; }
  /// Solid sphere moment of inertia, 2/5 m r^2 (kg m^2).
  double moment_of_inertia(Eigen::Index i) const { return 0.4 * mass_kg[i] * radius_m[i] * radius_m[i]; }
};

}  // namespace pdamp
