#include "hard/host_coupling.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "pdamp/model/hertz_contact.hpp"

namespace pdamp::hard {

namespace {

/// The margins of the tiers (near, imminent, close), relative to the smallest radius: a
/// wider margin means rarer sweeps but more spheres in the tier inside it. Spheres of a
/// landing bed close in at ~1 cm/s, one host impulse per µs: each tier holds ~50 times
/// fewer spheres than the one outside it.
constexpr std::array<double, 3> margin_fractions{0.1, 0.002, 4e-5};

const Eigen::Vector3d e_z = Eigen::Vector3d::UnitZ();

/// The speed below which a sphere leaving a cap or rider rests: hard.rest_speed_m_s, but at
/// least the elastic speed (if resting is on). A sphere slower than that bounces elastically,
/// so it would leave its support as fast as it came, again and again, and never rest.
double resting_floor_m_s(const HardRestingSettings& resting) {
  return resting.rest_speed_m_s > 0.0 ? std::max(resting.rest_speed_m_s, resting.elastic_speed_m_s) : 0.0;
}

}  // namespace

HostCoupling::SearchBox::SearchBox(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& half_m) {
  for (int d = 0; d < 3; ++d) {
    low_m[d] = centre_m[d] - half_m[d];
    high_m[d] = centre_m[d] + half_m[d];
  }
}

bool HostCoupling::SearchBox::holds(const Eigen::Vector3d& p_m, double slack_m) const {
  bool inside = true;
  for (int d = 0; d < 3; ++d) inside &= p_m[d] + slack_m >= low_m[d] && p_m[d] - slack_m <= high_m[d];
  return inside;
}

HostCoupling::MarginTier HostCoupling::tier(std::size_t level, const Particles& initial) const {
  return {ParticleSet(static_cast<int>(initial.size())), margin_fractions[level] * initial.radius_m.minCoeff(),
          1.0 / fastest_rate_1_s_};
}

HostCoupling::HostCoupling(const Scenario& scenario, const Particles& initial, FreeFlight& flight, HardLedger& ledger)
    : flight_(flight),
      ledger_(ledger),
      gravity_m_s2_(scenario.gravity_m_s2),
      cavity_(scenario.cavity),
      model_(scenario),
      fastest_rate_1_s_(std::max(model_.angular_frequency_rad_s(), model_.natural_angular_frequency_rad_s())),
      rest_speed_m_s_(resting_floor_m_s(scenario.hard_resting)),
      rest_tc_window_(scenario.hard_resting.rest_tc_window),
      sphere_kn_N_m1_5_(scenario.soft_particle.kn_N_m1_5),
      wall_kn_N_m1_5_(scenario.soft_wall.kn_N_m1_5),
      trajectory_(model_, 0.0, model_.initial_state()),
      speed_envelope_m_s_(2.0 * trajectory_.speed_bound_m_s()),
      rider_cells_(flight.grid().cell_count(), static_cast<int>(initial.size())),
      tiers_{tier(0, initial), tier(1, initial), tier(2, initial)},
      touching_(static_cast<int>(initial.size())),
      touching_bound_(initial.size()),
      touching_slack_m_(0.01 * initial.radius_m.minCoeff()),
      searched_(initial.size()),
      top_rider_layer_(static_cast<int>(std::floor(cavity_.height_m() / flight.grid().cell_size_m()))) {}

// ---------------------------------------------------------------------------------------------
// The host's motion

bool HostCoupling::restart(HostState start, double t_s) {
  ++ledger_.counts.host_impulses;
  book(t_s);
  const HostState old = trajectory_.at(t_s);
  const Departure departure = this->departure(old, start, t_s);
  trajectory_ = HostTrajectory(model_, t_s, start, riding_mass_kg_, riding_mass_kg_ * gravity_m_s2_.z());
  trajectory_riding_mass_kg_ = riding_mass_kg_;
  ++epoch_;
  if (prescribed()) {
    // The motion is a function of time alone: the touching spheres' predictions stand,
    // but for their collisions with the riders that left.
    for (const Eigen::Vector3d& departed : departed_m_) repredict_near_around(departed, t_s);
    departed_m_.clear();
    predict_bed_release(t_s);
    return true;
  }
  if (trajectory_.speed_bound_m_s() > speed_envelope_m_s_) {
    departed_m_.clear();
    speed_envelope_m_s_ = 2.0 * trajectory_.speed_bound_m_s();
    return false;
  }
  for (MarginTier& tier : tiers_) {
    const double tau = tier.horizon_s;
    tier.budget_m += departure.velocity_m_s * tau + 0.5 * departure.acceleration_m_s2 * tau * tau;
  }
  // The outermost tier whose budget is spent is swept (with every tier inside it);
  // otherwise only the touching spheres need new predictions.
  const auto spent =
      std::find_if(tiers_.begin(), tiers_.end(), [](const MarginTier& t) { return t.budget_m >= t.margin_m; });
  if (spent != tiers_.end()) {
    sweep_tier(static_cast<std::size_t>(spent - tiers_.begin()), t_s);
  } else {
    touching_.sweep([&](int i) {
      if (!departed_from_box(i, t_s) && defer_touching(i, departure, t_s)) {
        ++ledger_.counts.touching_deferrals;
        touching_.insert(i);
        return;
      }
      ++ledger_.counts.touching_repredictions;
      predict_relative(i, tiers_.size() - 1, t_s);
    });
  }
  departed_m_.clear();
  predict_bed_release(t_s);
  return true;
}

HostCoupling::Departure HostCoupling::departure(const HostState& old, const HostState& start, double t_s) const {
  // The new trajectory minus the old one solves (M + m_new) d'' + C d' + K d =
  // Δm (g_z − z_old'') from d = 0 and d' = Δv, so d(s) = Δv h(s) + ∫ h(s − u) Δm (g_z −
  // z_old''(u)) / (M + m_new) du, with the homogeneous response 0 ≤ h(s) ≤ s for s up to
  // half a damped period, longer than any tier looks ahead (its horizon is at most 1/ω of
  // the host alone, the fastest). Hence the bound on |d|; and d goes all one way while the
  // force keeps the sign of Δv, which it does while |z_old''(u) − z_old''(t)| stays below
  // |g_z − z_old''(t)|, at least until the old trajectory's jerk bound lets it cross. A
  // sphere coming to rest pulls the host towards it while its weight pushes the host
  // away, so a collision and the sticking that ends it restart the host once
  // (HardEngine::rest_if_slow): together, the host gives way.
  const double velocity_change = start.v_m_s - old.v_m_s;
  const double mass_change = riding_mass_kg_ - trajectory_riding_mass_kg_;
  const double relative_gravity = gravity_m_s2_.z() - trajectory_.acceleration_m_s2(t_s, old);
  const double force = mass_change * relative_gravity;
  const int pushed = (velocity_change > 0.0) - (velocity_change < 0.0);
  const int forced = (force > 0.0) - (force < 0.0);
  Departure d{};
  d.direction = pushed * forced < 0 ? 0 : pushed + forced * (pushed == 0);
  d.velocity_m_s = std::abs(velocity_change);
  d.acceleration_m_s2 = std::abs(mass_change) * (std::abs(gravity_m_s2_.z()) + trajectory_.acceleration_bound_m_s2()) /
                        (model_.mass_kg() + riding_mass_kg_);
  d.until_s = never;
  if (mass_change != 0.0) {
    const double jerk = trajectory_.jerk_bound_m_s3();
    d.until_s = forced == 0 ? t_s : jerk > 0.0 ? t_s + std::abs(relative_gravity) / jerk : never;
  }
  return d;
}

bool HostCoupling::presses(double normal_z_from_support, const HostState& host, double t_s) const {
  // The support pushes the sphere while the relative gravity g − z_h'' points into it.
  const double relative_gravity_z = gravity_m_s2_.z() - trajectory_.acceleration_m_s2(t_s, host);
  return normal_z_from_support * relative_gravity_z < 0.0;
}

// ---------------------------------------------------------------------------------------------
// The resting bed

bool HostCoupling::rests(int i, int support, double leaving_m_s, double normal_z_from_support, const HostState& host,
                         double t_s) const {
  const int side = normal_z_from_support > 0 ? 1 : -1;
  const bool slow =
      leaving_m_s < rest_speed_m_s_ ||
      (rest_tc_window_ > 0.0 && leaving_m_s < rest_speed_m_s(i, support, normal_z_from_support, host, t_s));
  return slow && presses(normal_z_from_support, host, t_s) && (riding_count_ == 0 || bed_side_ == side);
}

double HostCoupling::rest_speed_m_s(int i, int support, double normal_z_from_support, const HostState& host,
                                    double t_s) const {
  if (rest_tc_window_ == 0.0) return rest_speed_m_s_;
  // The pressing acceleration along the normal: the relative gravity g − z_h'' into the support.
  const double pressing = -normal_z_from_support * (gravity_m_s2_.z() - trajectory_.acceleration_m_s2(t_s, host));
  const PackedParticles& particles = flight_.particles();
  const double m = particles.mass_kg[i];
  const double effective_mass = support < 0 ? m : m * particles.mass_kg[support] / (m + particles.mass_kg[support]);
  const double enduring = hertz_enduring_speed_m_s(effective_mass, support < 0 ? wall_kn_N_m1_5_ : sphere_kn_N_m1_5_,
                                                   pressing, rest_tc_window_);
  return std::max(rest_speed_m_s_, enduring);
}

HostCoupling::Attached HostCoupling::attach(int i, int side, int support, const HostState& host, double t_s) {
  ++ledger_.counts.rests;
  book(t_s);  // with the riding mass of the interval that ends now
  PackedParticles& particles = flight_.particles();
  const double m = particles.mass_kg[i];
  const Eigen::Vector3d v = particles.velocity_m_s.col(i);
  // The normal part of the loss is impact, the sliding and spinning that stop are friction.
  const double friction_J =
      0.5 * m * (v.x() * v.x() + v.y() * v.y()) +
      0.5 * particles.moment_of_inertia(i) * particles.angular_velocity_rad_s.col(i).squaredNorm();
  const VerticalSticking sticking = stick_vertically(m, v.z(), host.v_m_s, prescribed(), carried_mass_kg());
  take_impulse(-sticking.body_impulse_N_s, t_s);
  ledger_.friction_J += friction_J;
  ledger_.impact_J += sticking.loss_J;
  ledger_.book_sphere(i, sticking.loss_J, friction_J);
  if (prescribed()) ledger_.excitation_J += sticking.host_work_J;
  const Eigen::Vector3d lab_position = particles.position_m.col(i);
  flight_.leave_cell(i);
  leave_sets(i);
  flight_.new_trajectory(i);
  flight_.sphere(i).riding = 1;
  bed_side_ = side;
  Eigen::Vector3d host_frame = particles.position_m.col(i) - host.z_m * e_z;
  // A sphere that rests sits at contact with what it landed on, not within the root
  // finders' tolerance beyond it: a rider knocked off and landing again would otherwise
  // start each flight up to that tolerance deeper, and the overlap would ratchet.
  const double r = particles.radius_m[i];
  if (support >= 0) {
    const Eigen::Vector3d below = particles.position_m.col(support);
    const Eigen::Vector3d out = host_frame - below;
    const double contact = r + particles.radius_m[support], distance = out.norm();
    if (distance < contact) host_frame = below + out * (contact / distance);
  }
  host_frame.z() = side > 0 ? std::max(host_frame.z(), r) : std::min(host_frame.z(), cavity_.height_m() - r);
  particles.position_m.col(i) = host_frame;
  particles.velocity_m_s.col(i).setZero();
  particles.angular_velocity_rad_s.col(i).setZero();
  rider_cells_.insert(i, flight_.grid().cell_of(host_frame));
  riding_mass_kg_ += m;
  ++riding_count_;
  const double depth = bed_side_ > 0 ? host_frame.z() + r : cavity_.height_m() - host_frame.z() + r;
  const bool deeper = depth > bed_depth_bound_m_;
  if (deeper) bed_depth_bound_m_ = depth + flight_.grid().cell_size_m();
  return {{host.z_m, sticking.host_v_m_s}, deeper, lab_position};
}

void HostCoupling::detach(int i, const HostState& host, double t_s) {
  book(t_s);  // with the riding mass of the interval that ends now
  PackedParticles& particles = flight_.particles();
  rider_cells_.remove(i);
  flight_.sphere(i).riding = 0;
  flight_.new_trajectory(i);
  particles.position_m.col(i) += host.z_m * e_z;
  departed_m_.emplace_back(particles.position_m.col(i));
  particles.velocity_m_s.col(i) = host.v_m_s * e_z;
  particles.t_ref_s[i] = t_s;
  flight_.enter_cell(i, flight_.grid().coord_of(particles.position_m.col(i)));
  --riding_count_;
  riding_mass_kg_ = riding_count_ > 0 ? riding_mass_kg_ - particles.mass_kg[i] : 0.0;
}

// ---------------------------------------------------------------------------------------------
// Host-dependent predictions

void HostCoupling::predict_relative(int i, std::size_t first_level, double t_s) {
  const double t = t_s;
  const double horizon = flight_.sphere(i).t_cross_s;
  const std::uint32_t stamp = flight_.replace_host_events(i);
  // Down the tiers while the sphere is within each one's margin.
  for (std::size_t level = first_level; level < tiers_.size(); ++level) {
    const double end = std::min(horizon, t + tiers_[level].horizon_s);
    if (!within_host_margin(i, end, tiers_[level].margin_m, t)) {
      if (level == first_level && level > 0) {
        predict_relative(i, 0, t);  // it has left the tier it was in: from the top
        return;
      }
      for (std::size_t deeper = level + 1; deeper < tiers_.size(); ++deeper) tiers_[deeper].members.erase(i);
      touching_.erase(i);
      const HostContact margin = host_contact(i, end, tiers_[level].margin_m, t);
      searched_[i] = margin.searched;
      if (margin.when.t_s < horizon) {
        flight_.push({margin.when.t_s, i, static_cast<std::int32_t>(level), stamp, EventKind::host_margin});
      }
      return;
    }
    if (level + 1 < tiers_.size()) tiers_[level + 1].members.insert(i);
  }
  touching_.insert(i);
  const HostContact exact = host_contact(i, std::min(horizon, t + tiers_.back().horizon_s), 0.0, t, &riders_searched_);
  searched_[i] = exact.searched;
  if (exact.when.contact) {
    flight_.push({exact.when.t_s, i, exact.partner, stamp, exact.kind});
  } else if (exact.when.t_s < horizon) {
    const auto last_tier = static_cast<std::int32_t>(tiers_.size() - 1);
    flight_.push({exact.when.t_s, i, last_tier, stamp, EventKind::host_margin});
  }
  touching_bound_[i] = touching_bound(i, std::min(exact.when.t_s, horizon), t);
}

HostCoupling::TouchingBound HostCoupling::touching_bound(int i, double until_s, double t_s) const {
  // Until the event, the sphere's host-frame motion is x0 + w0 s + O(s²), its
  // acceleration relative to the host bounded by |g| + the host's acceleration bound: its
  // centre's heights, and how much its gap to a rider can close, follow.
  const double span = until_s - t_s;
  const HostState host = now(t_s);
  const Ballistic f = flight_.flight(i);
  Eigen::Vector3d position = f.position_at(t_s, gravity_m_s2_), velocity = f.velocity_at(t_s, gravity_m_s2_);
  position.z() -= host.z_m;
  velocity.z() -= host.v_m_s;
  const double curve = 0.5 * (gravity_m_s2_.norm() + trajectory_.acceleration_bound_m_s2()) * span * span;
  TouchingBound bound{until_s, position.z() + std::min(velocity.z() * span, 0.0) - curve,
                      position.z() + std::max(velocity.z() * span, 0.0) + curve};
  const double closing = velocity.norm() * span + curve;
  if (riding_count_ > 0) {
    const PackedParticles& particles = flight_.particles();
    for (const int j : riders_searched_) {
      // A rider whose gap surely exceeds the slack changes no deferral (defer_touching
      // takes the gaps only up to it).
      const Eigen::Vector3d rider = particles.position_m.col(j);
      const double contact_distance = particles.radius_m[i] + particles.radius_m[j];
      const double squared = (position - rider).squaredNorm();
      if (surely_farther(squared, contact_distance + closing + touching_slack_m_)) continue;
      const double gap = std::sqrt(squared) - contact_distance - closing;
      if (rider.z() > bound.lowest_m) bound.gap_above_m = std::min(bound.gap_above_m, gap);
      if (rider.z() < bound.highest_m) bound.gap_below_m = std::min(bound.gap_below_m, gap);
    }
  }
  return bound;
}

bool HostCoupling::defer_touching(int i, const Departure& departure, double t_s) {
  // After restarts all one way, the walls and riders have moved that way by at most the
  // departures' sum until the sphere's event, and never back (departure). A cap or rider
  // moving away from the sphere can only meet it later than predicted; one moving towards
  // it closes its gap by at most the deviation. So the prediction stands as a lower bound
  // if every surface that moves towards the sphere is farther than that. Moving down,
  // those are the top cap and the riders whose centres are above the sphere's lowest
  // point (a rider's distance changes by at most the deviation, and grows if its centre
  // stays below the sphere's); moving up, the mirror. Riders outside the box searched are
  // farther than the slack it had; riders that came since are predicted for by
  // repredict_near_around.
  TouchingBound& b = touching_bound_[i];
  if (departure.velocity_m_s == 0.0 && departure.acceleration_m_s2 == 0.0) return true;
  const int direction = departure.direction;
  if (direction == 0 || b.event_s > departure.until_s) return false;
  if (b.direction != 0 && b.direction != direction) return false;
  const double r = flight_.particles().radius_m[i];
  const double span = b.event_s - t_s;
  const double deviation =
      b.deviation_m + departure.velocity_m_s * span + 0.5 * departure.acceleration_m_s2 * span * span;
  const double clearance = direction < 0 ? cavity_.height_m() - r - b.highest_m : b.lowest_m - r;
  const double riders =
      riding_count_ > 0 ? std::min(direction < 0 ? b.gap_above_m : b.gap_below_m, touching_slack_m_) : never;
  if (!(std::min(clearance, riders) - deviation > flight_.contact_tolerance_m())) return false;
  if (b.direction == 0 && b.event_s < flight_.sphere(i).t_cross_s) {
    // Its contact (if any) is no longer exact: a margin event at the same time re-predicts it.
    flight_.push({b.event_s, i, static_cast<std::int32_t>(tiers_.size() - 1), flight_.replace_host_events(i),
                  EventKind::host_margin});
  }
  b.deviation_m = deviation;
  b.direction = direction;
  return true;
}

bool HostCoupling::departed_from_box(int i, double t_s) const {
  const double host_z = now(t_s).z_m;
  return std::any_of(departed_m_.begin(), departed_m_.end(), [&](const Eigen::Vector3d& lab_m) {
    return searched_[i].holds(lab_m - host_z * e_z, flight_.contact_tolerance_m());
  });
}

template <class Visit>
void HostCoupling::for_each_rider_in(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& half_m,
                                     Visit visit) const {
  // The cells that cover the box (a rider's centre outside them is outside it).
  const CellGrid& grid = flight_.grid();
  const auto [low, high] = grid.cover(centre_m - half_m, centre_m + half_m);
  // Host-frame layers lie within the grid's first period: no wrap, no division per cell.
  for (int iz = std::max(0, low.iz); iz <= std::min(top_rider_layer_, high.iz); ++iz) {
    for (int iy = low.iy; iy <= high.iy; ++iy) {
      for (int ix = low.ix; ix <= high.ix; ++ix) rider_cells_.for_each_in(grid.index_in_period({ix, iy, iz}), visit);
    }
  }
}

bool HostCoupling::within_host_margin(int i, double end_s, double margin_m, double t_s) const {
  // What host_contact(i, end_s, margin_m, t_s) would answer, from the first sample each of
  // its root finders takes: whether some gap, grown by the margin, is within the contact
  // tolerance now. Only riders that near can be; host_contact's box holds them all.
  const double t = t_s;
  if (!(end_s > t)) return false;
  const Ballistic f = flight_.flight(i);
  const PackedParticles& particles = flight_.particles();
  const double r = particles.radius_m[i];
  const HostState host = now(t);
  const double height = cavity_.height_m();
  const double tolerance = flight_.contact_tolerance_m();
  for (const bool top : {false, true}) {
    if (cap_gap_m(f, r + margin_m, top, height, host, gravity_m_s2_, t) <= tolerance) return true;
  }
  if (riding_count_ == 0) return false;
  Eigen::Vector3d centre = f.position_at(t, gravity_m_s2_);
  centre.z() -= host.z_m;
  bool within = false;
  for_each_rider_in(centre, Eigen::Vector3d::Constant(r + flight_.max_radius_m() + margin_m), [&](int j) {
    const double reach = r + particles.radius_m[j] + margin_m;
    const double squared = rider_offset_m(f, particles.position_m.col(j), host, gravity_m_s2_, t).squaredNorm();
    if (surely_farther(squared, reach + tolerance)) return;
    within |= std::sqrt(squared) - reach <= tolerance;
  });
  return within;
}

HostCoupling::HostContact HostCoupling::host_contact(int i, double end_s, double margin_m, double t_s,
                                                     std::vector<int>* riders_searched) const {
  const double t = t_s;
  const Ballistic f = flight_.flight(i);
  const PackedParticles& particles = flight_.particles();
  const double r = particles.radius_m[i];
  const double tolerance = flight_.contact_tolerance_m();
  if (riders_searched) riders_searched->clear();
  HostContact best{{end_s, false}, EventKind::host_margin, 0, {}};
  // A margin is reached whichever way the sphere moves: a sphere within it but receding
  // can still be caught by a host that strays by less than the margin.
  const double closing = margin_m > 0.0 ? within_margin : min_approach_speed_m_s;
  // A tie goes to a contact, then to the lower kind and partner: a sphere wedged in a bed
  // touches several riders at once, and the cells may list them in any order.
  auto consider = [&](const Approach& a, EventKind kind, int partner) {
    const bool wins_tie = a.t_s == best.when.t_s && a.contact &&
                          (!best.when.contact || std::tie(kind, partner) < std::tie(best.kind, best.partner));
    if (a.t_s < best.when.t_s || wins_tie) {
      best.when = a;
      best.kind = kind;
      best.partner = partner;
    }
  };
  // The root finders run only where the bounds on the motion let a gap close: not for the
  // cap a sphere is far from, nor for most riders in the box (a result they would give,
  // no contact until the span's end, changes nothing that is used).
  const double height = cavity_.height_m();
  const HostState host = now(t);
  Eigen::Vector3d velocity = f.velocity_at(t, gravity_m_s2_);  // host frame
  velocity.z() -= host.v_m_s;
  const double acceleration_bound = trajectory_.acceleration_bound_m_s2();
  for (const bool top : {false, true}) {
    const double gap = cap_gap_m(f, r + margin_m, top, height, host, gravity_m_s2_, t);
    const double rate = top ? -velocity.z() : velocity.z();
    if (stays_apart(gap, rate, std::abs(gravity_m_s2_.z()) + acceleration_bound, end_s - t, tolerance)) continue;
    consider(cap_contact(f, r + margin_m, top, height, trajectory_, host, gravity_m_s2_, t, end_s, tolerance, closing),
             top ? EventKind::top_cap : EventKind::bottom_cap, 0);
  }
  if (riding_count_ == 0) return best;
  // Riders within reach of the sphere's host-frame path until the host has moved at most
  // a cell: a box around the path, widened by the largest contact distance.
  const double cell = flight_.grid().cell_size_m();
  const double host_speed = trajectory_.speed_bound_m_s();
  const double window_end = host_speed > 0 ? std::min(end_s, t + cell / host_speed) : end_s;
  const double span = window_end - t;
  Eigen::Vector3d centre = f.position_at(t, gravity_m_s2_);
  centre.z() -= host.z_m;
  Eigen::Vector3d half =
      f.velocity_at(t, gravity_m_s2_).cwiseAbs() * span + 0.5 * gravity_m_s2_.cwiseAbs() * span * span;
  half.array() += r + flight_.max_radius_m() + margin_m;
  half.z() += host_speed * span + (margin_m > 0.0 ? 0.0 : touching_slack_m_);
  best.searched = {centre, half};
  // The distance to a rider closes at most at the relative speed, which grows at most by
  // |g| + |z_h''|.
  const double speed = velocity.norm(), rider_curvature = gravity_m_s2_.norm() + acceleration_bound;
  // How far the gap can close within the span: a rider farther than that beyond contact
  // (and twice the tolerance) stays apart without its distance taken.
  const double reach_beyond_contact =
      2.0 * tolerance + std::abs(span) * (speed + 0.5 * rider_curvature * std::abs(span));
  for_each_rider_in(centre, half, [&](int j) {
    if (riders_searched) riders_searched->push_back(j);
    const auto rider = particles.position_m.col(j);
    const double contact_distance = r + particles.radius_m[j] + margin_m;
    const double squared = (centre - rider).squaredNorm();
    if (surely_farther(squared, contact_distance + reach_beyond_contact)) return;
    const double gap = std::sqrt(squared) - contact_distance;
    if (stays_apart(gap, -speed, rider_curvature, span, tolerance)) return;
    consider(
        rider_contact(f, rider, contact_distance, trajectory_, host, gravity_m_s2_, t, window_end, tolerance, closing),
        EventKind::rider, j);
  });
  consider({window_end, false}, EventKind::host_margin, 0);
  return best;
}

void HostCoupling::predict_bed_release(double t_s) {
  if (riding_count_ == 0) return;
  // Riders on the bottom cap leave when z_h'' falls to g_z, riders on the top when it rises to it.
  const double scale = std::abs(gravity_m_s2_.z()) + trajectory_.acceleration_bound_m_s2();
  const Approach release = host_acceleration_crossing(trajectory_, gravity_m_s2_.z(), bed_side_ > 0, t_s,
                                                      t_s + 1.0 / fastest_rate_1_s_, 1e-12 * scale);
  flight_.push({release.t_s, -1, release.contact ? 1 : 0, epoch_, EventKind::bed_release});
}

void HostCoupling::sweep_tier(std::size_t level, double t_s) {
  // τ → √(τ · time since the last sweep) balances sweeps against horizon ends; it moves
  // at most fourfold per sweep and stays between 10⁻³ and 1 radian of the host's fastest rate.
  MarginTier& tier = tiers_[level];
  const double since = t_s - tier.t_last_sweep_s;
  const double balanced = std::clamp(std::sqrt(tier.horizon_s * since), 0.25 * tier.horizon_s, 4.0 * tier.horizon_s);
  tier.horizon_s = std::clamp(balanced, 1e-3 / fastest_rate_1_s_, 1.0 / fastest_rate_1_s_);
  tier.t_last_sweep_s = t_s;
  ++ledger_.counts.tier_sweeps[level];
  // Deeper tiers' members are this tier's too: all are predicted anew.
  for (std::size_t deeper = level; deeper < tiers_.size(); ++deeper) tiers_[deeper].budget_m = 0.0;
  tier.members.sweep([&](int i) {
    tier.members.insert(i);
    ++ledger_.counts.tier_repredictions[level];
    predict_relative(i, level, t_s);
  });
}

void HostCoupling::repredict_near_around(const Eigen::Vector3d& lab_position_m, double t_s) {
  // A near sphere looks for riders within a cell of its own and the host's motion
  // within its window: three layers either way cover every sphere that could reach here.
  // Of those, a sphere whose last prediction searched a box without this place in it
  // could not have reached it before its event: that prediction stands.
  const CellGrid& grid = flight_.grid();
  const CellCoord c = grid.coord_of(lab_position_m);
  const Eigen::Vector3d host_frame = lab_position_m - now(t_s).z_m * e_z;
  const double slack = flight_.contact_tolerance_m();
  for (int iz = c.iz - 3; iz <= c.iz + 3; ++iz) {
    for (int iy = std::max(0, c.iy - 1); iy <= std::min(grid.ny() - 1, c.iy + 1); ++iy) {
      for (int ix = std::max(0, c.ix - 1); ix <= std::min(grid.nx() - 1, c.ix + 1); ++ix) {
        flight_.for_each_free_in(grid.index({ix, iy, iz}), [&](int j) {
          if (tiers_[0].members.contains(j) && flight_.sphere(j).cell.iz == iz &&
              searched_[j].holds(host_frame, slack)) {
            predict_relative(j, 0, t_s);
          }
        });
      }
    }
  }
}

void HostCoupling::forget_predictions() {
  ++epoch_;
  for (MarginTier& tier : tiers_) {
    tier.budget_m = 0.0;
    tier.members.clear();
  }
  touching_.clear();
}

int HostCoupling::tier_of(int i) const {
  if (touching_.contains(i)) return static_cast<int>(tiers_.size());
  for (int level = static_cast<int>(tiers_.size()) - 1; level >= 0; --level) {
    if (tiers_[static_cast<std::size_t>(level)].members.contains(i)) return level;
  }
  return -1;
}

}  // namespace pdamp::hard
