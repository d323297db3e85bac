#pragma once
/// The paper's contact law, shared by sphere–sphere and sphere–wall contacts:
///   normal      f_n = k_n δ^{3/2} + c_n δ'   clamped at 0 (never attractive)
///   tangential  f_s = −k_s ξ − c_s v_t        |f_s| ≤ μ f_n; when sliding, ξ is reset
///               so that the spring and dashpot give exactly the capped force.
/// ξ is the contact's accumulated tangential displacement, rotated onto the current
/// tangent plane (magnitude kept) as the contact turns.
///
/// Energy bookkeeping per step: the work the contact does on the pair is the trapezoid of
/// the forces and torques the integrator applied over the displacements and rotations it
/// made; what that work did not put into the contact's elastic energy was dissipated —
/// the normal force's share to impact, the tangential force's to friction. With velocity
/// Verlet the kinetic energy then differs from the books only by a term that telescopes,
/// Σ (|F_{n+1}|² − |F_n|²) Δt²/8m: the balance error is O(Δt²) and does not accumulate,
/// whatever the clamp or the sliding resets do.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "pdamp/scenario/scenario.hpp"

namespace pdamp::soft {

/// What a contact remembers from one step to the next.
struct ContactHistory {
  Eigen::Vector3d tangential_displacement_m = Eigen::Vector3d::Zero();  ///< ξ
  Eigen::Vector3d force_N = Eigen::Vector3d::Zero();                    ///< force on body i applied last step
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();                     ///< contact normal last step
  double overlap_m = 0.0;  ///< δ last step; > 0 while in contact

  bool active() const { return overlap_m > 0.0; }
};

/// How the two bodies meet this step, with the velocities the integrator moved them by.
struct ContactKinematics {
  Eigen::Vector3d normal;           ///< unit vector from body j to body i
  double overlap_m;                 ///< r_i + r_j − distance; ≤ 0 means apart
  Eigen::Vector3d centre_velocity;  ///< v_i − v_j (a wall's velocity for a wall contact)
  Eigen::Vector3d lever_spin;       ///< r_i ω_i + r_j ω_j (a wall does not spin)
};

/// The force on body i at one contact, and the energy it moved this step.
struct ContactForce {
  Eigen::Vector3d force_N;       ///< on body i (body j gets the opposite)
  Eigen::Vector3d tangential_N;  ///< tangential part of force_N, for the torques −r n × f_s
  double elastic_J = 0.0;               ///< energy stored in the contact after the step
  double dissipated_normal_J = 0.0;     ///< this step's impact loss
  double dissipated_tangential_J = 0.0; ///< this step's friction loss
};

/// Evaluates one contact for a step of length dt and updates its history. A contact
/// that has come apart (overlap ≤ 0) is closed: its books are balanced and its history
/// cleared.
inline ContactForce evaluate_contact(const SoftContactLaw& law, const ContactKinematics& k, double dt_s,
                                     ContactHistory& h) {
  const Eigen::Vector3d& n = k.normal;
  const Eigen::Vector3d contact_velocity = k.centre_velocity - k.lever_spin.cross(n);
  const double normal_speed = contact_velocity.dot(n);  // = −δ'
  const Eigen::Vector3d tangential_velocity = contact_velocity - normal_speed * n;

  const double old_fn = h.force_N.dot(h.normal);
  const Eigen::Vector3d old_fs = h.force_N - old_fn * h.normal;
  const double old_elastic =
      (h.active() ? 0.4 * law.kn_N_m1_5 * h.overlap_m * h.overlap_m * std::sqrt(h.overlap_m) : 0.0) +
      0.5 * law.ks_N_m * h.tangential_displacement_m.squaredNorm();

  double fn = 0.0;
  Eigen::Vector3d fs = Eigen::Vector3d::Zero();
  double elastic = 0.0;
  if (k.overlap_m > 0.0) {
    const double elastic_force = law.kn_N_m1_5 * k.overlap_m * std::sqrt(k.overlap_m);
    fn = std::max(0.0, elastic_force - law.cn_N_s_m * normal_speed);

    Eigen::Vector3d& xi = h.tangential_displacement_m;
    const double xi_norm = xi.norm();
    xi -= xi.dot(n) * n;  // onto the current tangent plane ...
    const double projected = xi.norm();
    if (projected > 0.0) xi *= xi_norm / projected;  // ... keeping the stored spring energy
    xi += tangential_velocity * dt_s;
    fs = -law.ks_N_m * xi - law.cs_N_s_m * tangential_velocity;
    const double cap = law.mu * fn;
    const double fs_norm = fs.norm();
    if (fs_norm > cap) {
      fs *= cap / fs_norm;
      if (law.ks_N_m > 0.0) xi = -(fs + law.cs_N_s_m * tangential_velocity) / law.ks_N_m;
    }
    elastic = 0.4 * elastic_force * k.overlap_m + 0.5 * law.ks_N_m * xi.squaredNorm();
  }

  // Work done on the pair this step: the trapezoid of the forces and torques the
  // integrator applies, over the displacements and rotations it makes.
  const Eigen::Vector3d centre_shift = k.centre_velocity * dt_s, spin_turn = k.lever_spin * dt_s;
  const double normal_work = 0.5 * (old_fn * h.normal + fn * n).dot(centre_shift);
  const double tangential_work =
      0.5 * (old_fs + fs).dot(centre_shift) - 0.5 * (h.normal.cross(old_fs) + n.cross(fs)).dot(spin_turn);
  const double elastic_normal_change =
      (k.overlap_m > 0.0 ? 0.4 * law.kn_N_m1_5 * k.overlap_m * k.overlap_m * std::sqrt(k.overlap_m) : 0.0) -
      (h.active() ? 0.4 * law.kn_N_m1_5 * h.overlap_m * h.overlap_m * std::sqrt(h.overlap_m) : 0.0);

  ContactForce out;
  out.force_N = fn * n + fs;
  out.tangential_N = fs;
  out.elastic_J = elastic;
  out.dissipated_normal_J = -normal_work - elastic_normal_change;
  out.dissipated_tangential_J = -tangential_work - (elastic - old_elastic - elastic_normal_change);
  if (k.overlap_m > 0.0) {
    h.force_N = out.force_N;
    h.normal = n;
    h.overlap_m = k.overlap_m;
  } else {
    h = ContactHistory{};
  }
  return out;
}

}  // namespace pdamp::soft
