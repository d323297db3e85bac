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
#include <optional>

#include "pdamp/model/restitution.hpp"
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

/// What a sphere collides with, as far as the law goes: a sphere (free or riding), a cap
/// or the side wall.
enum class Partner { sphere, cap, side_wall };

/// The laws of the engine's collisions: the scenario's constants, or with a `calibration`
/// the soft law's e_n(v) and β0(v) at each impact speed; e_n = 1 for a slow approach.
class ContactLaws {
 public:
  ContactLaws(const Scenario& scenario, const RestitutionTable* calibration);
  /// The law of a collision with a sphere or a wall at this approach speed. Approaches
  /// slower than the elastic speed (the side wall's own for the side wall) are elastic
  /// (which stops inelastic collapse in flight), unless a sphere involved has collided at
  /// this instant already (`repeat`: wedged between two bodies, the sequence must die out,
  /// not bounce for ever). `lasting`: within the TC window of an earlier collision
  /// (within_tc_window), elastic too.
  HardContactLaw at(double approach_speed_m_s, Partner partner, bool repeat, bool lasting = false) const;
  double side_wall_elastic_speed_m_s() const { return side_wall_elastic_speed_m_s_; }
  /// Whether the TC model is on (hard.tc_window > 0).
  bool tc_model() const { return tc_window_ > 0.0; }
  /// Whether a collision `since_s` after an earlier one of a sphere it involves falls within
  /// the TC window: tc_window soft contact times of bodies of `effective_mass_kg` at this
  /// approach speed (the wall's law for a wall).
  bool within_tc_window(double since_s, double effective_mass_kg, bool wall, double approach_speed_m_s) const;

 private:
  HardContactLaw sphere_, wall_;
  std::optional<RestitutionTable> calibration_;
  double elastic_speed_m_s_, side_wall_elastic_speed_m_s_;
  double tc_window_, sphere_kn_N_m1_5_, wall_kn_N_m1_5_;
};

/// A perfectly inelastic collision of a body with the host in the vertical, the only
/// direction the host moves in: what it loses, where the host goes, and the work a
/// prescribed host does on it.
struct VerticalSticking {
  double loss_J;                ///< kinetic energy of the vertical relative motion that stops
  double host_v_m_s;            ///< the host's (and the body's) vertical velocity after
  double host_work_J = 0;       ///< a prescribed host's work on the body (its velocity is kept)
  double body_impulse_N_s = 0;  ///< the body's vertical momentum change (the host and its riders take the opposite)
};
/// A body of `mass_kg` moving at `vz_m_s` sticks to a host moving at `host_v_m_s`: a free
/// host moving `carried_mass_kg` in all (its own and its riders') shares its momentum; a
/// prescribed one (`prescribed`) keeps its velocity.
VerticalSticking stick_vertically(double mass_kg, double vz_m_s, double host_v_m_s, bool prescribed,
                                  double carried_mass_kg);

/// A sphere bouncing off the curved side wall (`outward`, the wall's normal, horizontal)
/// with horizontal velocity `v`: it leaves at least at `floor_speed_m_s`, its horizontal
/// speed unchanged. Bouncing ever more often as its radial speed dies out (chords are
/// ∝ radial speed), it would never stop: the wall turns it as a lasting contact would,
/// without changing its energy.
Eigen::Vector2d turned_along_side_wall(const Eigen::Vector2d& v, const Eigen::Vector2d& outward,
                                       double floor_speed_m_s);

}  // namespace pdamp::hard
