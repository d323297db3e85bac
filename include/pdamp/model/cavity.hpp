#pragma once
/// The cylindrical hole in the host: side wall of radius R, bottom cap at the host's
/// displacement z_h, top cap at z_h + H. Queries take a sphere (centre, radius) in the
/// lab frame and return the gap between the sphere's surface and the wall (negative when
/// they overlap) with the wall's unit normal pointing into the cavity.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

enum class Wall { side, bottom, top };

struct WallGap {
  double gap_m;            ///< surface-to-wall distance, < 0 when overlapping
  Eigen::Vector3d normal;  ///< unit normal of the wall, pointing into the cavity
};

class Cavity {
 public:
  explicit Cavity(const CavitySettings& settings) : radius_m_(settings.radius_m()), height_m_(settings.height_m) {}

  double radius_m() const { return radius_m_; }
  double height_m() const { return height_m_; }

  WallGap side(const Eigen::Vector3d& centre, double radius_m) const {
    const double rho = std::sqrt(centre.x() * centre.x() + centre.y() * centre.y());
    // On the axis every direction is as good; a sphere there cannot touch the side anyway.
    const Eigen::Vector3d inward =
        rho > 0 ? Eigen::Vector3d(-centre.x() / rho, -centre.y() / rho, 0.0) : Eigen::Vector3d(-1.0, 0.0, 0.0);
    return {radius_m_ - rho - radius_m, inward};
  }
  WallGap bottom(const Eigen::Vector3d& centre, double radius_m, double host_z_m) const {
    return {centre.z() - host_z_m - radius_m, Eigen::Vector3d::UnitZ()};
  }
  WallGap top(const Eigen::Vector3d& centre, double radius_m, double host_z_m) const {
    return {host_z_m + height_m_ - centre.z() - radius_m, -Eigen::Vector3d::UnitZ()};
  }
  WallGap gap(Wall wall, const Eigen::Vector3d& centre, double radius_m, double host_z_m) const {
    switch (wall) {
      case Wall::side:
        return side(centre, radius_m);
      case Wall::bottom:
        return bottom(centre, radius_m, host_z_m);
      case Wall::top:
        break;
    }
    return top(centre, radius_m, host_z_m);
  }
  /// The smallest of the three gaps (m): how far the sphere is from leaving the cavity.
  double clearance_m(const Eigen::Vector3d& centre, double radius_m, double host_z_m) const {
    return std::min({side(centre, radius_m).gap_m, bottom(centre, radius_m, host_z_m).gap_m,
                     top(centre, radius_m, host_z_m).gap_m});
  }

 private:
  double radius_m_;
  double height_m_;
};

}  // namespace pdamp
