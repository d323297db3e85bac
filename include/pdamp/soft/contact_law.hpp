#pragma once
/// The paper's contact law, shared by sphere–sphere and sphere–wall contacts:
///   normal      f_n = k_n δ^{3/2} + c_n δ'   clamped at 0 (never attractive)
///   tangential  f_s = −k_s ξ − c_s v_t        |f_s| ≤ μ f_n; when sliding, ξ is reset
///               so that the spring and dashpot give exactly the capped force.
/// ξ is the contact's accumulated tangential displacement, rotated onto the current
/// tangent plane (magnitude kept) as the contact turns.
///
/// Energy: each step books what the mechanisms dissipate, as the trapezoid of the forces
/// the integrator applies over the displacements it makes (the same rule by which
/// velocity Verlet changes the kinetic energy, up to a term that does not accumulate):
///   impact   — the normal force beyond the elastic k_n δ^{3/2} (the dashpot, or where the
///              clamp acts, the elastic force it removes) times the change of overlap;
///   friction — the tangential force's work on the slip, less what the spring stores; for
///              a sticking contact this is exactly the tangential dashpot's work (the
///              trapezoid rule is exact for a linear spring), for a sliding one the
///              Coulomb slider's.
/// The Hertz spring is conservative and booked as stored energy, so what remains in the
/// energy balance is the integration error itself, O(Δt²).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "pdamp/scenario/scenario.hpp"

namespace pdamp::soft {

/// What a contact remembers from one step to the next. (Whether it is open at all is kept
/// apart, as one byte per pair, so that scanning pairs that do not touch stays cheap.)
struct ContactHistory {
  Eigen::Vector3d tangential_displacement_m = Eigen::Vector3d::Zero();  ///< ξ
  Eigen::Vector3d tangential_force_N = Eigen::Vector3d::Zero();         ///< f_s applied last step
  double normal_damping_force_N = 0.0;  ///< f_n − k_n δ^{3/2} applied last step (dashpot and clamp)
};

/// How the two bodies meet this step.
struct ContactKinematics {
  Eigen::Vector3d normal;  ///< unit vector from body j to body i
  double overlap_m;        ///< r_i + r_j − distance; ≤ 0 means apart
  /// Velocity of i's contact point relative to j's over the step (the half-step
  /// velocities the integrator moved them by): it loads the tangential spring and drives
  /// the dashpots.
  Eigen::Vector3d velocity;
};

/// The force on body i at one contact, and the energy it moved this step.
struct ContactForce {
  Eigen::Vector3d force_N;       ///< on body i (body j gets the opposite)
  Eigen::Vector3d tangential_N;  ///< tangential part of force_N, for the torques −l n × f_s
  double elastic_J = 0.0;               ///< energy stored in the contact after the step
  double dissipated_normal_J = 0.0;     ///< this step's impact loss
  double dissipated_tangential_J = 0.0; ///< this step's friction loss
};

/// Evaluates one contact — touching, or open last step — for a step of length dt and
/// updates its history; a contact that has come apart (overlap ≤ 0) is closed: its books
/// are balanced (the spring's leftover energy goes to friction) and its history cleared.
[[gnu::always_inline]] inline ContactForce evaluate_contact(const SoftContactLaw& law, const ContactKinematics& k, double dt_s,
                                     ContactHistory& h) {
  ContactForce out;
  const Eigen::Vector3d& n = k.normal;
  const double closing_speed = -k.velocity.dot(n);  // δ'
  const Eigen::Vector3d tangential_velocity = k.velocity + closing_speed * n;
  const Eigen::Vector3d slip_m = tangential_velocity * dt_s;
  const double overlap_change_m = closing_speed * dt_s;
  const double spring_energy_before = 0.5 * law.ks_N_m * h.tangential_displacement_m.squaredNorm();

  double damping_force = 0.0;
  Eigen::Vector3d fs = Eigen::Vector3d::Zero();
  if (k.overlap_m > 0.0) {
    const double elastic_force = law.kn_N_m1_5 * k.overlap_m * std::sqrt(k.overlap_m);
    const double fn = std::max(0.0, elastic_force + law.cn_N_s_m * closing_speed);
    damping_force = fn - elastic_force;

    Eigen::Vector3d& xi = h.tangential_displacement_m;
    const double xi_sq = xi.squaredNorm();
    if (xi_sq > 0.0) {
      // Onto the current tangent plane, keeping the stored spring energy.
      const double off_plane = xi.dot(n);
      const double in_plane_sq = xi_sq - off_plane * off_plane;
      if (in_plane_sq > 0.0) xi = (xi - off_plane * n) * std::sqrt(xi_sq / in_plane_sq);
    }
    xi += slip_m;
    fs = -law.ks_N_m * xi - law.cs_N_s_m * tangential_velocity;
    const double cap = law.mu * fn;
    const double fs_sq = fs.squaredNorm();
    if (fs_sq > cap * cap) {
      // Sliding: the force is capped and the spring keeps only what the capped force allows.
      fs *= cap / std::sqrt(fs_sq);
      if (law.ks_N_m > 0.0) xi = -(fs + law.cs_N_s_m * tangential_velocity) / law.ks_N_m;
    }
    out.force_N = fn * n + fs;
    out.elastic_J = 0.4 * elastic_force * k.overlap_m + 0.5 * law.ks_N_m * xi.squaredNorm();
  } else {
    out.force_N.setZero();
    h.tangential_displacement_m.setZero();  // apart: the spring lets go
  }
  out.tangential_N = fs;

  // Trapezoids of the forces over the displacements the integrator made this step.
  out.dissipated_normal_J = 0.5 * (h.normal_damping_force_N + damping_force) * overlap_change_m;
  out.dissipated_tangential_J = -0.5 * (h.tangential_force_N + fs).dot(slip_m) -
                                (0.5 * law.ks_N_m * h.tangential_displacement_m.squaredNorm() - spring_energy_before);
  h.tangential_force_N = fs;
  h.normal_damping_force_N = damping_force;
  return out;
}

}  // namespace pdamp::soft
