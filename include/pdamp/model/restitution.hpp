#pragma once
/// Restitution of a contact as a function of impact speed: what the soft contact law does
/// to an isolated collision, tabulated for the hard-sphere engine (sim/calibration.hpp).

#include <vector>

namespace pdamp {

struct RestitutionCurve {
  std::vector<double> impact_speed_m_s;  ///< ascending, > 0
  std::vector<double> en;                ///< normal restitution of a head-on impact
  std::vector<double> beta0;             ///< tangential restitution of a sticking oblique impact

  /// Interpolated linearly in log(speed); constant beyond the ends.
  double en_at(double speed_m_s) const;
  double beta0_at(double speed_m_s) const;
};

struct RestitutionTable {
  RestitutionCurve sphere_sphere;
  RestitutionCurve sphere_wall;
};

}  // namespace pdamp
