#include "hard/collision_rules.hpp"

#include <cmath>

#include "pdamp/model/hertz_contact.hpp"

namespace pdamp::hard {

Eigen::Vector3d apply_mobility(const Mobility& m, const Eigen::Vector3d& n, const Eigen::Vector3d& p) {
  const double pn = n.dot(p);
  Eigen::Vector3d k = m.tangential_1_kg * p + (m.normal_1_kg - m.tangential_1_kg) * pn * n;
  k.z() += m.host_1_kg * p.z();
  return k;
}

namespace {

/// K⁻¹·x by Sherman–Morrison: K = K0 + h e_z e_zᵀ with K0⁻¹ = nnᵀ/a + (I − nnᵀ)/b.
Eigen::Vector3d solve_mobility(const Mobility& m, const Eigen::Vector3d& n, const Eigen::Vector3d& x) {
  auto k0_inverse = [&](const Eigen::Vector3d& v) -> Eigen::Vector3d {
    const double vn = n.dot(v);
    return v / m.tangential_1_kg + (1.0 / m.normal_1_kg - 1.0 / m.tangential_1_kg) * vn * n;
  };
  Eigen::Vector3d y = k0_inverse(x);
  if (m.host_1_kg == 0.0) return y;
  const Eigen::Vector3d w = k0_inverse(Eigen::Vector3d::UnitZ());  // K0⁻¹ e_z (K0 is symmetric)
  return y - (m.host_1_kg * w.dot(x) / (1.0 + m.host_1_kg * w.z())) * w;
}

/// n·K·x for the unit normal n, from the mobility's parameters: K n = a n + h n_z e_z, so
/// n·K·x = a n·x + h n_z x_z. (Going through K n, n·K·n = b + (a − b) rounds differently
/// from a, by the same relative amount at every collision of the same spheres, and an
/// elastic gas drifted in energy by that bias.)
double normal_mobility(const Mobility& m, const Eigen::Vector3d& n, const Eigen::Vector3d& x) {
  return m.normal_1_kg * n.dot(x) + m.host_1_kg * n.z() * x.z();
}

/// Sliding at once, with no tangential impulse: λ from n·(u + K p) = −e_n u_n alone (the
/// sliding branch below with μ = 0, to the bit, without solving for a sticking impulse
/// that it would only drop).
Eigen::Vector3d frictionless_impulse(const Mobility& m, const Eigen::Vector3d& n, double u_n, double restitution) {
  return -((1.0 + restitution) * u_n / normal_mobility(m, n, n)) * n;
}

Eigen::Vector3d frictional_impulse(const Mobility& m, const Eigen::Vector3d& n, double u_n, const Eigen::Vector3d& u_t,
                                   const HardContactLaw& law, bool& sticking) {
  const double restitution = law.en;
  const Eigen::Vector3d target_change = -(1.0 + restitution) * u_n * n - (1.0 + law.beta0) * u_t;
  Eigen::Vector3d p = solve_mobility(m, n, target_change);
  const double normal_impulse = -p.dot(n);
  const Eigen::Vector3d p_t = p + normal_impulse * n;
  const double p_t_norm = p_t.norm();
  sticking = p_t_norm <= law.mu * normal_impulse;
  if (sticking) return p;
  // Sliding: tangential impulse μλ along the sticking impulse's tangential direction,
  // λ from n·(u + K p) = −e_n u_n.
  const Eigen::Vector3d t_hat = p_t / p_t_norm;
  const double denominator = normal_mobility(m, n, n) - law.mu * normal_mobility(m, n, t_hat);
  // Positive unless a light host couples friction into the normal direction more than
  // the spheres resist it; then the sticking impulse stands.
  if (!(denominator > 0.0)) return p;
  const double lambda = (1.0 + restitution) * u_n / denominator;
  return -lambda * n + law.mu * lambda * t_hat;
}

}  // namespace

CollisionOutcome walton_collision(const Eigen::Vector3d& u, const Eigen::Vector3d& n, double u_n,
                                  const Mobility& mobility, const HardContactLaw& law) {
  CollisionOutcome out;
  if (!(u_n > 0.0)) return out;
  const Eigen::Vector3d u_t = u - u.dot(n) * n;
  out.impulse_N_s = law.mu == 0.0 ? frictionless_impulse(mobility, n, u_n, law.en)
                                  : frictional_impulse(mobility, n, u_n, u_t, law, out.sticking);
  const Eigen::Vector3d& p = out.impulse_N_s;
  const Eigen::Vector3d mean_velocity = u_t + u_n * n + 0.5 * apply_mobility(mobility, n, p);
  const double p_n = p.dot(n);
  out.impact_J = -p_n * n.dot(mean_velocity);
  out.friction_J = -(p - p_n * n).dot(mean_velocity - n.dot(mean_velocity) * n);
  return out;
}

ContactLaws::ContactLaws(const Scenario& scenario, const RestitutionTable* calibration)
    : sphere_(scenario.hard_particle),
      wall_(scenario.hard_wall),
      calibration_(calibration ? std::optional<RestitutionTable>(*calibration) : std::nullopt),
      elastic_speed_m_s_(scenario.hard_resting.elastic_speed_m_s),
      side_wall_elastic_speed_m_s_(scenario.hard_resting.side_wall_elastic_speed_m_s),
      tc_window_(scenario.hard_resting.tc_window),
      sphere_kn_N_m1_5_(scenario.soft_particle.kn_N_m1_5),
      wall_kn_N_m1_5_(scenario.soft_wall.kn_N_m1_5) {}

bool ContactLaws::within_tc_window(double since_s, double effective_mass_kg, bool wall,
                                   double approach_speed_m_s) const {
  return since_s < tc_window_ * hertz_contact_time_s(effective_mass_kg, wall ? wall_kn_N_m1_5_ : sphere_kn_N_m1_5_,
                                                     approach_speed_m_s);
}

HardContactLaw ContactLaws::at(double approach_speed_m_s, Partner partner, bool repeat, bool lasting) const {
  const bool wall = partner != Partner::sphere;
  HardContactLaw law = wall ? wall_ : sphere_;
  if (calibration_) {
    const RestitutionCurve& curve = wall ? calibration_->sphere_wall : calibration_->sphere_sphere;
    law.en = curve.en_at(approach_speed_m_s);
    law.beta0 = curve.beta0_at(approach_speed_m_s);
  }
  const double elastic_speed_m_s = partner == Partner::side_wall ? side_wall_elastic_speed_m_s_ : elastic_speed_m_s_;
  if ((approach_speed_m_s < elastic_speed_m_s || lasting) && !repeat) law.en = 1.0;
  return law;
}

VerticalSticking stick_vertically(double mass_kg, double vz_m_s, double host_v_m_s, bool prescribed,
                                  double carried_mass_kg) {
  const double relative_vz = vz_m_s - host_v_m_s;
  if (prescribed) {
    return {0.5 * mass_kg * relative_vz * relative_vz, host_v_m_s, mass_kg * (host_v_m_s - vz_m_s) * host_v_m_s,
            mass_kg * (host_v_m_s - vz_m_s)};
  }
  const double host_v_after_m_s = (carried_mass_kg * host_v_m_s + mass_kg * vz_m_s) / (carried_mass_kg + mass_kg);
  return {0.5 * mass_kg * carried_mass_kg / (mass_kg + carried_mass_kg) * relative_vz * relative_vz, host_v_after_m_s,
          0.0, mass_kg * (host_v_after_m_s - vz_m_s)};
}

Eigen::Vector2d turned_along_side_wall(const Eigen::Vector2d& v, const Eigen::Vector2d& outward,
                                       double floor_speed_m_s) {
  const double leaving = -v.dot(outward);
  const double speed_sq = v.squaredNorm();
  if (leaving >= floor_speed_m_s || speed_sq <= floor_speed_m_s * floor_speed_m_s) return v;
  const Eigen::Vector2d along = (v + leaving * outward).normalized();
  return -floor_speed_m_s * outward + std::sqrt(speed_sq - floor_speed_m_s * floor_speed_m_s) * along;
}

}  // namespace pdamp::hard
