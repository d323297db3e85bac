#include "hard/event_prediction.hpp"

#include <algorithm>
#include <cmath>

namespace pdamp::hard {

Approach cap_contact(const Ballistic& flight, double radius_m, bool top, double height_m, const HostTrajectory& host,
                     const HostState& host_at_t0, const Eigen::Vector3d& g, double t0, double t1, double tolerance_m,
                     double min_closing_rate_m_s) {
  // Bottom: gap = z − r − z_h; top: gap = z_h + H − z − r. gap'' = ±(g_z − z_h''), and
  // |gap'''| = |z_h'''|.
  const double sign = top ? -1.0 : 1.0;
  auto gap = [&](double t) {
    const HostState h = t == t0 ? host_at_t0 : host.at(t);
    const double vz = flight.velocity_at(t, g).z();
    return GapSample{cap_gap_m(flight, radius_m, top, height_m, h, g, t), sign * (vz - h.v_m_s),
                     sign * (g.z() - host.acceleration_m_s2(t, h))};
  };
  return earliest_contact(gap, t0, t1, std::abs(g.z()) + host.acceleration_bound_m_s2(), tolerance_m,
                          min_closing_rate_m_s, host.jerk_bound_m_s3());
}

Approach rider_contact(const Ballistic& flight, const Eigen::Vector3d& rider_m, double contact_distance_m,
                       const HostTrajectory& host, const HostState& host_at_t0, const Eigen::Vector3d& g, double t0,
                       double t1, double tolerance_m, double min_closing_rate_m_s) {
  // The surface gap d = |dx| − σ has d'' = (|dv|² − d'²)/|dx| + dx·da/|dx|, so while the
  // spheres are apart (|dx| ≥ σ) |d''| ≤ V²/σ + A, with A = |g| + |z_h''|max bounding the
  // relative acceleration and V = |dv(t0)| + A (t1 − t0) the relative speed.
  const double relative_acceleration = g.norm() + host.acceleration_bound_m_s2();
  Eigen::Vector3d dv0 = flight.velocity_at(t0, g);
  dv0.z() -= host_at_t0.v_m_s;
  const double relative_speed = dv0.norm() + relative_acceleration * (t1 - t0);
  const double curvature = relative_speed * relative_speed / contact_distance_m + relative_acceleration;
  auto gap = [&](double t) {
    const HostState h = t == t0 ? host_at_t0 : host.at(t);
    const Eigen::Vector3d dx = rider_offset_m(flight, rider_m, h, g, t);
    Eigen::Vector3d dv = flight.velocity_at(t, g);
    dv.z() -= h.v_m_s;
    const double distance = dx.norm();
    return GapSample{distance - contact_distance_m, dx.dot(dv) / distance};
  };
  return earliest_contact(gap, t0, t1, curvature, tolerance_m, min_closing_rate_m_s);
}

Approach side_wall_contact_curved(const Ballistic& flight, double reach_m, const Eigen::Vector3d& g, double t0,
                                  double t1, double tolerance_m) {
  // A parabola in x, y: f = reach² − |p|², |f''| = 2 |v|² + 2 p·g ≤ 2 (V² + reach |g_xy|).
  const Eigen::Vector2d g_xy = g.head<2>();
  const double speed = flight.velocity_at(t0, g).head<2>().norm() + g_xy.norm() * (t1 - t0);
  auto gap = [&](double t) {
    const Eigen::Vector2d p = flight.position_at(t, g).head<2>(), v = flight.velocity_at(t, g).head<2>();
    return GapSample{reach_m * reach_m - p.squaredNorm(), -2.0 * p.dot(v)};
  };
  return earliest_contact(gap, t0, t1, 2.0 * (speed * speed + reach_m * g_xy.norm()), 2.0 * reach_m * tolerance_m,
                          2.0 * reach_m * min_approach_speed_m_s);
}

Approach host_acceleration_crossing(const HostTrajectory& host, double level_m_s2, bool from_above, double t0,
                                    double t1, double tolerance_m_s2) {
  // First-order conservative advancement: |f'| ≤ jerk bound.
  constexpr int max_steps = 400;
  const double lipschitz = host.jerk_bound_m_s3();
  const double sign = from_above ? 1.0 : -1.0;
  double t = t0;
  for (int k = 0; k < max_steps && t < t1; ++k) {
    const double f = sign * (host.acceleration_m_s2(t) - level_m_s2);
    if (f <= tolerance_m_s2) return {t, true};
    if (lipschitz == 0.0) break;
    t += f / lipschitz;
  }
  return {lipschitz == 0.0 ? t1 : std::min(t, t1), false};
}

}  // namespace pdamp::hard
