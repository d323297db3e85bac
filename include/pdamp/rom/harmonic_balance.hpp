#pragma once
/// The steady forced response of a single-degree-of-freedom host carrying the damper, by
/// single-harmonic balance (docs/rom.md, "The model" and "Stability").
///
/// With the host at x = Re(X e^{iωt}) and the damper's first-harmonic force −m_app ẍ − c_eq ẋ,
///   Z(A, ω) X = R,   Z = K − ω²(M + m_app(A, ω)) + iω(C + c_eq(A, ω)),   A = |X|,
/// where R = F0 (force on the host) or R = (K + iωC) Y (base motion y = Re(Y e^{iωt}); X is
/// then the host's absolute motion). The amplitudes solve A |Z(A, ω)| = |R|.

#include <complex>
#include <string>
#include <vector>

#include "pdamp/rom/table_interpolation.hpp"

namespace pdamp::rom {

struct HostSdof {
  double mass_kg = 0.0;        ///< M > 0
  double stiffness_N_m = 0.0;  ///< K > 0
  double damping_N_s_m = 0.0;  ///< C >= 0
};

enum class ExcitationKind { force, base };

struct Excitation {
  ExcitationKind kind = ExcitationKind::force;
  double amplitude = 0.0;  ///< F0 in N (force) or Y in m (base), > 0
};

/// Throws InputError unless M > 0, K > 0, C >= 0 and the excitation amplitude > 0 (all finite).
void validate_host(const HostSdof& host, const Excitation& excitation);

/// Stability of a solution on the averaged (slow-flow) equations; see docs/rom.md.
enum class Stability {
  stable,
  unstable,  ///< a saddle (between turning points) or a growing amplitude (negative slow-flow damping)
  marginal,  ///< on a turning point or on the slow-flow damping's sign change
  unknown,   ///< M + m_app <= 0: the slow flow as derived does not apply
};
const char* to_string(Stability stability);

struct Solution {
  double amplitude_m = 0.0;    ///< A = |X|
  std::complex<double> ratio;  ///< X / F0 · K (force) or X / Y (base): dimensionless
  DamperValues damper;         ///< m_app, c_eq and their spreads at (A, f)
  Stability stability = Stability::unknown;
  /// sign of d(A|Z|)/dA at the root: +1 where the residual rises through zero (a turning-point
  /// criterion's stable side), −1 where it falls, 0 on a turning point
  int crossing = 0;
  bool saddle = false;            ///< d(A|Z|)/dA < 0: between two turning points
  bool slow_flow_growth = false;  ///< d(A² (C + c_eq))/dA < 0: the amplitude would grow
  bool unsettled = false;         ///< an unsettled table point has weight here

  // Set along the whole curve by predict_response (response_curve.hpp).
  int branch = 0;              ///< the continuation this solution belongs to (1, 2, ...)
  bool on_sweep_up = false;    ///< a stepped sine sweeping up would be on this solution
  bool on_sweep_down = false;  ///< ... sweeping down
};

/// Everything the balance gives at one frequency.
struct FrequencyResponse {
  double frequency_hz = 0.0;
  std::vector<Solution> solutions;  ///< inside the characterised amplitudes, by increasing amplitude
  /// The residual's sign at the ends of the characterised amplitudes proves an odd number of
  /// solutions below (above) them (A|Z| > |R| at the lowest amplitude, < |R| at the highest).
  bool solution_below = false;
  bool solution_above = false;
  bool not_covered = false;         ///< the table covers no amplitude at this frequency
  double lowest_amplitude_m = 0.0;  ///< the characterised amplitudes at this frequency
  double highest_amplitude_m = 0.0;
};

/// All roots of A|Z(A)| = |R| within the profile's amplitudes, each refined to a relative
/// 1e-14 in A, with their stability.
FrequencyResponse solve_frequency(const AmplitudeProfile& profile, const HostSdof& host, const Excitation& excitation);

}  // namespace pdamp::rom
