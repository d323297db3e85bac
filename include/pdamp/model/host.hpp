#pragma once
/// The single-degree-of-freedom host that carries the cavity:
///   M z'' + C (z' − y') + K (z − y) = F(t) + F_particles,
/// with y(t) the base motion (zero unless excitation.mode = base) and F(t) the applied
/// force (zero unless excitation.mode = force). A prescribed-motion host follows
/// z = A sin(ωt + φ) whatever the particles do (infinite mass).
///
/// `HostModel` gives the forces and energies at a state, for time-stepping engines;
/// `HostTrajectory` is the exact closed-form motion between particle impulses, for the
/// event-driven engine and for runs without particles.

#include <array>
#include <cstddef>

#include "pdamp/model/checkpoint.hpp"
#include "pdamp/model/energy_ledger.hpp"
#include "pdamp/model/host_load.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

struct HostState {
  double z_m = 0.0;
  double v_m_s = 0.0;
  bool operator==(const HostState&) const = default;
};

class HostModel {
 public:
  explicit HostModel(const Scenario& scenario);

  double mass_kg() const { return mass_kg_; }
  double stiffness_N_m() const { return stiffness_N_m_; }
  double damping_N_s_m() const { return damping_N_s_m_; }
  bool has_infinite_mass() const { return mode_ == ExcitationMode::prescribed_motion; }
  ExcitationMode mode() const { return mode_; }
  double angular_frequency_rad_s() const { return omega_; }
  /// ω and φ of the excitation, whose sin(ωt + φ) and cos(ωt + φ) weight the harmonic integrals.
  ExcitationPhase excitation_phase() const { return {omega_, phase_rad_}; }
  /// √(K/M): the undamped angular frequency of the host alone (rad/s).
  double natural_angular_frequency_rad_s() const;
  /// A of the base or prescribed motion (m).
  double motion_amplitude_m() const { return amplitude_m_; }
  HostState initial_state() const;

  /// Base displacement y(t) and velocity y'(t); zero unless base motion.
  double base_position_m(double t_s) const;
  double base_velocity_m_s(double t_s) const;
  /// The applied force F(t); zero unless force excitation.
  double applied_force_N(double t_s) const;
  /// The prescribed motion z(t), z'(t), z''(t) (prescribed mode only).
  HostState prescribed_state(double t_s) const;
  double prescribed_acceleration_m_s2(double t_s) const;

  /// Spring, damper and excitation force on the host at a state (N), particles excluded.
  double force_N(double t_s, const HostState& s) const;
  /// ½ K (z − y)²
  double spring_energy_J(double t_s, double z_m) const;
  /// The host's share of a ledger at a state: ½ M z'², ½ K (z − y)², and whether they
  /// count in the stored energy (not for a prescribed host).
  void write_energy_to(EnergyLedger& ledger, double t_s, const HostState& s) const;
  /// C (z' − y')², the rate at which the damper turns energy into heat (W).
  double viscous_power_W(double t_s, double v_m_s) const;
  /// Power the excitation feeds into host, spring and damper (W): F z' for a force,
  /// −(K (z − y) + C (z' − y')) y' for base motion, zero otherwise. (A prescribed host
  /// feeds energy into the particles only; the engines book that work.)
  double excitation_power_W(double t_s, const HostState& s) const;

  /// The host forcing written as a sin(ωt) + b cos(ωt), valid for the base and force
  /// modes: for base motion it is K y + C y'.
  double forcing_sin_N() const { return forcing_sin_N_; }
  double forcing_cos_N() const { return forcing_cos_N_; }

  /// z₁ = sin_m sin ωt + cos_m cos ωt.
  struct Harmonic {
    double sin_m = 0.0, cos_m = 0.0;
  };
  /// The steady forced response (base and force modes) of the host with mass and viscous
  /// damping added on its absolute motion, (M + m) z'' + (C + c) z' + K z = forcing: the
  /// host alone (0, 0), the riding bed (its mass, 0), or a bed's apparent mass and
  /// equivalent damping at ω.
  Harmonic forced_response(double added_mass_kg, double added_damping_N_s_m) const;

 private:
  ExcitationMode mode_;
  double mass_kg_, stiffness_N_m_, damping_N_s_m_;
  double z0_m_, v0_m_s_;
  double amplitude_m_, force_N_, omega_, phase_rad_;
  double forcing_sin_N_ = 0.0, forcing_cos_N_ = 0.0;
};

/// Exact host motion from (t0, state) while no impulse acts, for every excitation mode
/// and for under-, critically and over-damped hosts. `added_mass_kg` and
/// `added_force_N` let particles resting on the host ride along as mass and weight.
class HostTrajectory {
 public:
  HostTrajectory(const HostModel& model, double t0_s, HostState start, double added_mass_kg = 0.0,
                 double added_force_N = 0.0);

  double t0_s() const { return t0_s_; }
  HostState at(double t_s) const;
  double acceleration_m_s2(double t_s) const;
  /// The same, given the state at t_s (saves evaluating it again).
  double acceleration_m_s2(double t_s, const HostState& state) const;

  /// Bounds on |z'| and |z''| that hold for every t ≥ t0 (the host's energy relative to
  /// its forced response can only decrease between impulses).
  double speed_bound_m_s() const { return speed_bound_; }
  double acceleration_bound_m_s2() const { return acceleration_bound_; }
  /// A bound on |z'''| for every t ≥ t0, from the equation of motion and the bounds above.
  double jerk_bound_m_s3() const { return jerk_bound_; }

  /// What the host did over [from, to] ⊂ [t0, ∞): ∫ C (z' − y')² dt (the damper's loss),
  /// ∫ excitation power dt (HostModel::excitation_power_W), and its load integrals, with
  /// spheres of `riding_mass_kg` riding on it that load it with m_r (g_z − z'') (g_z:
  /// `gravity_z_m_s2`). Exact to round-off: Gauss–Legendre on panels far shorter than every
  /// time scale of the integrands, which are analytic; one pass for all of them.
  struct Stretch {
    double viscous_J = 0.0, excitation_J = 0.0;
    HostLoadIntegrals load;
  };
  Stretch stretch(double from_s, double to_s, double riding_mass_kg, double gravity_z_m_s2) const;

  /// Every number of the trajectory, verbatim (its model is the engine's own).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  /// ∫ f dt over [from, to] for each of f's N components.
  template <std::size_t N, class Integrand>
  std::array<double, N> integrate(double from_s, double to_s, Integrand f) const;
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);

  const HostModel* model_;
  double t0_s_;
  double mass_kg_;
  // Response = static offset + forced harmonic + free part u(s), s = t − t0.
  double offset_m_ = 0.0;
  double forced_sin_m_ = 0.0, forced_cos_m_ = 0.0;
  double u0_m_ = 0.0, du0_m_s_ = 0.0;
  double decay_rate_1_s_ = 0.0;  ///< α = C / 2M
  double lambda_1_s2_ = 0.0;     ///< K/M − α²: > 0 under-, 0 critically, < 0 over-damped
  double omega0_sq_ = 0.0;       ///< K/M
  double fastest_rate_1_s_ = 0.0;
  double speed_bound_ = 0.0, acceleration_bound_ = 0.0, jerk_bound_ = 0.0;
};

}  // namespace pdamp
