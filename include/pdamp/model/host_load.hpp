#pragma once
/// The host's load and motion integrated over time: what a frequency-response point's
/// first harmonics are made of (docs/studies.md, FRF studies). Each engine keeps them
/// cumulative since t = 0, integrated exactly as it applies the forces (not from samples),
/// and reports them with every observation; differences at cycle boundaries give a
/// cycle's integrals.

#include <cmath>

#include "pdamp/model/energy_ledger.hpp"

namespace pdamp {

/// ∫ over time of the particles' vertical force on the host F_p (N·s), of the host's own
/// forces (spring, damper, excitation; N·s) and of its displacement z (m·s); F_p and z
/// also weighted by the excitation's sin(ωt + φ) and cos(ωt + φ). A prescribed host's own
/// forces are not defined (it has no finite mass): 0.
struct HostLoadIntegrals {
  double particles_N_s = 0.0, particles_sin_N_s = 0.0, particles_cos_N_s = 0.0;
  double own_N_s = 0.0;
  double z_m_s = 0.0, z_sin_m_s = 0.0, z_cos_m_s = 0.0;

  bool operator==(const HostLoadIntegrals&) const = default;
  HostLoadIntegrals operator-(const HostLoadIntegrals& earlier) const {
    return {particles_N_s - earlier.particles_N_s,
            particles_sin_N_s - earlier.particles_sin_N_s,
            particles_cos_N_s - earlier.particles_cos_N_s,
            own_N_s - earlier.own_N_s,
            z_m_s - earlier.z_m_s,
            z_sin_m_s - earlier.z_sin_m_s,
            z_cos_m_s - earlier.z_cos_m_s};
  }
};

/// sin(ωt + φ) and cos(ωt + φ) of the excitation: the weights of the harmonic integrals.
struct ExcitationPhase {
  double omega_rad_s = 0.0, phase_rad = 0.0;
  struct Weights {
    double sin, cos;
  };
  Weights at(double t_s) const {
    const double angle = omega_rad_s * t_s + phase_rad;
    return {std::sin(angle), std::cos(angle)};
  }
};

/// Cumulative HostLoadIntegrals, added term by term with compensated sums: a run adds
/// millions of impulses, and the books must stay exact to about one rounding of the total.
class HostLoadBooks {
 public:
  explicit HostLoadBooks(ExcitationPhase phase = {}) : phase_(phase) {}

  const ExcitationPhase& phase() const { return phase_; }
  /// An impulse on the host from the particles at t_s (N·s).
  void add_impulse(double impulse_N_s, double t_s) {
    const ExcitationPhase::Weights w = phase_.at(t_s);
    particles_ += impulse_N_s;
    particles_sin_ += impulse_N_s * w.sin;
    particles_cos_ += impulse_N_s * w.cos;
  }
  /// Integrals over a stretch of time.
  void add(const HostLoadIntegrals& stretch) {
    particles_ += stretch.particles_N_s;
    particles_sin_ += stretch.particles_sin_N_s;
    particles_cos_ += stretch.particles_cos_N_s;
    own_ += stretch.own_N_s;
    z_ += stretch.z_m_s;
    z_sin_ += stretch.z_sin_m_s;
    z_cos_ += stretch.z_cos_m_s;
  }
  HostLoadIntegrals value() const {
    return {particles_.value(), particles_sin_.value(), particles_cos_.value(), own_.value(),
            z_.value(),         z_sin_.value(),         z_cos_.value()};
  }

 private:
  ExcitationPhase phase_;
  CompensatedSum particles_, particles_sin_, particles_cos_, own_, z_, z_sin_, z_cos_;
};

}  // namespace pdamp
