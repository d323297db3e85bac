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

#include "pdamp/scenario/scenario.hpp"
#include "simd/lanes.hpp"

namespace pdamp::soft {

// The kernels are written over the lanes both engines share.
using namespace simd;

/// What a contact remembers from one step to the next (kept for open contacts only, in a
/// ContactTable).
template <class Real = double>
struct ContactHistory {
  Vec3<Real> tangential_displacement_m = zero_vec3<Real>();  ///< ξ
  Vec3<Real> tangential_force_N = zero_vec3<Real>();         ///< f_s applied last step
  Real normal_damping_force_N{};  ///< f_n − k_n δ^{3/2} applied last step (dashpot and clamp)
};

/// How the two bodies meet this step.
template <class Real>
struct ContactKinematics {
  Vec3<Real> normal;  ///< unit vector from body j to body i
  Real overlap_m;     ///< r_i + r_j − distance; ≤ 0 means apart
  /// Velocity of i's contact point relative to j's over the step (the half-step
  /// velocities the integrator moved them by): it loads the tangential spring and drives
  /// the dashpots.
  Vec3<Real> velocity;
};

/// The force on body i at one contact, and the energy it moved this step.
template <class Real>
struct ContactForce {
  Vec3<Real> force_N;            ///< on body i (body j gets the opposite)
  Vec3<Real> tangential_N;       ///< tangential part of force_N, for the torques −l n × f_s
  Real elastic_J;                ///< energy stored in the contact after the step
  Real dissipated_normal_J;      ///< this step's impact loss
  Real dissipated_tangential_J;  ///< this step's friction loss
};

/// Evaluates one contact (or two, in lanes) — touching, or open last step — for a step of
/// length dt and updates its history; a contact that has come apart (overlap ≤ 0) is
/// closed: its books are balanced (the spring's leftover energy goes to friction) and its
/// history cleared. Written without branches on the contact, each `if` a select.
template <class Real>
[[gnu::always_inline]] inline ContactForce<Real> evaluate_contact(const SoftContactLaw& law,
                                                                  const ContactKinematics<Real>& k, double dt_s,
                                                                  ContactHistory<Real>& h) {
  const Vec3<Real>& n = k.normal;
  const Real closing_speed = -dot(k.velocity, n);  // δ'
  const Vec3<Real> tangential_velocity = k.velocity + closing_speed * n;
  const Vec3<Real> slip_m = tangential_velocity * dt_s;
  const Real overlap_change_m = closing_speed * dt_s;
  const Real spring_energy_before = 0.5 * law.ks_N_m * squared_norm(h.tangential_displacement_m);
  const auto touching = k.overlap_m > 0.0;

  // Where apart, the overlap's square root is not a number; the selects below drop it.
  const Real elastic_force = law.kn_N_m1_5 * k.overlap_m * sqrt_of(k.overlap_m);
  const Real pushing = elastic_force + law.cn_N_s_m * closing_speed;
  const Real fn = select(pushing > 0.0, pushing, Real{});
  const Real damping_force = select(touching, fn - elastic_force, Real{});

  // ξ onto the current tangent plane, keeping the stored spring energy.
  Vec3<Real> xi = h.tangential_displacement_m;
  const Real xi_sq = squared_norm(xi);
  const Real off_plane = dot(xi, n);
  const Real in_plane_sq = xi_sq - off_plane * off_plane;
  xi = select(in_plane_sq > 0.0, (xi - off_plane * n) * sqrt_of(xi_sq / in_plane_sq), xi);
  xi = xi + slip_m;
  Vec3<Real> fs = -law.ks_N_m * xi - law.cs_N_s_m * tangential_velocity;
  const Real cap = law.mu * fn;
  const Real fs_sq = squared_norm(fs);
  // Sliding: the force is capped and the spring keeps only what the capped force allows.
  const auto sliding = fs_sq > cap * cap;
  fs = select(sliding, fs * (cap / sqrt_of(fs_sq)), fs);
  // One scalar reciprocal, not a vector division per component.
  if (law.ks_N_m > 0.0) xi = select(sliding, -(1.0 / law.ks_N_m) * (fs + law.cs_N_s_m * tangential_velocity), xi);

  // Apart: no force, and the spring lets go.
  fs = select(touching, fs, zero_vec3<Real>());
  xi = select(touching, xi, zero_vec3<Real>());
  ContactForce<Real> out;
  out.force_N = select(touching, fn * n + fs, zero_vec3<Real>());
  out.tangential_N = fs;
  out.elastic_J = select(touching, 0.4 * elastic_force * k.overlap_m + 0.5 * law.ks_N_m * squared_norm(xi), Real{});

  // Trapezoids of the forces over the displacements the integrator made this step.
  out.dissipated_normal_J = 0.5 * (h.normal_damping_force_N + damping_force) * overlap_change_m;
  out.dissipated_tangential_J =
      -0.5 * dot(h.tangential_force_N + fs, slip_m) - (0.5 * law.ks_N_m * squared_norm(xi) - spring_energy_before);
  h.tangential_displacement_m = xi;
  h.tangential_force_N = fs;
  h.normal_damping_force_N = damping_force;
  return out;
}

}  // namespace pdamp::soft
