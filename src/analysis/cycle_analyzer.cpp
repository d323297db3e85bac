#include "pdamp/analysis/cycle_analyzer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace pdamp {
namespace {

/// The extreme value of the parabola through three points (t0 < t1 < t2), if its vertex
/// lies between t0 and t2; otherwise the middle value.
double parabola_vertex(double t0, double y0, double t1, double y1, double t2, double y2) {
  const double slope01 = (y1 - y0) / (t1 - t0), slope12 = (y2 - y1) / (t2 - t1);
  const double curvature = (slope12 - slope01) / (t2 - t0);
  if (curvature == 0.0) return y1;
  const double t_vertex = 0.5 * (t0 + t1) - slope01 / (2.0 * curvature);
  if (t_vertex < t0 || t_vertex > t2) return y1;
  return y0 + (t_vertex - t0) * slope01 + curvature * (t_vertex - t0) * (t_vertex - t1);
}

}  // namespace

CycleAnalyzer::CycleAnalyzer(double host_mass_kg, double equilibrium_z_m, double vertical_gravity_m_s2)
    : mass_kg_(host_mass_kg), equilibrium_z_m_(equilibrium_z_m), gravity_m_s2_(vertical_gravity_m_s2) {}

void CycleAnalyzer::start_cycle(const Crest& crest) {
  crest_ = crest;
  armed_ = false;
  z_min_m_ = std::numeric_limits<double>::infinity();
  max_kinetic_J_ = 0.0;
}

std::optional<CycleRecord> CycleAnalyzer::feed(const Observation& now) {
  std::optional<CycleRecord> completed;
  if (previous_) {
    const Observation& p = *previous_;
    const double h = now.t_s - p.t_s;
    const double kinetic_now = 0.5 * mass_kg_ * now.host.v_m_s * now.host.v_m_s;
    max_kinetic_J_ = std::max(max_kinetic_J_, kinetic_now);
    if (before_previous_) {
      const Observation& b = *before_previous_;
      auto kinetic = [&](const Observation& o) { return 0.5 * mass_kg_ * o.host.v_m_s * o.host.v_m_s; };
      if (kinetic(p) >= kinetic(b) && kinetic(p) >= kinetic_now) {
        max_kinetic_J_ =
            std::max(max_kinetic_J_, parabola_vertex(b.t_s, kinetic(b), p.t_s, kinetic(p), now.t_s, kinetic_now));
      }
    }
    // Where the velocity changes sign, linear velocity gives the crossing time, and the
    // area under it the displacement there (exact to third order in the spacing).
    const bool sign_change = (p.host.v_m_s >= 0.0) != (now.host.v_m_s >= 0.0);
    if (sign_change && h > 0) {
      const double fraction = p.host.v_m_s / (p.host.v_m_s - now.host.v_m_s);
      const double t_cross = p.t_s + fraction * h;
      const double z_cross = p.host.z_m + 0.5 * p.host.v_m_s * fraction * h;
      if (now.host.v_m_s < 0.0) {
        if (armed_ && z_cross > equilibrium_z_m_) {
          auto lerp = [&](double a, double b) { return a + fraction * (b - a); };
          const Crest crest{t_cross, z_cross, lerp(p.energy.dissipated_impact_J, now.energy.dissipated_impact_J),
                            lerp(p.energy.dissipated_friction_J, now.energy.dissipated_friction_J),
                            lerp(p.energy.dissipated_viscous_J, now.energy.dissipated_viscous_J)};
          if (crest_ && max_kinetic_J_ > 0.0) {
            CycleRecord r;
            r.cycle = ++cycles_;
            r.t_start_s = crest_->t_s;
            r.t_end_s = crest.t_s;
            r.amplitude_m = 0.5 * (crest_->z_m - z_min_m_);
            r.freq_hz = 1.0 / (crest.t_s - crest_->t_s);
            const double omega = 2.0 * std::numbers::pi * r.freq_hz;
            if (gravity_m_s2_ > 0.0) r.gamma = r.amplitude_m * omega * omega / gravity_m_s2_;
            r.max_host_kinetic_J = max_kinetic_J_;
            r.psi_impact = (crest.impact_J - crest_->impact_J) / max_kinetic_J_;
            r.psi_friction = (crest.friction_J - crest_->friction_J) / max_kinetic_J_;
            r.psi_viscous = (crest.viscous_J - crest_->viscous_J) / max_kinetic_J_;
            r.psi = r.psi_impact + r.psi_friction + r.psi_viscous;
            completed = r;
          }
          start_cycle(crest);
        }
      } else {
        z_min_m_ = std::min(z_min_m_, z_cross);
      }
    }
  }
  z_min_m_ = std::min(z_min_m_, now.host.z_m);
  if (now.host.z_m < equilibrium_z_m_) armed_ = true;
  before_previous_ = previous_;
  previous_ = now;
  return completed;
}

}  // namespace pdamp
