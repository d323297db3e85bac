#pragma once
/// Frequency-response analysis of a harmonically driven host (docs/studies.md, FRF
/// studies): each excitation cycle's first harmonics from the engines' exact integrals
/// (HostLoadIntegrals) at the cycle's ends, the steady-state criterion on successive
/// cycles, and a point's metrics over its last cycles.
///
/// Conventions, with θ = ωt + φ the excitation's angle (force F0 sin θ, base y = Y sin θ):
/// - z₁ = X sin(θ + φ_X): amplitude X ≥ 0, phase φ_X in (−π, π] (negative: the host lags
///   the excitation);
/// - F_p,1 = −m_app z₁'' − c_eq z₁': the particles' force at ω, split along the host's
///   acceleration (apparent mass) and velocity (equivalent viscous damping);
/// - η = D_cycle / (2π · ½ K X_s²), D_cycle every mechanism's loss in a cycle and X_s the
///   spring's stretch amplitude: X under a force, |z₁ − y| under base motion (the spring
///   stores ½ K (z − y)²). The host alone gives η = C ω / K in both modes.

#include <optional>
#include <vector>

#include "pdamp/model/host.hpp"
#include "pdamp/model/state.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

/// The first harmonics at ω over whole cycles [t_start, t_end]: (2/T) ∫ · sin θ dt and
/// (2/T) ∫ · cos θ dt of the host's displacement and of the particles' force.
struct HarmonicCycle {
  double t_start_s = 0.0, t_end_s = 0.0;
  double z_sin_m = 0.0, z_cos_m = 0.0;  ///< z₁ = z_sin sin θ + z_cos cos θ
  double load_sin_N = 0.0, load_cos_N = 0.0;

  double amplitude_m() const;
  double phase_rad() const;
  double load_amplitude_N() const;
  double load_phase_rad() const;
};
HarmonicCycle first_harmonics(const Observation& start, const Observation& end);

/// The particles' force at ω split along the host's first harmonic z₁ = X sin(θ + φ_X):
/// F_p,1 = −m_app z₁'' − c_eq z₁'.
struct ApparentLoad {
  double mass_kg = 0.0;
  double damping_N_s_m = 0.0;
};
ApparentLoad apparent_load(const HarmonicCycle& cycle, double omega_rad_s);

/// When a point is steady (defaults documented in docs/studies.md; `[frf]` sets them).
struct SteadyStateCriterion {
  int consecutive_cycles = 5;         ///< k: this many successive cycles all within the tolerances
  double amplitude_tolerance = 1e-3;  ///< |X_i − X_{i−1}| ≤ tol · X_i
  double phase_tolerance_rad = 1e-3;  ///< |φ_i − φ_{i−1}| ≤ tol
  int min_cycles = 10;                ///< never settled before this many cycles
  int max_cycles = 400;               ///< the cap: not settled by then, the point is stored as not settled
  int measured_cycles = 10;           ///< n: the metrics are over the n cycles after settling
  bool operator==(const SteadyStateCriterion&) const = default;
};

/// Which first harmonic a steady state is judged on: the host's displacement (a host the
/// excitation drives through its spring or mass) or the particles' force on it (a host whose
/// motion is prescribed: its displacement is steady from the start).
enum class SteadyWatch { displacement, load };

/// Feeds on successive cycles; settled once the last k changes of the watched harmonic
/// (amplitude and phase) are all within tolerance and at least min_cycles have run.
class SteadyStateDetector {
 public:
  explicit SteadyStateDetector(const SteadyStateCriterion& criterion, SteadyWatch watch = SteadyWatch::displacement)
      : criterion_(criterion), watch_(watch) {}
  /// Adds the next cycle; true if the point is (now) settled.
  bool add(const HarmonicCycle& cycle);
  int cycles() const { return cycles_; }

 private:
  SteadyStateCriterion criterion_;
  SteadyWatch watch_;
  HarmonicCycle last_;
  int cycles_ = 0;
  int streak_ = 0;
};

/// What drives the host, for normalising the response.
struct FrfDrive {
  ExcitationMode mode = ExcitationMode::force;
  double level = 0.0;  ///< F0 (N) under a force, Y (m) under base motion
  double omega_rad_s = 0.0;
  double stiffness_N_m = 0.0;
  double gravity_m_s2 = 0.0;  ///< |g|, for Γ
  /// Of a force or base scenario; throws InputError for another mode.
  static FrfDrive of(const Scenario& scenario);
};

/// A frequency-response point's metrics over its measured cycles.
struct ResponseMetrics {
  bool settled = false;
  int cycles_to_steady = 0;  ///< cycles run before the measured ones (not settled: all but the last n)
  int measured_cycles = 0;
  double amplitude_m = 0.0;         ///< X over the measured cycles together
  double amplitude_spread_m = 0.0;  ///< max − min of the measured cycles' own X
  double phase_rad = 0.0;
  double normalised_amplitude = 0.0;  ///< X / (F0/K) under a force, X / Y under base motion
  std::optional<double> gamma;        ///< X ω² / |g|; none without gravity, where Γ is undefined
  double impact_J_per_cycle = 0.0, friction_J_per_cycle = 0.0, viscous_J_per_cycle = 0.0;
  double loss_factor = 0.0;
  double apparent_mass_kg = 0.0, equivalent_damping_N_s_m = 0.0;
};

/// The metrics over the cycles between successive `boundaries` (observations at whole
/// cycles, at least two).
ResponseMetrics response_metrics(const std::vector<Observation>& boundaries, const FrfDrive& drive, bool settled,
                                 int cycles_to_steady);

/// Continuation with a predictor (`start = predict`, docs/studies.md): how far to move the
/// host, and the spheres rigidly with it, from the end of a point (a whole number of its
/// cycles, where θ = φ) so that the next point starts on its predicted steady state. The
/// prediction is the harmonic balance of `next` (the host at the new ω) carrying the
/// previous point's apparent mass and equivalent damping; the shift is that harmonic at
/// t = 0 less the previous point's measured first harmonic at its end. Host alone, it is
/// the exact steady state.
HostState predicted_shift(const ResponseMetrics& previous, double previous_omega_rad_s, const HostModel& next);

}  // namespace pdamp
