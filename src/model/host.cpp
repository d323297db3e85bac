#include "pdamp/model/host.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace pdamp {

HostModel::HostModel(const Scenario& scenario)
    : mode_(scenario.excitation.mode),
      mass_kg_(scenario.host.mass_kg),
      stiffness_N_m_(scenario.host.stiffness_N_m),
      damping_N_s_m_(scenario.host.damping_N_s_m),
      z0_m_(scenario.host.z0_m),
      v0_m_s_(scenario.host.v0_m_s),
      amplitude_m_(scenario.excitation.amplitude_m),
      force_N_(scenario.excitation.force_N),
      omega_(scenario.excitation.angular_frequency_rad_s()),
      phase_rad_(scenario.excitation.phase_rad) {
  const double cos_phase = std::cos(phase_rad_), sin_phase = std::sin(phase_rad_);
  if (mode_ == ExcitationMode::base_motion) {
    // K y + C y' with y = A sin(ωt + φ), expanded in sin ωt and cos ωt.
    const double k_amp = stiffness_N_m_ * amplitude_m_, c_amp = damping_N_s_m_ * amplitude_m_ * omega_;
    forcing_sin_N_ = k_amp * cos_phase - c_amp * sin_phase;
    forcing_cos_N_ = k_amp * sin_phase + c_amp * cos_phase;
  } else if (mode_ == ExcitationMode::force) {
    forcing_sin_N_ = force_N_ * cos_phase;
    forcing_cos_N_ = force_N_ * sin_phase;
  }
}

HostModel::Harmonic HostModel::forced_response(double added_mass_kg, double added_damping_N_s_m) const {
  if (mode_ != ExcitationMode::base_motion && mode_ != ExcitationMode::force) return {};
  // Particular solution P sin ωt + Q cos ωt of M z'' + C z' + K z = a sin ωt + b cos ωt.
  const double a = forcing_sin_N_, b = forcing_cos_N_, w = omega_;
  const double mass_kg = mass_kg_ + added_mass_kg;
  const double kd = stiffness_N_m_ - mass_kg * w * w, cd = (damping_N_s_m_ + added_damping_N_s_m) * w;
  const double det = kd * kd + cd * cd;
  return {(kd * a + cd * b) / det, (kd * b - cd * a) / det};
}

HostState HostModel::initial_state() const {
  if (has_infinite_mass()) return prescribed_state(0.0);
  return {z0_m_, v0_m_s_};
}

double HostModel::base_position_m(double t_s) const {
  return mode_ == ExcitationMode::base_motion ? amplitude_m_ * std::sin(omega_ * t_s + phase_rad_) : 0.0;
}

double HostModel::base_velocity_m_s(double t_s) const {
  return mode_ == ExcitationMode::base_motion ? amplitude_m_ * omega_ * std::cos(omega_ * t_s + phase_rad_) : 0.0;
}

double HostModel::applied_force_N(double t_s) const {
  return mode_ == ExcitationMode::force ? force_N_ * std::sin(omega_ * t_s + phase_rad_) : 0.0;
}

HostState HostModel::prescribed_state(double t_s) const {
  const double angle = omega_ * t_s + phase_rad_;
  return {amplitude_m_ * std::sin(angle), amplitude_m_ * omega_ * std::cos(angle)};
}

double HostModel::prescribed_acceleration_m_s2(double t_s) const {
  return -amplitude_m_ * omega_ * omega_ * std::sin(omega_ * t_s + phase_rad_);
}

double HostModel::force_N(double t_s, const HostState& s) const {
  return -stiffness_N_m_ * (s.z_m - base_position_m(t_s)) - damping_N_s_m_ * (s.v_m_s - base_velocity_m_s(t_s)) +
         applied_force_N(t_s);
}

double HostModel::spring_energy_J(double t_s, double z_m) const {
  if (has_infinite_mass()) return 0.0;
  const double stretch = z_m - base_position_m(t_s);
  return 0.5 * stiffness_N_m_ * stretch * stretch;
}

double HostModel::natural_angular_frequency_rad_s() const { return std::sqrt(stiffness_N_m_ / mass_kg_); }

void HostModel::write_energy_to(EnergyLedger& ledger, double t_s, const HostState& s) const {
  ledger.host_counts = !has_infinite_mass();
  ledger.host_kinetic_J = 0.5 * mass_kg_ * s.v_m_s * s.v_m_s;
  ledger.spring_potential_J = spring_energy_J(t_s, s.z_m);
}

double HostModel::viscous_power_W(double t_s, double v_m_s) const {
  if (has_infinite_mass()) return 0.0;
  const double rate = v_m_s - base_velocity_m_s(t_s);
  return damping_N_s_m_ * rate * rate;
}

double HostModel::excitation_power_W(double t_s, const HostState& s) const {
  switch (mode_) {
    case ExcitationMode::force:
      return applied_force_N(t_s) * s.v_m_s;
    case ExcitationMode::base_motion: {
      const double y_dot = base_velocity_m_s(t_s);
      return -(stiffness_N_m_ * (s.z_m - base_position_m(t_s)) + damping_N_s_m_ * (s.v_m_s - y_dot)) * y_dot;
    }
    default:
      return 0.0;
  }
}

namespace {

/// e^{−αs}·C(s) and e^{−αs}·S(s), where C'' = −λC, S'' = −λS, C(0) = 1, C'(0) = 0,
/// S(0) = 0, S'(0) = 1: cos/sin (λ > 0), 1/s (λ = 0), cosh/sinh (λ < 0), computed
/// without the cancellation that the separate formulas suffer near critical damping.
struct DampedBasis {
  double c, s;
};

DampedBasis damped_basis(double alpha, double lambda, double s) {
  const double x = lambda * s * s;
  if (std::abs(x) < 1e-2) {
    // Taylor series; the first omitted terms are below 3e-17 relative.
    const double c = 1 - x / 2 * (1 - x / 12 * (1 - x / 30 * (1 - x / 56)));
    const double sn = s * (1 - x / 6 * (1 - x / 20 * (1 - x / 42 * (1 - x / 72))));
    const double decay = std::exp(-alpha * s);
    return {decay * c, decay * sn};
  }
  if (lambda > 0) {
    const double w = std::sqrt(lambda), decay = std::exp(-alpha * s);
    return {decay * std::cos(w * s), decay * std::sin(w * s) / w};
  }
  // Over-damped: e^{−αs} cosh(bs) = (e^{(b−α)s} + e^{−(α+b)s}) / 2, overflow-free.
  const double b = std::sqrt(-lambda);
  const double slow = std::exp((b - alpha) * s), fast = std::exp(-(alpha + b) * s);
  return {0.5 * (slow + fast), 0.5 * (slow - fast) / b};
}

// 8-point Gauss–Legendre nodes and weights on [−1, 1].
constexpr std::array<double, 8> gl_nodes{-0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                                         -0.1834346424956498, 0.1834346424956498,  0.5255324099163290,
                                         0.7966664774136267,  0.9602898564975363};
constexpr std::array<double, 8> gl_weights{0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                                           0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                                           0.2223810344533745, 0.1012285362903763};

}  // namespace

HostTrajectory::HostTrajectory(const HostModel& model, double t0_s, HostState start, double added_mass_kg,
                               double added_force_N)
    : model_(&model), t0_s_(t0_s), mass_kg_(model.mass_kg() + added_mass_kg) {
  const double w = model.angular_frequency_rad_s();
  if (model.has_infinite_mass()) {
    const double amplitude = model.motion_amplitude_m();
    speed_bound_ = amplitude * w;
    acceleration_bound_ = amplitude * w * w;
    jerk_bound_ = amplitude * w * w * w;
    fastest_rate_1_s_ = w;
    return;
  }
  const double k = model.stiffness_N_m(), c = model.damping_N_s_m();
  offset_m_ = added_force_N / k;
  const HostModel::Harmonic forced = model.forced_response(added_mass_kg, 0.0);
  forced_sin_m_ = forced.sin_m;
  forced_cos_m_ = forced.cos_m;
  const double forced_z = forced_sin_m_ * std::sin(w * t0_s) + forced_cos_m_ * std::cos(w * t0_s);
  const double forced_v = w * (forced_sin_m_ * std::cos(w * t0_s) - forced_cos_m_ * std::sin(w * t0_s));
  u0_m_ = start.z_m - offset_m_ - forced_z;
  du0_m_s_ = start.v_m_s - forced_v;
  decay_rate_1_s_ = c / (2.0 * mass_kg_);
  omega0_sq_ = k / mass_kg_;
  lambda_1_s2_ = omega0_sq_ - decay_rate_1_s_ * decay_rate_1_s_;

  // The free part's energy ½u'² + ½ω0²u² never grows, which bounds u' and u'' = −2αu' − ω0²u.
  const double omega0 = std::sqrt(omega0_sq_);
  const double free_speed = std::sqrt(du0_m_s_ * du0_m_s_ + omega0_sq_ * u0_m_ * u0_m_);
  double free_speed_bound = free_speed;
  double free_acceleration_bound = (2.0 * decay_rate_1_s_ + omega0) * free_speed;
  if (lambda_1_s2_ < 0.0) {
    // Over-damped, u = A e^{r1 s} + B e^{r2 s}: a far tighter bound when damping is heavy.
    const double b = std::sqrt(-lambda_1_s2_), r1 = -decay_rate_1_s_ + b, r2 = -decay_rate_1_s_ - b;
    const double a_coef = (du0_m_s_ - r2 * u0_m_) / (2.0 * b), b_coef = (r1 * u0_m_ - du0_m_s_) / (2.0 * b);
    free_speed_bound = std::min(free_speed_bound, std::abs(a_coef * r1) + std::abs(b_coef * r2));
    free_acceleration_bound =
        std::min(free_acceleration_bound, std::abs(a_coef * r1 * r1) + std::abs(b_coef * r2 * r2));
  }
  const double forced_amplitude = std::hypot(forced_sin_m_, forced_cos_m_);
  speed_bound_ = free_speed_bound + w * forced_amplitude;
  acceleration_bound_ = free_acceleration_bound + w * w * forced_amplitude;
  fastest_rate_1_s_ = std::max({omega0, w, 2.0 * decay_rate_1_s_});
  // M z''' = −K (z' − y') − C (z'' − y'') + F'(t), term by term.
  const double base_amplitude = model.mode() == ExcitationMode::base_motion ? model.motion_amplitude_m() : 0.0;
  const double force_amplitude =
      model.mode() == ExcitationMode::force ? std::hypot(model.forcing_sin_N(), model.forcing_cos_N()) : 0.0;
  jerk_bound_ = (k * (speed_bound_ + base_amplitude * w) + c * (acceleration_bound_ + base_amplitude * w * w) +
                 force_amplitude * w) /
                mass_kg_;
}

HostState HostTrajectory::at(double t_s) const {
  if (model_->has_infinite_mass()) return model_->prescribed_state(t_s);
  const double w = model_->angular_frequency_rad_s();
  const double s = t_s - t0_s_;
  const auto [ec, es] = damped_basis(decay_rate_1_s_, lambda_1_s2_, s);
  const double alpha = decay_rate_1_s_;
  const double u = u0_m_ * ec + (du0_m_s_ + alpha * u0_m_) * es;
  const double du = du0_m_s_ * ec - (omega0_sq_ * u0_m_ + alpha * du0_m_s_) * es;
  // Without a forced harmonic (a free host) its terms are zeros: no sin ωt and cos ωt.
  if (forced_sin_m_ == 0.0 && forced_cos_m_ == 0.0) return {offset_m_ + u, du};
  const double sin_wt = std::sin(w * t_s), cos_wt = std::cos(w * t_s);
  return {offset_m_ + forced_sin_m_ * sin_wt + forced_cos_m_ * cos_wt + u,
          w * (forced_sin_m_ * cos_wt - forced_cos_m_ * sin_wt) + du};
}

double HostTrajectory::acceleration_m_s2(double t_s) const { return acceleration_m_s2(t_s, at(t_s)); }

double HostTrajectory::acceleration_m_s2(double t_s, const HostState& state) const {
  if (model_->has_infinite_mass()) return model_->prescribed_acceleration_m_s2(t_s);
  return (model_->force_N(t_s, state) + model_->stiffness_N_m() * offset_m_) / mass_kg_;
}

template <std::size_t N, class Integrand>
std::array<double, N> HostTrajectory::integrate(double from_s, double to_s, Integrand f) const {
  std::array<double, N> sum{};
  if (to_s <= from_s) return sum;
  const double span = to_s - from_s;
  const auto panels = static_cast<long>(std::ceil(span * fastest_rate_1_s_)) + 1;
  const double h = span / static_cast<double>(panels);
  for (long p = 0; p < panels; ++p) {
    const double mid = from_s + (static_cast<double>(p) + 0.5) * h;
    std::array<double, N> panel{};
    for (std::size_t i = 0; i < gl_nodes.size(); ++i) {
      const std::array<double, N> value = f(mid + 0.5 * h * gl_nodes[i]);
      for (std::size_t k = 0; k < N; ++k) panel[k] += gl_weights[i] * value[k];
    }
    for (std::size_t k = 0; k < N; ++k) sum[k] += 0.5 * h * panel[k];
  }
  return sum;
}

HostTrajectory::Stretch HostTrajectory::stretch(double from_s, double to_s, double riding_mass_kg,
                                                double gravity_z_m_s2) const {
  const bool viscous = !model_->has_infinite_mass() && model_->damping_N_s_m() != 0.0;
  const bool driven = model_->mode() == ExcitationMode::base_motion || model_->mode() == ExcitationMode::force;
  const bool own = !model_->has_infinite_mass();
  const ExcitationPhase phase = model_->excitation_phase();
  const std::array<double, 9> sums = integrate<9>(from_s, to_s, [&](double t) {
    const HostState s = at(t);
    const ExcitationPhase::Weights w = phase.at(t);
    const double riders_N = riding_mass_kg > 0.0 ? riding_mass_kg * (gravity_z_m_s2 - acceleration_m_s2(t, s)) : 0.0;
    return std::array<double, 9>{viscous ? model_->viscous_power_W(t, s.v_m_s) : 0.0,
                                 driven ? model_->excitation_power_W(t, s) : 0.0,
                                 riders_N,
                                 riders_N * w.sin,
                                 riders_N * w.cos,
                                 own ? model_->force_N(t, s) : 0.0,
                                 s.z_m,
                                 s.z_m * w.sin,
                                 s.z_m * w.cos};
  });
  return {sums[0], sums[1], {sums[2], sums[3], sums[4], sums[5], sums[6], sums[7], sums[8]}};
}

}  // namespace pdamp
