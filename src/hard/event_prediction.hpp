#pragma once
/// When will it happen? Exact or provably conservative event times for spheres in free
/// flight under uniform gravity:
/// - sphere–sphere: both spheres feel the same gravity, so their relative motion is a
///   straight line and the contact time a quadratic root;
/// - plane crossings (cell faces, guards): a quadratic root;
/// - side wall: a quadratic root when gravity has no horizontal part, else a quartic,
///   found like the host-dependent events below;
/// - caps and spheres riding on the host, which move with the host's closed-form but
///   non-polynomial motion: conservative advancement (`earliest_contact`), which steps
///   only as far as a bound on the gap's curvature proves the gap cannot close, so it
///   can never skip an earlier contact.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>

#include "pdamp/model/host.hpp"
#include "simd/lanes.hpp"

namespace pdamp::hard {

inline constexpr double never = std::numeric_limits<double>::infinity();
/// Bodies that approach slower than this are touching, not colliding: it keeps round-off
/// in a velocity that a collision has just zeroed from scheduling another collision at
/// the same instant (m/s).
inline constexpr double min_approach_speed_m_s = 1e-12;

/// Two doubles side by side in one SSE2 register, from the lanes both engines share; each
/// lane rounds exactly as a double would. The predictions below run on the baseline's two
/// lanes whatever SimdPath is chosen.
using simd::Lanes2;
using simd::Mask2;

/// A sphere's free flight from (x0, v0) at t0 under gravity g.
struct Ballistic {
  Eigen::Vector3d x0_m;
  Eigen::Vector3d v0_m_s;
  double t0_s;
  Eigen::Vector3d position_at(double t_s, const Eigen::Vector3d& g) const {
    const double s = t_s - t0_s;
    return x0_m + s * (v0_m_s + 0.5 * s * g);
  }
  Eigen::Vector3d velocity_at(double t_s, const Eigen::Vector3d& g) const { return v0_m_s + (t_s - t0_s) * g; }
};

// Inline: these two run for every neighbour and cell face at every prediction.

/// The first s ≥ 0 at which gap + rate·s + ½ accel·s² reaches 0, or `never`, for a
/// double or lane by lane. A gap that round-off made negative counts as 0 (touching).
/// Both roots are computed and one is selected: whether a sphere approaches a face is a
/// coin toss, which lanes (compiled to blends) do not branch on.
template <class Real>
[[gnu::always_inline]] inline Real time_to_close(Real gap, Real rate, Real accel) {
  const Real zero{};
  gap = simd::blend(gap < 0.0, zero, gap);
  const Real discriminant = rate * rate - 2.0 * accel * gap;
  const Real root = simd::sqrt_of(simd::blend(discriminant < 0.0, zero, discriminant));
  const Real closing = 2.0 * gap / (root - rate);  // the smaller root, without cancellation
  const Real opening = (rate + root) / -accel;     // moving away, turned back by accel < 0
  const auto approaching = rate < 0.0;
  const auto misses = (approaching & (discriminant < 0.0)) | ((rate >= 0.0) & (accel >= 0.0));
  return simd::blend(misses, zero + never, simd::blend(approaching, closing, opening));
}

/// time_to_close lane by lane, to the bit, but by one division where no lane accelerates
/// (the faces in z and the host guards without gravity): √(rate²) is |rate| exactly, and
/// 2 gap / (|rate| − rate) = gap / −rate towards a plane approached (except where rate²
/// underflows, as in time_to_faces below; the division is right there too).
[[gnu::always_inline]] inline Lanes2 time_to_plane(Lanes2 gap, Lanes2 rate, Lanes2 accel) {
  if ((accel[0] != 0.0) | (accel[1] != 0.0)) return time_to_close(gap, rate, accel);
  const Lanes2 zero{};
  const auto approaching = rate < 0.0;
  gap = simd::blend(gap < 0.0, zero, gap);
  const Lanes2 time = gap / simd::blend(approaching, -rate, zero + 1.0);  // no 0/0 where it stays
  return simd::blend(approaching, time, zero + never);
}

/// The first s ≥ 0 at which a point between two planes per lane, `lower_gap` above the
/// lower and `upper_gap` below the upper, moving at `rate` with acceleration `accel`
/// along their normal, reaches each: time_to_close(lower_gap, rate, accel) and
/// time_to_close(upper_gap, −rate, −accel), to the bit. Without acceleration (the faces in
/// x and y under vertical gravity) that is one division, gap / |rate| towards the face
/// approached: √(rate²) is |rate| exactly, and 2 gap / (|rate| − rate) = gap / |rate|
/// (except below |rate| ≈ 10⁻¹⁵⁴ m/s, where rate² underflows and time_to_close doubles
/// the time; the division is right there too).
struct FaceTimes {
  Lanes2 to_lower, to_upper;
};
[[gnu::always_inline]] inline FaceTimes time_to_faces(Lanes2 lower_gap, Lanes2 upper_gap, Lanes2 rate, Lanes2 accel) {
  if ((accel[0] != 0.0) | (accel[1] != 0.0)) {
    return {time_to_close(lower_gap, rate, accel), time_to_close(upper_gap, -rate, -accel)};
  }
  const Lanes2 zero{}, none = zero + never;
  const auto falling = rate < 0.0;
  const auto rising = rate > 0.0;
  Lanes2 gap = simd::blend(falling, lower_gap, upper_gap);
  gap = simd::blend(gap < 0.0, zero, gap);
  const Lanes2 speed = simd::blend(falling, -rate, rate);
  const Lanes2 time = gap / simd::blend(falling | rising, speed, zero + 1.0);  // no 0/0 where it stays
  return {simd::blend(falling, time, none), simd::blend(rising, time, none)};
}

/// The contact test of two spheres whose centres are dx = x_i − x_j apart and move with
/// dv = v_i − v_j: |dx + dv s|² = σ² reads c + 2 b s + |dv|² s² = 0.
struct PairQuadratic {
  double b = 0.0;             ///< dx·dv: < 0 while they approach
  double c = 0.0;             ///< |dx|² − σ²: ≤ 0 if they touch or overlap
  double discriminant = 0.0;  ///< b² − |dv|² c: < 0 if they miss each other

  /// From the components of dx and dv (written out, so that a loop over pairs vectorises).
  static PairQuadratic of(double dx, double dy, double dz, double dvx, double dvy, double dvz,
                          double contact_distance_m) {
    const double b = (dx * dvx + dy * dvy) + dz * dvz;
    const double c = ((dx * dx + dy * dy) + dz * dz) - contact_distance_m * contact_distance_m;
    return {b, c, b * b - ((dvx * dvx + dvy * dvy) + dvz * dvz) * c};
  }
  static PairQuadratic of(const Eigen::Vector3d& dx, const Eigen::Vector3d& dv, double contact_distance_m) {
    return of(dx.x(), dx.y(), dx.z(), dv.x(), dv.y(), dv.z(), contact_distance_m);
  }
  /// Whether they approach and meet (or already overlap). Free of branches: whether a
  /// neighbour approaches is a coin toss, and a mispredicted branch costs more than the test.
  bool meets(double contact_distance_m) const {
    return (b < -min_approach_speed_m_s * contact_distance_m) & ((c <= 0) | (discriminant >= 0));
  }
  /// When they meet (0 if they overlap), given meets().
  double time_s() const {
    return c <= 0 ? 0.0 : c / (std::sqrt(discriminant) - b);
  }  // the smaller root, without cancellation
};

/// The first s ≥ 0 at which two spheres, centres dx = x_i − x_j apart moving with
/// dv = v_i − v_j, come within `contact_distance_m`; 0 if they already overlap and
/// approach; `never` if they do not meet.
inline double sphere_sphere_time(const Eigen::Vector3d& dx, const Eigen::Vector3d& dv, double contact_distance_m) {
  const PairQuadratic pair = PairQuadratic::of(dx, dv, contact_distance_m);
  return pair.meets(contact_distance_m) ? pair.time_s() : never;
}

/// A closing rate for `earliest_contact` that makes it report the first time the gap is
/// within the tolerance, closing or not: the question a margin asks.
inline constexpr double within_margin = -never;

/// Result of a conservative search on [t0, t1]: a contact at t_s, or none before t_s
/// (t1, or the point where the search stopped early and must be resumed).
struct Approach {
  double t_s;
  bool contact;
};

struct GapSample {
  double value;
  double rate;
  /// gap'' now, where it is cheap to know (caps); −∞ where it is not.
  double acceleration = -never;
};

/// A step that cannot skip a contact, from the gap's acceleration a > 0 and a bound J
/// on |gap'''|: up to s = 1.5 a/J the jerk takes at most half of ½ a s², so the gap stays
/// above value + rate·s + ¼ a s². It lets a sphere that touches a receding cap wait for
/// the cap's acceleration to turn, where the curvature bound alone would creep along in
/// steps of √(2·tolerance/bound). 0 when it does not apply.
inline double jerk_limited_step(double value, double rate, double acceleration, double jerk_bound) {
  if (!(acceleration > 0.0)) return 0.0;
  const double horizon = jerk_bound > 0.0 ? 1.5 * acceleration / jerk_bound : never;
  const double discriminant = rate * rate - acceleration * value;  // of value + rate·s + ¼ a s²
  if (rate >= 0.0 || discriminant < 0.0) return horizon;
  return std::min(horizon, 2.0 * value / (std::sqrt(discriminant) - rate));  // the first root
}

/// The first t in [t0, t1] where gap(t) ≤ tolerance while closing faster than
/// `min_closing_rate` (in the gap's units per second), given |gap''| ≤
/// curvature_bound on [t0, t1]. Each step h keeps the lower bound
/// gap + rate·h − ½·bound·h² ≥ 0, so no contact lies inside a step; near a contact the
/// steps shrink quadratically (Newton from the safe side); past a grazing minimum they
/// grow again. Unless closing, steps are at least √(2·tolerance/bound), so an overlap is
/// never deeper than about `tolerance`. With the gap's acceleration in the samples and a
/// `jerk_bound` on |gap'''|, a step is also as long as jerk_limited_step allows.
template <class Gap>
Approach earliest_contact(Gap gap, double t0, double t1, double curvature_bound, double tolerance,
                          double min_closing_rate, double jerk_bound = never) {
  constexpr int max_steps = 200;
  const double bound = curvature_bound > 0 ? curvature_bound : std::numeric_limits<double>::min();
  const double min_step = std::sqrt(2.0 * tolerance / bound);
  double t = t0;
  for (int k = 0; k < max_steps && t < t1; ++k) {
    const GapSample s = gap(t);
    if (s.value <= tolerance && s.rate < -min_closing_rate) return {t, true};
    const double v = std::max(s.value, 0.0);
    const double root = std::sqrt(s.rate * s.rate + 2.0 * bound * v);
    const double h = std::max(s.rate < 0 ? 2.0 * v / (root - s.rate) : (s.rate + root) / bound,
                              jerk_limited_step(v, s.rate, s.acceleration, jerk_bound));
    // Closing: the safe steps converge like Newton's. Touching without closing: the
    // minimum step gets past the stagnation and dips at most `tolerance` below zero.
    t += s.rate < -min_closing_rate ? h : std::max(h, min_step);
  }
  return {std::min(t, t1), false};
}

/// Whether a gap of `gap_m` now, changing at `rate_m_s` with |gap''| ≤ `curvature_bound`,
/// surely stays above twice `tolerance_m` for `span_s`: then earliest_contact on that span
/// (whose samples count a gap within the tolerance) finds nothing, and need not run. The
/// lower bound gap + rate·s − ½·bound·s² is least at an end of the span; twice the
/// tolerance leaves the samples' round-off a tolerance to spare.
inline bool stays_apart(double gap_m, double rate_m_s, double curvature_bound, double span_s, double tolerance_m) {
  const double lowest = std::min(gap_m, gap_m + span_s * (rate_m_s - 0.5 * curvature_bound * span_s));
  return lowest > 2.0 * tolerance_m;
}

/// Whether a distance whose square is `squared_norm_m2` surely exceeds `distance_m` by
/// more than the round-off of a square root and a few additions (a relative 5·10⁻¹¹): then
/// a test of the distance, `std::sqrt(squared_norm_m2)` as Eigen's norm() takes it, against
/// `distance_m` or anything below it is settled without the square root. False where it
/// cannot tell (NaN, infinity). Most riders a sphere's search meets in a bed are a
/// diameter away: their tests end here.
inline bool surely_farther(double squared_norm_m2, double distance_m) {
  const double beyond = distance_m * (1.0 + 1e-10);
  return squared_norm_m2 > beyond * beyond;
}

/// A free sphere's gap to the bottom (z − r − z_h) or top (z_h + H − z − r) cap at time
/// t, the host then at `host` (cap_contact's gap, to the bit).
inline double cap_gap_m(const Ballistic& flight, double radius_m, bool top, double height_m, const HostState& host,
                        const Eigen::Vector3d& g, double t_s) {
  const double sign = top ? -1.0 : 1.0;
  const double offset = top ? radius_m - height_m : radius_m;
  return sign * (flight.position_at(t_s, g).z() - host.z_m) - offset;
}

/// A free sphere's centre relative to the lab position of a rider at host-frame `rider_m`
/// at time t, the host then at `host` (rider_contact's, to the bit).
inline Eigen::Vector3d rider_offset_m(const Ballistic& flight, const Eigen::Vector3d& rider_m, const HostState& host,
                                      const Eigen::Vector3d& g, double t_s) {
  Eigen::Vector3d dx = flight.position_at(t_s, g) - rider_m;
  dx.z() -= host.z_m;
  return dx;
}

/// The first contact of a free sphere with the bottom or top cap of a cavity of height
/// `height_m` moving with `host` (whose state at t0 the caller has at hand), on [t0, t1].
/// `min_closing_rate_m_s` as for earliest_contact; `within_margin` (−∞) reports the first
/// time the gap is within the tolerance whichever way it moves.
Approach cap_contact(const Ballistic& flight, double radius_m, bool top, double height_m, const HostTrajectory& host,
                     const HostState& host_at_t0, const Eigen::Vector3d& g, double t0, double t1, double tolerance_m,
                     double min_closing_rate_m_s = min_approach_speed_m_s);

/// The first contact of a free sphere with a sphere riding on the host at host-frame
/// position `rider_m` (lab position rider_m + z_host e_z), contact distance σ, on [t0, t1].
Approach rider_contact(const Ballistic& flight, const Eigen::Vector3d& rider_m, double contact_distance_m,
                       const HostTrajectory& host, const HostState& host_at_t0, const Eigen::Vector3d& g, double t0,
                       double t1, double tolerance_m, double min_closing_rate_m_s = min_approach_speed_m_s);

/// side_wall_contact where gravity has a horizontal part: a quartic, by conservative advancement.
Approach side_wall_contact_curved(const Ballistic& flight, double reach_m, const Eigen::Vector3d& g, double t0,
                                  double t1, double tolerance_m);

/// The first contact with the side wall (the centre reaching distance `reach_m` = R − r
/// from the axis) on [t0, t1]. Inline: under vertical gravity, the case of every
/// prediction near the wall, it is a quadratic root.
inline Approach side_wall_contact(const Ballistic& flight, double reach_m, const Eigen::Vector3d& g, double t0,
                                  double t1, double tolerance_m) {
  if (g.head<2>().squaredNorm() != 0.0) return side_wall_contact_curved(flight, reach_m, g, t0, t1, tolerance_m);
  // Straight line in x, y: |p + v s|² = reach², p inside.
  const Eigen::Vector2d p = flight.position_at(t0, g).head<2>(), v = flight.v0_m_s.head<2>();
  const double a = v.squaredNorm(), b = p.dot(v), c = p.squaredNorm() - reach_m * reach_m;
  if (a == 0.0) return {t1, false};
  const double root = std::sqrt(std::max(b * b - a * c, 0.0));
  const double closing = min_approach_speed_m_s * reach_m;  // p·v of the slowest approach that counts
  double s;
  if (c >= 0) {
    // Touching: now if moving out, when it comes back if moving in, and if sliding
    // along the wall when p·v = b + a s grows past the threshold.
    s = b > closing ? 0.0 : b < 0 ? -2.0 * b / a : (closing - b) / a;
  } else {
    s = b > 0 ? -c / (b + root) : (root - b) / a;
  }
  return t0 + s < t1 ? Approach{t0 + s, true} : Approach{t1, false};
}

/// The first t in [t0, t1] where the host's acceleration minus `level_m_s2` reaches 0
/// from the side it starts on (`from_above`), searched with the host's jerk bound.
Approach host_acceleration_crossing(const HostTrajectory& host, double level_m_s2, bool from_above, double t0,
                                    double t1, double tolerance_m_s2);

}  // namespace pdamp::hard
