#include "pdamp/analysis/frf_response.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pdamp/errors.hpp"

namespace pdamp {
namespace {

/// φ wrapped into (−π, π].
double wrapped_rad(double angle_rad) {
  const double turn = 2.0 * std::numbers::pi;
  double wrapped = std::remainder(angle_rad, turn);
  if (wrapped <= -std::numbers::pi) wrapped += turn;
  return wrapped;
}

}  // namespace

double HarmonicCycle::amplitude_m() const { return std::hypot(z_sin_m, z_cos_m); }
double HarmonicCycle::phase_rad() const { return std::atan2(z_cos_m, z_sin_m); }
double HarmonicCycle::load_amplitude_N() const { return std::hypot(load_sin_N, load_cos_N); }
double HarmonicCycle::load_phase_rad() const { return std::atan2(load_cos_N, load_sin_N); }

ApparentLoad apparent_load(const HarmonicCycle& cycle, double omega_rad_s) {
  const double x = cycle.amplitude_m(), phase = cycle.phase_rad(), w = omega_rad_s;
  // F_p,1 along sin(θ + φ_X) (against z₁'' = −ω² z₁) and along cos(θ + φ_X) (against z₁').
  const double c = std::cos(phase), s = std::sin(phase);
  const double in_phase_N = cycle.load_sin_N * c + cycle.load_cos_N * s;
  const double quadrature_N = -cycle.load_sin_N * s + cycle.load_cos_N * c;
  return {in_phase_N / (w * w * x), -quadrature_N / (w * x)};
}

HarmonicCycle first_harmonics(const Observation& start, const Observation& end) {
  const HostLoadIntegrals d = end.host_load - start.host_load;
  const double two_over_t = 2.0 / (end.t_s - start.t_s);
  return {start.t_s,
          end.t_s,
          two_over_t * d.z_sin_m_s,
          two_over_t * d.z_cos_m_s,
          two_over_t * d.particles_sin_N_s,
          two_over_t * d.particles_cos_N_s};
}

bool SteadyStateDetector::add(const HarmonicCycle& cycle) {
  if (cycles_ > 0) {
    const bool load = watch_ == SteadyWatch::load;
    const double x = load ? cycle.load_amplitude_N() : cycle.amplitude_m();
    const double x_before = load ? last_.load_amplitude_N() : last_.amplitude_m();
    const double phase_change =
        load ? cycle.load_phase_rad() - last_.load_phase_rad() : cycle.phase_rad() - last_.phase_rad();
    const bool amplitude_still = std::abs(x - x_before) <= criterion_.amplitude_tolerance * x;
    const bool phase_still = std::abs(wrapped_rad(phase_change)) <= criterion_.phase_tolerance_rad;
    streak_ = amplitude_still && phase_still ? streak_ + 1 : 0;
  }
  last_ = cycle;
  ++cycles_;
  return cycles_ >= criterion_.min_cycles && streak_ >= criterion_.consecutive_cycles;
}

HostState predicted_shift(const ResponseMetrics& previous, double previous_omega_rad_s, const HostModel& next) {
  const HostModel::Harmonic forced = next.forced_response(previous.apparent_mass_kg, previous.equivalent_damping_N_s_m);
  const double angle = next.excitation_phase().phase_rad + previous.phase_rad;
  const double x = previous.amplitude_m;
  return {forced.cos_m - x * std::sin(angle),
          next.angular_frequency_rad_s() * forced.sin_m - previous_omega_rad_s * x * std::cos(angle)};
}

FrfDrive FrfDrive::of(const Scenario& scenario) {
  const ExcitationSettings& e = scenario.excitation;
  if (e.mode != ExcitationMode::force && e.mode != ExcitationMode::base_motion) {
    throw InputError("a frequency response needs excitation.mode = force or base");
  }
  return {e.mode, e.mode == ExcitationMode::force ? e.force_N : e.amplitude_m, e.angular_frequency_rad_s(),
          scenario.host.stiffness_N_m, scenario.gravity_m_s2.norm()};
}

ResponseMetrics response_metrics(const std::vector<Observation>& boundaries, const FrfDrive& drive, bool settled,
                                 int cycles_to_steady) {
  if (boundaries.size() < 2) throw RuntimeFailure("a frequency-response point needs at least one whole cycle");
  const Observation &first = boundaries.front(), &last = boundaries.back();
  const auto n = static_cast<int>(boundaries.size() - 1);
  ResponseMetrics m;
  m.settled = settled;
  m.cycles_to_steady = cycles_to_steady;
  m.measured_cycles = n;
  const HarmonicCycle all = first_harmonics(first, last);
  m.amplitude_m = all.amplitude_m();
  m.phase_rad = all.phase_rad();
  double lowest = m.amplitude_m, highest = m.amplitude_m;
  for (std::size_t k = 1; k < boundaries.size(); ++k) {
    const double x = first_harmonics(boundaries[k - 1], boundaries[k]).amplitude_m();
    lowest = std::min(lowest, x);
    highest = std::max(highest, x);
  }
  m.amplitude_spread_m = highest - lowest;
  const bool force = drive.mode == ExcitationMode::force;
  m.normalised_amplitude = m.amplitude_m / (force ? drive.level / drive.stiffness_N_m : drive.level);
  const double w = drive.omega_rad_s;
  if (drive.gravity_m_s2 > 0.0) m.gamma = m.amplitude_m * w * w / drive.gravity_m_s2;

  const EnergyLedger &e0 = first.energy, &e1 = last.energy;
  m.impact_J_per_cycle = (e1.dissipated_impact_J - e0.dissipated_impact_J) / n;
  m.friction_J_per_cycle = (e1.dissipated_friction_J - e0.dissipated_friction_J) / n;
  m.viscous_J_per_cycle = (e1.dissipated_viscous_J - e0.dissipated_viscous_J) / n;
  const double stretch_m = force ? m.amplitude_m : std::hypot(all.z_sin_m - drive.level, all.z_cos_m);
  const double d_cycle = m.impact_J_per_cycle + m.friction_J_per_cycle + m.viscous_J_per_cycle;
  m.loss_factor = d_cycle / (2.0 * std::numbers::pi * 0.5 * drive.stiffness_N_m * stretch_m * stretch_m);

  const ApparentLoad load = apparent_load(all, w);
  m.apparent_mass_kg = load.mass_kg;
  m.equivalent_damping_N_s_m = load.damping_N_s_m;
  return m;
}

}  // namespace pdamp
