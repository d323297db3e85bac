#pragma once
/// Walton's three-parameter collision law (normal restitution e_n, Coulomb friction μ,
/// tangential restitution β0) for rigid spheres that rotate, written for any contact
/// whose point mobility has the form
///
///     K = a n nᵀ + b (I − n nᵀ) + h e_z e_zᵀ,
///
/// the change of the contact's relative velocity per unit impulse: a and b from the
/// spheres (a solid sphere adds 1/m to a and 1/m + r²/I = 7/(2m) to b) and h = 1/M from
/// a host that moves only vertically (0 for a prescribed, infinitely heavy host). A cap
/// contact (n = ±e_z) adds h to the normal mobility; a side-wall contact adds it to the
/// vertical tangential direction, so the host takes the vertical part of the friction
/// impulse; a contact with a sphere riding on the host mixes both.

#include <Eigen/Core>

#include "pdamp/scenario/scenario.hpp"

namespace pdamp::hard {

struct Mobility {
  double normal_1_kg = 0.0;      ///< a
  double tangential_1_kg = 0.0;  ///< b
  double host_1_kg = 0.0;        ///< h
};

/// The mobility a solid sphere of mass m contributes to a contact on its surface.
inline Mobility sphere_mobility(double mass_kg) { return {1.0 / mass_kg, 3.5 / mass_kg, 0.0}; }
inline Mobility operator+(const Mobility& x, const Mobility& y) {
  return {x.normal_1_kg + y.normal_1_kg, x.tangential_1_kg + y.tangential_1_kg, x.host_1_kg + y.host_1_kg};
}

struct CollisionOutcome {
  Eigen::Vector3d impulse_N_s = Eigen::Vector3d::Zero();  ///< on the first body; the partner takes −impulse
  double impact_J = 0.0;                                  ///< energy lost to the normal impulse, ½ (1 − e) λ u_n
  double friction_J = 0.0;  ///< energy lost to the tangential impulse; impact + friction = the total loss
  bool sticking = false;    ///< the tangential impulse was below μ times the normal one
};

/// The impulse of one collision. `relative_velocity` is the first body's contact point
/// velocity minus the partner's, `normal` the unit vector from the first body towards
/// the partner, `approach_speed` its normal component (> 0 when the bodies approach,
/// otherwise the outcome is zero). The caller computes it from the centres' velocities
/// exactly as the event prediction did, so that round-off in the rotation's normal part
/// can never turn a predicted contact into a non-event.
///
/// Sticking: the impulse that reverses the normal relative velocity times e_n and the
/// tangential one times β0. If its tangential part exceeds μ times its normal part the
/// collision slides: the tangential impulse keeps the sticking impulse's direction with
/// magnitude μ λ, and λ is set by the normal restitution. Both branches lose energy for
/// any e_n, μ ≥ 0 and β0 ∈ [−1, 1]; the loss is split exactly into the work of the normal
/// and of the tangential impulse at the mean of the pre- and post-collision velocities.
CollisionOutcome walton_collision(const Eigen::Vector3d& relative_velocity, const Eigen::Vector3d& normal,
                                  double approach_speed, const Mobility& mobility, const HardContactLaw& law);

/// K·p for the mobility above.
Eigen::Vector3d apply_mobility(const Mobility& mobility, const Eigen::Vector3d& normal, const Eigen::Vector3d& p);

}  // namespace pdamp::hard
