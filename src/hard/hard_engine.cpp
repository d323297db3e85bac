#include "pdamp/hard/hard_engine.hpp"

#include <unistd.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>
#include <tuple>

#include "pdamp/errors.hpp"
#include "pdamp/model/placement.hpp"

namespace pdamp::hard {

namespace {

/// Cells a little wider than the largest sphere, so that round-off at a face can never
/// hide a contact between spheres two cells apart.
constexpr double cell_margin = 1.0 + 1e-6;
/// Root finders stop this close to contact, relative to the smallest radius.
constexpr double relative_contact_tolerance = 1e-10;
/// The margins of the tiers (near, imminent, close), relative to the smallest radius: a
/// wider margin means rarer sweeps but more spheres in the tier inside it. Spheres of a
/// landing bed close in at ~1 cm/s, one host impulse per µs: each tier holds ~50 times
/// fewer spheres than the one outside it.
constexpr std::array<double, 3> margin_fractions{0.1, 0.002, 4e-5};
/// A sphere that collides with riders, or with free spheres, this many times at one
/// instant is jammed among them.
constexpr int jam_repeats = 64;

const Eigen::Vector3d e_z = Eigen::Vector3d::UnitZ();

/// Whether `bytes` of randomly read data outgrow half of this processor's L2 cache (1 MB
/// if the system does not say).
bool outgrows_l2_cache(std::size_t bytes) {
  const long l2_bytes = sysconf(_SC_LEVEL2_CACHE_SIZE);
  return bytes > static_cast<std::size_t>(l2_bytes > 0 ? l2_bytes : 1L << 20) / 2;
}

}  // namespace

HardEngine::MarginTier HardEngine::tier(std::size_t level, const Particles& initial) const {
  return {ParticleSet(static_cast<int>(initial.size())), margin_fractions[level] * initial.radius_m.minCoeff(),
          1.0 / fastest_host_rate_1_s_};
}

HardEngine::HardEngine(const Scenario& scenario, const Particles& initial, const RestitutionTable* calibration)
    : gravity_m_s2_(scenario.gravity_m_s2),
      sphere_law_(scenario.hard_particle),
      wall_law_(scenario.hard_wall),
      resting_(scenario.hard_resting),
      calibration_(calibration ? std::optional<RestitutionTable>(*calibration) : std::nullopt),
      cavity_(scenario.cavity),
      host_model_(scenario),
      fastest_host_rate_1_s_(std::max(scenario.excitation.angular_frequency_rad_s(),
                                      std::sqrt(scenario.host.stiffness_N_m / scenario.host.mass_kg))),
      particles_(initial),
      sphere_(initial.size()),
      trajectory_counter_(initial.size(), 0),
      jam_{-1.0,
           std::vector<int>(initial.size(), 0),
           std::vector<std::vector<int>>(initial.size()),
           std::vector<std::uint8_t>(initial.size(), 0),
           {},
           {}},
      in_jam_(initial.size(), 0),
      tiers_{tier(0, initial), tier(1, initial), tier(2, initial)},
      touching_(static_cast<int>(initial.size())),
      touching_bound_(initial.size()),
      touching_slack_m_(0.01 * initial.radius_m.minCoeff()),
      grid_(scenario.cavity.radius_m(), scenario.cavity.height_m, 2.0 * initial.max_radius_m() * cell_margin),
      free_cells_(grid_.cell_count() + 1, static_cast<int>(initial.size())),  // + enter_cell's empty stand-in
      rider_cells_(grid_.cell_count(), static_cast<int>(initial.size())),
      queue_(static_cast<int>(initial.size())),
      neighbours_(initial.size() + std::max(CellMembers::copy_width, screen_width)),
      screen_result_(static_cast<int>(initial.size())),
      contact_tolerance_m_(relative_contact_tolerance * initial.radius_m.minCoeff()),
      max_radius_m_(initial.max_radius_m()),
      host_(host_model_, 0.0, host_model_.initial_state()),
      by_sphere_{Eigen::VectorXd::Zero(initial.size()), Eigen::VectorXd::Zero(initial.size())},
      max_events_(scenario.run.max_events),
      next_poll_(std::min(poll_interval, max_events_ + 1)) {
  host_speed_envelope_m_s_ = 2.0 * host_.speed_bound_m_s();
  prefetch_records_ = outgrows_l2_cache(static_cast<std::size_t>(initial.size()) * sizeof(FlightRecord));
  prefetch_cells_ = outgrows_l2_cache(free_cells_.cells_bytes());
  // A collision cascade through a touching bed can take a few events per contact at one
  // instant; far more than that means no progress.
  stall_limit_ = 1000 * static_cast<std::int64_t>(initial.size()) + 100000;
  // A bed settled with soft contacts overlaps by a tiny fraction of a radius: the hard
  // engine starts from it with the spheres pushed just apart.
  Particles separated = initial;
  separation_m_ = separate_overlaps(separated, scenario.cavity, host_.at(0.0).z_m);
  particles_.assign(separated);
  const int n = static_cast<int>(particles_.size());
  for (int i = 0; i < n; ++i) {
    enter_cell(i, grid_.coord_of(particles_.position_m.col(i)));
  }
  if (const double overlap = max_overlap_m(); overlap > 0.0) {
    std::ostringstream why;
    why << "the hard engine needs non-overlapping initial spheres inside the cavity; the deepest overlap is " << overlap
        << " m";
    throw InputError(why.str());
  }
  rebuild_predictions();
}

// ---------------------------------------------------------------------------------------------
// Time and state

void HardEngine::advance_to(double t_s) {
  const auto current = [this](const Event& e) { return is_current(e); };
  for (const Event* next = queue_.top(current); next && next->t_s <= t_s; next = queue_.top(current)) {
    const Event event = *next;
    queue_.pop();
    if (++events_ >= next_poll_) poll();
    if (!is_current(event)) {
      ++stats_.stale;
      continue;
    }
    if (event.t_s > t_s_) {
      t_s_ = event.t_s;
      events_at_this_instant_ = 0;
    } else if (++events_at_this_instant_ > stall_limit_) {
      std::ostringstream why;
      why << "hard engine stalled at t = " << t_s_ << " s: " << events_at_this_instant_
          << " events without time advancing (last: kind " << static_cast<int>(event.kind) << ", sphere " << event.i
          << ", partner " << event.j << ")";
      throw RuntimeFailure(why.str());
    }
    handle(event);
  }
  t_s_ = t_s;
  book_host(t_s);
#ifndef NDEBUG
  if (const double overlap = max_overlap_m(); overlap > overlap_tolerance_m()) {
    std::ostringstream why;
    why << "hard engine invariant broken at t = " << t_s << " s: spheres overlap by " << overlap << " m";
    throw RuntimeFailure(why.str());
  }
#endif
}

void HardEngine::poll() {
  throw_if_stop_requested();
  if (events_ > max_events_) {
    std::ostringstream why;
    why << "the hard engine reached run.max_events = " << max_events_ << " events at t = " << t_s_
        << " s; raise run.max_events if the run is meant to take more";
    throw RuntimeFailure(why.str());
  }
  next_poll_ = std::min(events_ + poll_interval, max_events_ + 1);
}

Eigen::Vector3d HardEngine::position_now(int i, const HostState& host) const {
  if (sphere_[i].riding) return particles_.position_m.col(i) + host.z_m * e_z;
  return flight(i).position_at(t_s_, gravity_m_s2_);
}

inline HostState HardEngine::host_now() const {
  // A host that cannot move (speed bound 0: fixed walls) is where it was: its trig need
  // not be evaluated at every instant.
  const bool moved = host_now_.t_s != t_s_ && (host_.speed_bound_m_s() > 0.0 || host_now_.t_s == -never);
  const bool stale = host_now_.epoch != host_epoch_ || moved;
  if (stale) host_now_ = {t_s_, host_epoch_, host_.at(t_s_)};
  return host_now_.state;
}

void HardEngine::bring_to_now(int i) {
  const Ballistic f = flight(i);
  particles_.position_m.col(i) = f.position_at(t_s_, gravity_m_s2_);
  particles_.velocity_m_s.col(i) = f.velocity_at(t_s_, gravity_m_s2_);
  particles_.t_ref_s[i] = t_s_;
}

State HardEngine::state() const {
  State s{observe(), particles_.unpacked()};
  const HostState host = s.observation.host;
  for (Eigen::Index i = 0; i < particles_.size(); ++i) {
    const int k = static_cast<int>(i);
    s.particles.position_m.col(i) = position_now(k, host);
    s.particles.velocity_m_s.col(i) =
        sphere_[k].riding ? Eigen::Vector3d(host.v_m_s * e_z) : flight(k).velocity_at(t_s_, gravity_m_s2_);
  }
  return s;
}

Observation HardEngine::observe() const {
  Observation o;
  o.t_s = t_s_;
  o.host = host_.at(t_s_);
  EnergyLedger& e = o.energy;
  ParticleEnergySums sums;
  for (Eigen::Index i = 0; i < particles_.size(); ++i) {
    const int k = static_cast<int>(i);
    const Eigen::Vector3d v =
        sphere_[k].riding ? Eigen::Vector3d(o.host.v_m_s * e_z) : flight(k).velocity_at(t_s_, gravity_m_s2_);
    sums.add(particles_.mass_kg[i], particles_.moment_of_inertia(i), position_now(k, o.host), v,
             particles_.angular_velocity_rad_s.col(i), gravity_m_s2_);
  }
  sums.write_to(e);
  e.host_counts = !host_model_.has_infinite_mass();
  e.host_kinetic_J = 0.5 * host_model_.mass_kg() * o.host.v_m_s * o.host.v_m_s;
  e.spring_potential_J = host_model_.spring_energy_J(t_s_, o.host.z_m);
  e.dissipated_impact_J = impact_J_;
  e.dissipated_friction_J = friction_J_;
  // Everything is booked up to t_host_booked_s_ = t_s_ after advance_to; the rest covers
  // an observation taken before the first advance.
  e.dissipated_viscous_J = viscous_J_ + host_.viscous_dissipation_J(t_host_booked_s_, t_s_);
  e.excitation_work_J = excitation_J_ + host_.excitation_work_J(t_host_booked_s_, t_s_);
  if (host_model_.has_infinite_mass()) {
    e.excitation_work_J += rider_energy_J(o.host) - rider_energy_J(host_.at(t_host_booked_s_));
  }
  o.counters.events = collisions();
  o.counters.contacts = riding_count_;
  return o;
}

std::int64_t HardEngine::collisions() const {
  return stats_.sphere_sphere + stats_.side_wall + stats_.cap + stats_.rider;
}

std::vector<std::string> HardEngine::warnings() const {
  // A few percent of a radius is where soft overlaps stop being a resting bed's (the
  // soft engine warns there too); a push that large changes the start noticeably.
  if (separation_m_ <= 0.05 * max_radius_m_) return {};
  std::ostringstream text;
  text << "the initial spheres overlapped: separating them moved a sphere by up to " << separation_m_ << " m";
  return {text.str()};
}

EngineStatistics HardEngine::statistics() const {
  return {{"events_sphere_sphere", stats_.sphere_sphere},
          {"events_wall", stats_.side_wall},
          {"events_cap", stats_.cap},
          {"events_rider", stats_.rider},
          {"events_cell_crossing", stats_.cell_crossing},
          {"events_host_check", stats_.host_check},
          {"events_host_margin", stats_.host_margin},
          {"events_stale", stats_.stale},
          {"bed_rests", stats_.rests},
          {"bed_knock_offs", stats_.knocked_off},
          {"bed_releases", stats_.bed_releases},
          {"bed_jammed", stats_.jammed},
          {"jam_merges", stats_.jam_merges},
          {"jam_merged_spheres", stats_.jam_merged_spheres},
          {"jam_stuck_to_host", stats_.jam_stuck_to_host},
          {"host_impulses", stats_.host_impulses},
          {"near_sweeps", tiers_[0].sweeps},
          {"near_repredictions", tiers_[0].repredictions},
          {"imminent_sweeps", tiers_[1].sweeps},
          {"imminent_repredictions", tiers_[1].repredictions},
          {"close_sweeps", tiers_[2].sweeps},
          {"close_repredictions", tiers_[2].repredictions},
          {"touching_repredictions", stats_.touching_repredictions},
          {"touching_deferrals", stats_.touching_deferrals},
          {"prediction_rebuilds", stats_.rebuilds}};
}

double HardEngine::max_overlap_m() const {
  const HostState host = host_.at(t_s_);
  const auto n = particles_.size();
  Eigen::Matrix3Xd positions(3, n);
  for (Eigen::Index i = 0; i < n; ++i) positions.col(i) = position_now(static_cast<int>(i), host);
  CellList cells;
  cells.build(grid_, positions);
  double deepest = 0.0;
  std::array<int, 27> around{};
  for (Eigen::Index i = 0; i < n; ++i) {
    const double r = particles_.radius_m[i];
    deepest = std::max(deepest, -cavity_.clearance_m(positions.col(i), r, host.z_m));
    const int count = grid_.neighbours(grid_.coord_of(positions.col(i)), around);
    for (int c = 0; c < count; ++c) {
      for (const int j : cells.particles_in(around[c])) {
        if (j <= i) continue;
        const double gap = (positions.col(i) - positions.col(j)).norm() - r - particles_.radius_m[j];
        deepest = std::max(deepest, -gap);
      }
    }
  }
  return deepest;
}

// ---------------------------------------------------------------------------------------------
// Prediction

inline bool HardEngine::is_current(const Event& e) const {
  if (e.kind == EventKind::bed_release) return host_epoch_ == e.count_j;
  // Where count_j came from, chosen without a jump table (its jumps mispredict).
  const bool stamped = carries_host_stamp(e.kind);
  // Both read whatever the kind, then one chosen, without branches (the kinds of
  // successive events are a coin toss); j of another kind may be no sphere: clamped.
  const auto last = static_cast<std::uint32_t>(trajectory_counter_.size() - 1);
  const std::uint32_t partner = trajectory_counter_[std::min(static_cast<std::uint32_t>(e.j), last)];
  const std::uint32_t stamp = sphere_[e.i].host_stamp;
  const std::uint32_t pair_mask = 0u - static_cast<std::uint32_t>(e.kind == EventKind::sphere_sphere);
  const std::uint32_t stamp_mask = 0u - static_cast<std::uint32_t>(stamped);
  const std::uint32_t second = (partner & pair_mask) | (stamp & stamp_mask) | (e.count_j & ~(pair_mask | stamp_mask));
  return second == e.count_j;  // i's own trajectory is current: its change forgot i's events
}

void HardEngine::predict(int i, std::span<const int> new_cells) {
  // Whatever host-dependent event i had is replaced; before anything is entered, which
  // keeps a list refilled after a trajectory change fresh (EventQueue::host_stamp_changed).
  replace_host_events(i);
  const double t = t_s_;
  const Ballistic f = flight(i);
  const Eigen::Vector3d x = f.position_at(t, gravity_m_s2_), v = f.velocity_at(t, gravity_m_s2_);
  const double r = particles_.radius_m[i];
  const CellCoord c = sphere_[i].cell;
  const Eigen::Vector3d& g = gravity_m_s2_;

  // The next face crossing bounds the predictions of walls and host: the sphere is
  // predicted anew there. Lanes pair the faces in x and y, and the face in z with a
  // guard on the host (see below); a cell at the grid's side has no face there.
  const HostState host = host_now();
  const double envelope = host_speed_envelope_m_s_;
  const FaceTimes xy = time_to_faces(Lanes2{x.x() - grid_.x_lower_m(c.ix), x.y() - grid_.x_lower_m(c.iy)},
                                     Lanes2{grid_.x_lower_m(c.ix + 1) - x.x(), grid_.x_lower_m(c.iy + 1) - x.y()},
                                     Lanes2{v.x(), v.y()}, Lanes2{g.x(), g.y()});
  const Lanes2 to_lower_z =
      time_to_plane(Lanes2{x.z() - grid_.z_lower_m(c.iz), x.z() - r - host.z_m - bed_depth_bound_m_},
                    Lanes2{v.z(), v.z() - envelope}, Lanes2{g.z(), g.z()});
  const Lanes2 to_upper_z = time_to_plane(
      Lanes2{grid_.z_lower_m(c.iz + 1) - x.z(), host.z_m + cavity_.height_m() - bed_depth_bound_m_ - x.z() - r},
      Lanes2{-v.z(), -v.z() - envelope}, Lanes2{-g.z(), -g.z()});
  const std::array<double, 6> to_face{c.ix > 0 ? xy.to_lower[0] : never,
                                      c.ix < grid_.nx() - 1 ? xy.to_upper[0] : never,
                                      c.iy > 0 ? xy.to_lower[1] : never,
                                      c.iy < grid_.ny() - 1 ? xy.to_upper[1] : never,
                                      to_lower_z[0],
                                      to_upper_z[0]};
  // The earliest face, the first of equals; none if all are `never`. Without branches
  // (a minimum, and the index by a mask): which face comes first is a coin toss.
  double crossing = to_face[0];
  int earliest = 0;
  for (int k = 1; k < 6; ++k) {
    const int sooner = -static_cast<int>(to_face[k] < crossing);
    earliest += (k - earliest) & sooner;
    crossing = std::min(crossing, to_face[k]);
  }
  const int face = crossing < never ? earliest : -1;
  const double horizon = t + crossing;
  sphere_[i].t_cross_s = horizon;
  if (face >= 0) push({horizon, i, face, 0, EventKind::cell_crossing});

  // The spheres in the new cells first, then which of them i meets, without branches (i
  // itself does not: it neither approaches nor recedes), then only those spheres'
  // contact times, however late: a contact is exact whichever cells the two are in.
  int* const candidates = neighbours_.data();
  const int candidate_count = new_cells.size() == std::tuple_size_v<Around>
                                  ? free_cells_.gather<std::tuple_size_v<Around>>(new_cells.data(), candidates)
                                  : free_cells_.gather<std::tuple_size_v<Layer>>(new_cells.data(), candidates);
  if (prefetch_records_) {
    for (int k = 0; k < candidate_count; ++k) __builtin_prefetch(&particles_.record(candidates[k]));
  }
  screen_neighbours({x, v, r, t, i}, g, &particles_.record(0), candidates, candidate_count, screen_result_);
  screen_result_.for_each_met(candidate_count, [&](int k, const PairQuadratic& pair) {
    const int j = candidates[k];
    push({t + pair.time_s(), i, j, trajectory_counter_[j], EventKind::sphere_sphere});
  });

  // The side wall, if any point of the cell is within reach of it.
  const double far_x = std::max(std::abs(grid_.x_lower_m(c.ix)), std::abs(grid_.x_lower_m(c.ix + 1)));
  const double far_y = std::max(std::abs(grid_.x_lower_m(c.iy)), std::abs(grid_.x_lower_m(c.iy + 1)));
  const double reach = cavity_.radius_m() - r;
  const bool outermost = c.ix == 0 || c.iy == 0 || c.ix == grid_.nx() - 1 || c.iy == grid_.ny() - 1;
  if (outermost || far_x * far_x + far_y * far_y >= reach * reach) {
    const Approach wall = side_wall_contact(Ballistic{x, v, t}, reach, g, t, horizon, contact_tolerance_m_);
    if (wall.contact) push({wall.t_s, i, 0, 0, EventKind::side_wall});
  }

  // Caps and the resting bed: a guard from the host's speed envelope (when the sphere
  // could reach the bed's farthest extent if the host moved at the envelope's speed),
  // or exact predictions.
  const double guard = t + std::min(to_lower_z[1], to_upper_z[1]);
  if (guard <= t) {
    tiers_[0].members.insert(i);
    predict_host_relative(i);
    return;
  }
  leave_host_sets(i);
  if (guard < horizon) push({guard, i, 0, 0, EventKind::host_check});
}

void HardEngine::predict_host_relative(int i, std::size_t first_level) {
  const double t = t_s_;
  const double horizon = sphere_[i].t_cross_s;
  const std::uint32_t stamp = replace_host_events(i);
  // Down the tiers while the sphere is within each one's margin.
  for (std::size_t level = first_level; level < tiers_.size(); ++level) {
    const double end = std::min(horizon, t + tiers_[level].horizon_s);
    if (!within_host_margin(i, end, tiers_[level].margin_m)) {
      if (level == first_level && level > 0) {
        predict_host_relative(i);  // it has left the tier it was in: from the top
        return;
      }
      for (std::size_t deeper = level + 1; deeper < tiers_.size(); ++deeper) tiers_[deeper].members.erase(i);
      touching_.erase(i);
      const HostContact margin = host_contact(i, end, tiers_[level].margin_m);
      if (margin.when.t_s < horizon) {
        push({margin.when.t_s, i, static_cast<std::int32_t>(level), stamp, EventKind::host_margin});
      }
      return;
    }
    if (level + 1 < tiers_.size()) tiers_[level + 1].members.insert(i);
  }
  touching_.insert(i);
  const HostContact exact = host_contact(i, std::min(horizon, t + tiers_.back().horizon_s), 0.0, &riders_searched_);
  if (exact.when.contact) {
    push({exact.when.t_s, i, exact.partner, stamp, exact.kind});
  } else if (exact.when.t_s < horizon) {
    const auto last_tier = static_cast<std::int32_t>(tiers_.size() - 1);
    push({exact.when.t_s, i, last_tier, stamp, EventKind::host_margin});
  }
  // Until the event, the sphere's host-frame motion is x0 + w0 s + O(s²), its
  // acceleration relative to the host bounded by |g| + the host's acceleration bound: its
  // centre's heights, and how much its gap to a rider can close, follow.
  const double until = std::min(exact.when.t_s, horizon), span = until - t;
  const HostState host = host_now();
  const Ballistic f = flight(i);
  Eigen::Vector3d position = f.position_at(t, gravity_m_s2_), velocity = f.velocity_at(t, gravity_m_s2_);
  position.z() -= host.z_m;
  velocity.z() -= host.v_m_s;
  const double curve = 0.5 * (gravity_m_s2_.norm() + host_.acceleration_bound_m_s2()) * span * span;
  TouchingBound bound{until, position.z() + std::min(velocity.z() * span, 0.0) - curve,
                      position.z() + std::max(velocity.z() * span, 0.0) + curve};
  const double closing = velocity.norm() * span + curve;
  if (riding_count_ > 0) {
    for (const int j : riders_searched_) {
      const Eigen::Vector3d rider = particles_.position_m.col(j);
      const double gap = (position - rider).norm() - (particles_.radius_m[i] + particles_.radius_m[j]) - closing;
      if (rider.z() > bound.lowest_m) bound.gap_above_m = std::min(bound.gap_above_m, gap);
      if (rider.z() < bound.highest_m) bound.gap_below_m = std::min(bound.gap_below_m, gap);
    }
  }
  touching_bound_[i] = bound;
}

bool HardEngine::defer_touching(int i, double velocity_change_m_s) {
  // The new host trajectory minus the old one solves the host's homogeneous equation (the
  // same mass, spring, damper and forcing) from zero displacement and velocity Δv: it is
  // Δv h(s) with 0 ≤ h(s) ≤ s for s up to half a damped period, longer than any touching
  // prediction looks ahead (a tier's horizon is at most 1/ω). So after impulses all one
  // way, the walls and riders have moved that way by at most Σ |Δv| (t_event − t_impulse)
  // and never back. A cap or rider moving away from the sphere can only meet it later
  // than predicted; one moving towards it closes its gap by at most the deviation. So the
  // prediction stands as a lower bound if every surface that moves towards the sphere is
  // farther than that. Moving down, those are the top cap and the riders whose centres
  // are above the sphere's lowest point (a rider's distance changes by at most the
  // deviation, and grows if its centre stays below the sphere's); moving up, the mirror.
  // Riders outside the box searched are farther than the slack it had.
  TouchingBound& b = touching_bound_[i];
  if (velocity_change_m_s == 0.0) return true;
  const int direction = velocity_change_m_s > 0.0 ? 1 : -1;
  if (b.direction != 0 && b.direction != direction) return false;
  const double r = particles_.radius_m[i];
  const double deviation = b.deviation_m + std::abs(velocity_change_m_s) * (b.event_s - t_s_);
  const double clearance = direction < 0 ? cavity_.height_m() - r - b.highest_m : b.lowest_m - r;
  // (Riders attached since the prediction changed the riding mass, which re-predicts.)
  const double riders =
      riding_count_ > 0 ? std::min(direction < 0 ? b.gap_above_m : b.gap_below_m, touching_slack_m_) : never;
  if (!(std::min(clearance, riders) - deviation > contact_tolerance_m_)) return false;
  if (b.direction == 0 && b.event_s < sphere_[i].t_cross_s) {
    // Its contact (if any) is no longer exact: a margin event at the same time re-predicts it.
    push({b.event_s, i, static_cast<std::int32_t>(tiers_.size() - 1), replace_host_events(i), EventKind::host_margin});
  }
  b.deviation_m = deviation;
  b.direction = direction;
  return true;
}

template <class Visit>
void HardEngine::for_each_rider_in(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& half_m, Visit visit) const {
  // The cells that cover the box (a rider's centre outside them is outside it).
  const CellCoord low = grid_.coord_of(centre_m - half_m), high = grid_.coord_of(centre_m + half_m);
  // Host-frame layers lie within the grid's first period: no wrap, no division per cell.
  const int top_layer = static_cast<int>(std::floor(cavity_.height_m() / grid_.cell_size_m()));
  for (int iz = std::max(0, low.iz); iz <= std::min(top_layer, high.iz); ++iz) {
    for (int iy = low.iy; iy <= high.iy; ++iy) {
      for (int ix = low.ix; ix <= high.ix; ++ix) rider_cells_.for_each_in(grid_.index_in_period({ix, iy, iz}), visit);
    }
  }
}

bool HardEngine::within_host_margin(int i, double end_s, double margin_m) const {
  // What host_contact(i, end_s, margin_m) would answer, from the first sample each of its
  // root finders takes: whether some gap, grown by the margin, is within the contact
  // tolerance now. Only riders that near can be; host_contact's box holds them all.
  const double t = t_s_;
  if (!(end_s > t)) return false;
  const Ballistic f = flight(i);
  const double r = particles_.radius_m[i];
  const HostState host = host_now();
  const double height = cavity_.height_m();
  for (const bool top : {false, true}) {
    if (cap_gap_m(f, r + margin_m, top, height, host, gravity_m_s2_, t) <= contact_tolerance_m_) return true;
  }
  if (riding_count_ == 0) return false;
  Eigen::Vector3d centre = f.position_at(t, gravity_m_s2_);
  centre.z() -= host.z_m;
  bool within = false;
  for_each_rider_in(centre, Eigen::Vector3d::Constant(r + max_radius_m_ + margin_m), [&](int j) {
    const double distance = rider_offset_m(f, particles_.position_m.col(j), host, gravity_m_s2_, t).norm();
    within |= distance - (r + particles_.radius_m[j] + margin_m) <= contact_tolerance_m_;
  });
  return within;
}

HardEngine::HostContact HardEngine::host_contact(int i, double end_s, double margin_m,
                                                 std::vector<int>* riders_searched) const {
  const double t = t_s_;
  const Ballistic f = flight(i);
  const double r = particles_.radius_m[i];
  if (riders_searched) riders_searched->clear();
  HostContact best{{end_s, false}, EventKind::host_margin, 0};
  // A margin is reached whichever way the sphere moves: a sphere within it but receding
  // can still be caught by a host that strays by less than the margin.
  const double closing = margin_m > 0.0 ? within_margin : min_approach_speed_m_s;
  // A tie goes to a contact, then to the lower kind and partner: a sphere wedged in a bed
  // touches several riders at once, and the cells may list them in any order.
  auto consider = [&](const Approach& a, EventKind kind, int partner) {
    const bool wins_tie = a.t_s == best.when.t_s && a.contact &&
                          (!best.when.contact || std::tie(kind, partner) < std::tie(best.kind, best.partner));
    if (a.t_s < best.when.t_s || wins_tie) best = {a, kind, partner};
  };
  // The root finders run only where the bounds on the motion let a gap close: not for the
  // cap a sphere is far from, nor for most riders in the box (a result they would give,
  // no contact until the span's end, changes nothing that is used).
  const double height = cavity_.height_m();
  const HostState host = host_now();
  Eigen::Vector3d velocity = f.velocity_at(t, gravity_m_s2_);  // host frame
  velocity.z() -= host.v_m_s;
  const double acceleration_bound = host_.acceleration_bound_m_s2();
  for (const bool top : {false, true}) {
    const double gap = cap_gap_m(f, r + margin_m, top, height, host, gravity_m_s2_, t);
    const double rate = top ? -velocity.z() : velocity.z();
    if (stays_apart(gap, rate, std::abs(gravity_m_s2_.z()) + acceleration_bound, end_s - t, contact_tolerance_m_)) {
      continue;
    }
    consider(
        cap_contact(f, r + margin_m, top, height, host_, host, gravity_m_s2_, t, end_s, contact_tolerance_m_, closing),
        top ? EventKind::top_cap : EventKind::bottom_cap, 0);
  }
  if (riding_count_ == 0) return best;
  // Riders within reach of the sphere's host-frame path until the host has moved at most
  // a cell: a box around the path, widened by the largest contact distance.
  const double cell = grid_.cell_size_m();
  const double host_speed = host_.speed_bound_m_s();
  const double window_end = host_speed > 0 ? std::min(end_s, t + cell / host_speed) : end_s;
  const double span = window_end - t;
  Eigen::Vector3d centre = f.position_at(t, gravity_m_s2_);
  centre.z() -= host.z_m;
  Eigen::Vector3d half =
      f.velocity_at(t, gravity_m_s2_).cwiseAbs() * span + 0.5 * gravity_m_s2_.cwiseAbs() * span * span;
  half.array() += r + max_radius_m_ + margin_m;
  half.z() += host_speed * span + (margin_m > 0.0 ? 0.0 : touching_slack_m_);
  // The distance to a rider closes at most at the relative speed, which grows at most by
  // |g| + |z_h''|.
  const double speed = velocity.norm(), rider_curvature = gravity_m_s2_.norm() + acceleration_bound;
  for_each_rider_in(centre, half, [&](int j) {
    if (riders_searched) riders_searched->push_back(j);
    const auto rider = particles_.position_m.col(j);
    const double contact_distance = r + particles_.radius_m[j] + margin_m;
    const double gap = (centre - rider).norm() - contact_distance;
    if (stays_apart(gap, -speed, rider_curvature, span, contact_tolerance_m_)) return;
    consider(rider_contact(f, rider, contact_distance, host_, host, gravity_m_s2_, t, window_end, contact_tolerance_m_,
                           closing),
             EventKind::rider, j);
  });
  consider({window_end, false}, EventKind::host_margin, 0);
  return best;
}

void HardEngine::predict_bed_release() {
  if (riding_count_ == 0) return;
  // Riders on the bottom cap leave when z_h'' falls to g_z, riders on the top when it rises to it.
  const double scale = std::abs(gravity_m_s2_.z()) + host_.acceleration_bound_m_s2();
  const Approach release = host_acceleration_crossing(host_, gravity_m_s2_.z(), bed_side_ > 0, t_s_,
                                                      t_s_ + 1.0 / fastest_host_rate_1_s_, 1e-12 * scale);
  push({release.t_s, -1, release.contact ? 1 : 0, host_epoch_, EventKind::bed_release});
}

void HardEngine::leave_host_sets(int i) {
  // The sets nest (touching within the close tier, within the imminent, within the near),
  // and most spheres are in none: one look at the outermost settles it.
  if (!tiers_[0].members.contains(i)) return;
  for (MarginTier& tier : tiers_) tier.members.erase(i);
  touching_.erase(i);
}

void HardEngine::sweep_tier(std::size_t level) {
  // τ → √(τ · time since the last sweep) balances sweeps against horizon ends; it moves
  // at most fourfold per sweep and stays between 10⁻³ and 1 radian of the host's fastest rate.
  MarginTier& tier = tiers_[level];
  const double since = t_s_ - tier.t_last_sweep_s;
  const double balanced = std::clamp(std::sqrt(tier.horizon_s * since), 0.25 * tier.horizon_s, 4.0 * tier.horizon_s);
  tier.horizon_s = std::clamp(balanced, 1e-3 / fastest_host_rate_1_s_, 1.0 / fastest_host_rate_1_s_);
  tier.t_last_sweep_s = t_s_;
  ++tier.sweeps;
  // Deeper tiers' members are this tier's too: all are predicted anew.
  for (std::size_t deeper = level; deeper < tiers_.size(); ++deeper) tiers_[deeper].budget_m = 0.0;
  tier.members.sweep([&](int i) {
    tier.members.insert(i);
    ++tier.repredictions;
    predict_host_relative(i, level);
  });
}

void HardEngine::repredict_near_around(const Eigen::Vector3d& lab_position) {
  // A near sphere looks for riders within a cell of its own and the host's motion
  // within its window: three layers either way cover every sphere that could reach here.
  const CellCoord c = grid_.coord_of(lab_position);
  for (int iz = c.iz - 3; iz <= c.iz + 3; ++iz) {
    for (int iy = std::max(0, c.iy - 1); iy <= std::min(grid_.ny() - 1, c.iy + 1); ++iy) {
      for (int ix = std::max(0, c.ix - 1); ix <= std::min(grid_.nx() - 1, c.ix + 1); ++ix) {
        free_cells_.for_each_in(grid_.index({ix, iy, iz}), [&](int j) {
          if (tiers_[0].members.contains(j) && sphere_[j].cell.iz == iz) predict_host_relative(j);
        });
      }
    }
  }
}

void HardEngine::rebuild_predictions() {
  ++stats_.rebuilds;
  queue_.clear();
  ++host_epoch_;
  for (MarginTier& tier : tiers_) {
    tier.budget_m = 0.0;
    tier.members.clear();
  }
  touching_.clear();
  for (int i = 0; i < static_cast<int>(particles_.size()); ++i) {
    if (!sphere_[i].riding) predict(i);
  }
  predict_bed_release();
}

// ---------------------------------------------------------------------------------------------
// Events

void HardEngine::handle(const Event& e) {
  switch (e.kind) {
    case EventKind::sphere_sphere:
      ++stats_.sphere_sphere;
      collide_spheres(e.i, e.j);
      return;
    case EventKind::side_wall:
      ++stats_.side_wall;
      collide_wall(e.i, e.kind);
      return;
    case EventKind::bottom_cap:
    case EventKind::top_cap:
      ++stats_.cap;
      collide_wall(e.i, e.kind);
      return;
    case EventKind::rider:
      ++stats_.rider;
      collide_rider(e.i, e.j);
      return;
    case EventKind::cell_crossing:
      ++stats_.cell_crossing;
      cross_face(e.i, static_cast<Face>(e.j));
      return;
    case EventKind::host_check:
      ++stats_.host_check;
      tiers_[0].members.insert(e.i);
      predict_host_relative(e.i);
      return;
    case EventKind::host_margin:
      ++stats_.host_margin;
      predict_host_relative(e.i, static_cast<std::size_t>(e.j));
      return;
    case EventKind::bed_release:
      if (e.j == 1) {
        release_bed();
      } else {
        predict_bed_release();
      }
      return;
  }
}

HardContactLaw HardEngine::law_for(double approach_speed_m_s, bool wall, int i, int j) {
  HardContactLaw law = wall ? wall_law_ : sphere_law_;
  if (calibration_) {
    const RestitutionCurve& curve = wall ? calibration_->sphere_wall : calibration_->sphere_sphere;
    law.en = curve.en_at(approach_speed_m_s);
    law.beta0 = curve.beta0_at(approach_speed_m_s);
  }
  // A sphere wedged between two bodies collides again at the same instant; keeping those
  // repeats inelastic lets the sequence die out instead of bouncing elastically forever.
  const bool repeat = sphere_[i].last_collision_s == t_s_ || (j >= 0 && sphere_[j].last_collision_s == t_s_);
  sphere_[i].last_collision_s = t_s_;
  if (j >= 0) sphere_[j].last_collision_s = t_s_;
  if (approach_speed_m_s < resting_.elastic_speed_m_s && !repeat) law.en = 1.0;
  return law;
}

void HardEngine::collide_spheres(int i, int j) {
  // The cells around both spheres are asked for first: with many spheres they are out of
  // cache, and their loads then overlap the collision instead of stalling the predictions.
  Around around_i, around_j;
  grid_.block(sphere_[i].cell, grid_.cell_count(), around_i);
  grid_.block(sphere_[j].cell, grid_.cell_count(), around_j);
  if (prefetch_cells_) {
    free_cells_.prefetch(around_i);
    free_cells_.prefetch(around_j);
  }
  bring_to_now(i);
  bring_to_now(j);
  if (note_collision(i, j)) {
    merge_jam(i);
    return;
  }
  const double ri = particles_.radius_m[i], rj = particles_.radius_m[j];
  const Eigen::Vector3d n = (particles_.position_m.col(j) - particles_.position_m.col(i)).normalized();
  const Eigen::Vector3d dv = particles_.velocity_m_s.col(i) - particles_.velocity_m_s.col(j);
  const Eigen::Vector3d u =
      dv + (ri * particles_.angular_velocity_rad_s.col(i) + rj * particles_.angular_velocity_rad_s.col(j)).cross(n);
  const double mi = particles_.mass_kg[i], mj = particles_.mass_kg[j];
  const double approach = dv.dot(n);
  const HardContactLaw law = law_for(approach, false, i, j);
  const CollisionOutcome out = walton_collision(u, n, approach, sphere_mobility(mi) + sphere_mobility(mj), law);
  const Eigen::Vector3d& p = out.impulse_N_s;
  const Eigen::Vector3d torque_arm = n.cross(p);
  particles_.velocity_m_s.col(i) += p / mi;
  particles_.velocity_m_s.col(j) -= p / mj;
  particles_.angular_velocity_rad_s.col(i) += ri * torque_arm / particles_.moment_of_inertia(i);
  particles_.angular_velocity_rad_s.col(j) += rj * torque_arm / particles_.moment_of_inertia(j);
  impact_J_ += out.impact_J;
  friction_J_ += out.friction_J;
  book_sphere_loss(i, 0.5 * out.impact_J, 0.5 * out.friction_J);
  book_sphere_loss(j, 0.5 * out.impact_J, 0.5 * out.friction_J);
  new_trajectory(i);
  new_trajectory(j);
  predict(i, around_i);
  predict(j, around_j);
}

bool HardEngine::note_collision(int i, int j, std::uint8_t hold) {
  // Most instants see one collision, which cannot be a jam: it is only set aside, and
  // entered in the spheres' records when a second one comes at the same instant.
  if (jam_.t_s != t_s_) {
    for (const int k : jam_.involved) {
      jam_.count[k] = 0;
      jam_.partners[k].clear();
      jam_.hold[k] = 0;
    }
    jam_.involved.clear();
    jam_.t_s = t_s_;
    jam_.first = {i, j, hold, true};
    return false;
  }
  if (jam_.first.pending) {
    jam_.first.pending = false;
    record_collision(jam_.first.i, jam_.first.j, jam_.first.hold);
  }
  return record_collision(i, j, hold);
}

bool HardEngine::record_collision(int i, int j, std::uint8_t hold) {
  const auto count = [this](int k) {
    if (jam_.count[k]++ == 0) jam_.involved.push_back(k);
  };
  count(i);
  if (j < 0) {
    jam_.hold[i] |= hold;
    return jam_.count[i] > jam_repeats;
  }
  count(j);
  std::vector<int>& of_i = jam_.partners[i];
  if (std::find(of_i.begin(), of_i.end(), j) == of_i.end()) {
    of_i.push_back(j);
    jam_.partners[j].push_back(i);
  }
  return jam_.count[i] > jam_repeats || jam_.count[j] > jam_repeats;
}

void HardEngine::merge_jam(int i) {
  // Touching spheres that keep colliding at one instant are the hard-sphere limit of a
  // jam: inelastic collapse drives their approach speeds to zero in infinitely many
  // collisions, and friction in a wedge can turn slip at one contact into approach at
  // the next for ever. Its limit is taken at once: the cluster (free spheres linked by
  // collisions at this instant, all touching since time has not moved) moves on as one
  // rigid body. A cluster that a wall or the bed holds as well would be driven back into
  // it by that rigid motion, so it sticks to the host.
  std::vector<int> members{i};
  std::vector<std::uint8_t>& in = in_jam_;
  in[i] = 1;
  std::uint8_t hold = 0;
  for (std::size_t k = 0; k < members.size(); ++k) {
    hold |= jam_.hold[members[k]];
    for (const int j : jam_.partners[members[k]]) {
      if (in[j] || sphere_[j].riding) continue;
      in[j] = 1;
      members.push_back(j);
    }
  }
  std::sort(members.begin(), members.end());
  for (const int k : members) {
    bring_to_now(k);
    new_trajectory(k);
  }
  merge_rigidly(members);
  if (hold) {
    stick_to_host(members, hold);
    ++stats_.jam_stuck_to_host;
  }
  ++stats_.jam_merges;
  stats_.jam_merged_spheres += static_cast<std::int64_t>(members.size());
  for (const int k : members) {
    in[k] = 0;
    predict(k);
  }
}

void HardEngine::merge_rigidly(const std::vector<int>& members) {
  // The rigid body keeps the cluster's momentum and angular momentum. A rigid motion
  // flown ballistically never brings two of its spheres closer, so no collision among
  // them is left; the energy of the relative motion removed is the loss (≥ 0: the rigid
  // motion is the kinetic-energy projection of the old one).
  const std::vector<std::uint8_t>& in = in_jam_;
  double mass = 0.0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), momentum = Eigen::Vector3d::Zero();
  for (const int k : members) {
    const double m = particles_.mass_kg[k];
    mass += m;
    centre += m * particles_.position_m.col(k);
    momentum += m * particles_.velocity_m_s.col(k);
  }
  centre /= mass;
  const Eigen::Vector3d velocity = momentum / mass;
  Eigen::Vector3d angular_momentum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (const int k : members) {
    const double m = particles_.mass_kg[k], moment = particles_.moment_of_inertia(k);
    const Eigen::Vector3d r = particles_.position_m.col(k) - centre;
    angular_momentum +=
        m * r.cross(particles_.velocity_m_s.col(k) - velocity) + moment * particles_.angular_velocity_rad_s.col(k);
    inertia += (moment + m * r.squaredNorm()) * Eigen::Matrix3d::Identity() - m * r * r.transpose();
  }
  const Eigen::Vector3d spin = inertia.llt().solve(angular_momentum);
  // The loss is split as the contacts' relative motion was: its normal part is impact,
  // its sliding and rolling part friction.
  double normal = 0.0, total = 0.0;
  for (const int k : members) {
    for (const int j : jam_.partners[k]) {
      if (j < k || !in[j]) continue;
      const Eigen::Vector3d n = (particles_.position_m.col(j) - particles_.position_m.col(k)).normalized();
      const Eigen::Vector3d u = particles_.velocity_m_s.col(k) - particles_.velocity_m_s.col(j) +
                                (particles_.radius_m[k] * particles_.angular_velocity_rad_s.col(k) +
                                 particles_.radius_m[j] * particles_.angular_velocity_rad_s.col(j))
                                    .cross(n);
      const double reduced =
          particles_.mass_kg[k] * particles_.mass_kg[j] / (particles_.mass_kg[k] + particles_.mass_kg[j]);
      normal += reduced * u.dot(n) * u.dot(n);
      total += reduced * u.squaredNorm();
    }
  }
  const double impact_share = total > 0.0 ? normal / total : 1.0;
  double loss = 0.0;
  for (const int k : members) {
    // Each sphere's part of the loss is the energy of its own motion removed.
    const Eigen::Vector3d v = velocity + spin.cross(particles_.position_m.col(k) - centre);
    const double sphere_loss =
        0.5 * particles_.mass_kg[k] * (particles_.velocity_m_s.col(k) - v).squaredNorm() +
        0.5 * particles_.moment_of_inertia(k) * (particles_.angular_velocity_rad_s.col(k) - spin).squaredNorm();
    loss += sphere_loss;
    book_sphere_loss(k, impact_share * sphere_loss, (1.0 - impact_share) * sphere_loss);
    particles_.velocity_m_s.col(k) = v;
    particles_.angular_velocity_rad_s.col(k) = spin;
  }
  impact_J_ += impact_share * loss;
  friction_J_ += (1.0 - impact_share) * loss;
}

void HardEngine::stick_to_host(const std::vector<int>& members, std::uint8_t hold) {
  // The host moves only vertically, so the walls take the body's horizontal momentum and
  // its spin, and the host its vertical momentum. Each part of the loss is impact where
  // it is normal to a holding wall (horizontal at the side wall, vertical at a cap or the
  // bed) and friction otherwise; the spin is friction.
  const HostState host = host_now();
  double mass = 0.0;
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();
  for (const int k : members) {
    mass += particles_.mass_kg[k];
    momentum += particles_.mass_kg[k] * particles_.velocity_m_s.col(k);
  }
  const Eigen::Vector3d velocity = momentum / mass;
  double spin_J = 0.0;
  for (const int k : members) {
    spin_J += 0.5 * particles_.mass_kg[k] * (particles_.velocity_m_s.col(k) - velocity).squaredNorm() +
              0.5 * particles_.moment_of_inertia(k) * particles_.angular_velocity_rad_s.col(k).squaredNorm();
  }
  const double horizontal_J = 0.5 * mass * velocity.head<2>().squaredNorm();
  const double relative_vz = velocity.z() - host.v_m_s;
  HostState after = host;
  double vertical_J;
  if (host_model_.has_infinite_mass()) {
    vertical_J = 0.5 * mass * relative_vz * relative_vz;
    excitation_J_ += mass * (host.v_m_s - velocity.z()) * host.v_m_s;  // the host's work on the body
  } else {
    const double carried = host_model_.mass_kg() + riding_mass_kg_;
    vertical_J = 0.5 * mass * carried / (mass + carried) * relative_vz * relative_vz;
    after.v_m_s = (carried * host.v_m_s + mass * velocity.z()) / (carried + mass);
  }
  const bool side = hold & held_by_side_wall, cap = hold & held_by_cap_or_bed;
  impact_J_ += (side ? horizontal_J : 0.0) + (cap ? vertical_J : 0.0);
  friction_J_ += spin_J + (side ? 0.0 : horizontal_J) + (cap ? 0.0 : vertical_J);
  for (const int k : members) {
    // Each sphere's part: its own spin and motion relative to the body, and its mass's
    // share of the body's.
    const double m = particles_.mass_kg[k], share = m / mass;
    const double sphere_spin_J =
        0.5 * m * (particles_.velocity_m_s.col(k) - velocity).squaredNorm() +
        0.5 * particles_.moment_of_inertia(k) * particles_.angular_velocity_rad_s.col(k).squaredNorm();
    book_sphere_loss(k, share * ((side ? horizontal_J : 0.0) + (cap ? vertical_J : 0.0)),
                     sphere_spin_J + share * ((side ? 0.0 : horizontal_J) + (cap ? 0.0 : vertical_J)));
    particles_.velocity_m_s.col(k) = after.v_m_s * e_z;
    particles_.angular_velocity_rad_s.col(k).setZero();
    leave_host_sets(k);
  }
  if (after.v_m_s != host.v_m_s) restart_host(after);
}

double HardEngine::host_inverse_mass_1_kg() const {
  return host_model_.has_infinite_mass() ? 0.0 : 1.0 / (host_model_.mass_kg() + riding_mass_kg_);
}

void HardEngine::apply_host_impulse(int i, const Eigen::Vector3d& n, const CollisionOutcome& out, const HostState& host,
                                    int rider) {
  const Eigen::Vector3d& p = out.impulse_N_s;
  const double r = particles_.radius_m[i];
  particles_.velocity_m_s.col(i) += p / particles_.mass_kg[i];
  particles_.angular_velocity_rad_s.col(i) +=
      r * n.cross(p) / particles_.moment_of_inertia(static_cast<Eigen::Index>(i));
  impact_J_ += out.impact_J;
  friction_J_ += out.friction_J;
  if (rider < 0) {
    book_sphere_loss(i, out.impact_J, out.friction_J);
  } else {
    book_sphere_loss(i, 0.5 * out.impact_J, 0.5 * out.friction_J);
    book_sphere_loss(rider, 0.5 * out.impact_J, 0.5 * out.friction_J);
  }
  new_trajectory(i);
  leave_host_sets(i);
  if (host_model_.has_infinite_mass()) {
    excitation_J_ += p.z() * host.v_m_s;  // the wall's work on the sphere
  } else if (p.z() != 0.0) {
    restart_host({host.z_m, host.v_m_s - p.z() * host_inverse_mass_1_kg()});
  }
}

void HardEngine::collide_wall(int i, EventKind wall) {
  bring_to_now(i);
  if (note_collision(i, -1, wall == EventKind::side_wall ? held_by_side_wall : held_by_cap_or_bed)) {
    merge_jam(i);
    return;
  }
  const HostState host = host_now();
  const Eigen::Vector3d x = particles_.position_m.col(i);
  Eigen::Vector3d n;  // from the sphere towards the wall
  if (wall == EventKind::side_wall) {
    n = Eigen::Vector3d(x.x(), x.y(), 0.0).normalized();
  } else {
    n = wall == EventKind::bottom_cap ? -e_z : e_z;
  }
  const double r = particles_.radius_m[i];
  const Eigen::Vector3d dv = particles_.velocity_m_s.col(i) - host.v_m_s * e_z;
  const Eigen::Vector3d u = dv + (r * particles_.angular_velocity_rad_s.col(i)).cross(n);
  const Mobility mobility = sphere_mobility(particles_.mass_kg[i]) + Mobility{0, 0, host_inverse_mass_1_kg()};
  // As predicted: the cap's gap rate ∓(v_z − v_h), the side wall's x·v in the plane.
  const double approach = wall == EventKind::side_wall ? x.head<2>().dot(dv.head<2>()) / x.head<2>().norm()
                                                       : n.z() * (particles_.velocity_m_s(2, i) - host.v_m_s);
  const HardContactLaw law = law_for(approach, true, i, -1);
  const CollisionOutcome out = walton_collision(u, n, approach, mobility, law);
  apply_host_impulse(i, n, out, host);
  if (wall == EventKind::side_wall) {
    turn_along_side_wall(i, n);
    predict(i);
  } else {
    rest_if_slow(i, -n, host_now());  // the host as the impulse left it
  }
}

void HardEngine::turn_along_side_wall(int i, const Eigen::Vector3d& outward) {
  // A sphere sliding along the curved wall would bounce ever more often as its radial
  // speed dies out (chords ∝ radial speed). It leaves at least at the elastic speed
  // instead, its horizontal speed unchanged: the wall turns it as a lasting contact
  // would, without changing its energy.
  const double floor_speed = resting_.elastic_speed_m_s;
  Eigen::Vector2d v = particles_.velocity_m_s.col(i).head<2>();
  const Eigen::Vector2d radial = outward.head<2>();
  const double leaving = -v.dot(radial);
  const double speed_sq = v.squaredNorm();
  if (leaving >= floor_speed || speed_sq <= floor_speed * floor_speed) return;
  const Eigen::Vector2d along = (v + leaving * radial).normalized();
  v = -floor_speed * radial + std::sqrt(speed_sq - floor_speed * floor_speed) * along;
  particles_.velocity_m_s.col(i).head<2>() = v;
}

void HardEngine::collide_rider(int i, int j) {
  bring_to_now(i);
  const HostState host = host_.at(t_s_);
  const double ri = particles_.radius_m[i];
  // dx and dv exactly as rider_contact computes them, so the approach agrees with the prediction.
  Eigen::Vector3d dx = particles_.position_m.col(i) - particles_.position_m.col(j);
  dx.z() -= host.z_m;
  Eigen::Vector3d dv = particles_.velocity_m_s.col(i);
  dv.z() -= host.v_m_s;
  const Eigen::Vector3d n = -dx.normalized();
  const double approach = -dx.dot(dv) / dx.norm();
  const Eigen::Vector3d u = dv + (ri * particles_.angular_velocity_rad_s.col(i)).cross(n);
  const bool jammed = note_collision(i, -1, held_by_cap_or_bed);
  if (jammed && approach <= resting_.rest_speed_m_s) {
    // Wedged among riders and still colliding at this one instant: friction can turn the
    // slip along one contact into approach towards the next for ever. The sphere is
    // jammed in the bed, so it comes to rest in it.
    ++stats_.jammed;
    attach(i);
    return;
  }
  if (approach > resting_.rest_speed_m_s) {
    // Hit hard enough to knock the rider off: it leaves the bed with the host's velocity
    // (no momentum changes hands) and the collision is between two free spheres.
    ++stats_.knocked_off;
    detach(j, host);
    restart_host(host);
    collide_spheres(i, j);
    return;
  }
  const Mobility mobility = sphere_mobility(particles_.mass_kg[i]) + Mobility{0, 0, host_inverse_mass_1_kg()};
  const HardContactLaw law = law_for(approach, false, i, -1);
  const CollisionOutcome out = walton_collision(u, n, approach, mobility, law);
  apply_host_impulse(i, n, out, host, j);
  rest_if_slow(i, -n, host_.at(t_s_));
}

void HardEngine::cross_face(int i, Face face) {
  CellCoord c = sphere_[i].cell;
  const int step = face % 2 == 1 ? 1 : -1;
  switch (face / 2) {
    case 0:
      c.ix += step;
      break;
    case 1:
      c.iy += step;
      break;
    default:
      c.iz += step;
      break;
  }
  free_cells_.remove(i);
  enter_cell(i, c);
  // Only the layer of cells beyond the face is new around i: its contacts with the
  // spheres in the others were predicted with the same trajectory.
  Around around;
  grid_.block(c, grid_.cell_count(), around);    // the empty stand-in beyond the sides
  constexpr std::array<int, 3> stride{1, 3, 9};  // in Around, of x, y and z
  const int axis = face / 2, beyond = (face % 2 == 1 ? 2 : 0) * stride[axis];
  const int u_stride = stride[(axis + 1) % 3], w_stride = stride[(axis + 2) % 3];
  Layer entered{};
  for (int u = 0; u < 3; ++u) {
    for (int w = 0; w < 3; ++w) entered[3 * u + w] = around[beyond + u * u_stride + w * w_stride];
  }
  predict(i, entered);
}

void HardEngine::enter_cell(int i, const CellCoord& c) {
  sphere_[i].cell = c;
  free_cells_.insert(i, grid_.index(c));
}

// ---------------------------------------------------------------------------------------------
// The host and the resting bed

void HardEngine::book_host(double t_s) {
  viscous_J_ += host_.viscous_dissipation_J(t_host_booked_s_, t_s);
  excitation_J_ += host_.excitation_work_J(t_host_booked_s_, t_s);
  if (host_model_.has_infinite_mass()) {
    // A prescribed host carries its riders: their energy change is the host's work.
    excitation_J_ += rider_energy_J(host_.at(t_s)) - rider_energy_J(host_.at(t_host_booked_s_));
  }
  t_host_booked_s_ = t_s;
}

double HardEngine::rider_energy_J(const HostState& host) const {
  // The part of the riders' kinetic and potential energy that moves with the host.
  return riding_mass_kg_ * (0.5 * host.v_m_s * host.v_m_s - gravity_m_s2_.z() * host.z_m);
}

void HardEngine::restart_host(HostState start) {
  ++stats_.host_impulses;
  book_host(t_s_);
  const double old_velocity_m_s = host_.at(t_s_).v_m_s;
  const double velocity_change = std::abs(start.v_m_s - old_velocity_m_s);
  const double mass_change = std::abs(riding_mass_kg_ - trajectory_riding_mass_kg_);
  const double old_acceleration_bound = host_.acceleration_bound_m_s2();
  host_ = HostTrajectory(host_model_, t_s_, start, riding_mass_kg_, riding_mass_kg_ * gravity_m_s2_.z());
  trajectory_riding_mass_kg_ = riding_mass_kg_;
  ++host_epoch_;
  if (host_.speed_bound_m_s() > host_speed_envelope_m_s_) {
    host_speed_envelope_m_s_ = 2.0 * host_.speed_bound_m_s();
    rebuild_predictions();
    return;
  }
  if (!host_model_.has_infinite_mass()) {
    // The new trajectory minus the old one solves the host's equation with initial
    // velocity Δv and a force Δm (g_z − z_h''), so within τ it strays by at most
    // |Δv| τ + ½ Δm (|g_z| + |z_h''|max) / M_new τ².
    const double acceleration_change = mass_change * (std::abs(gravity_m_s2_.z()) + old_acceleration_bound) /
                                       (host_model_.mass_kg() + riding_mass_kg_);
    for (MarginTier& tier : tiers_) {
      const double tau = tier.horizon_s;
      tier.budget_m += velocity_change * tau + 0.5 * acceleration_change * tau * tau;
    }
  }
  // The outermost tier whose budget is spent is swept (with every tier inside it);
  // otherwise only the touching spheres need new predictions.
  const auto spent =
      std::find_if(tiers_.begin(), tiers_.end(), [](const MarginTier& t) { return t.budget_m >= t.margin_m; });
  if (spent != tiers_.end()) {
    sweep_tier(static_cast<std::size_t>(spent - tiers_.begin()));
  } else {
    const double velocity_change_m_s = start.v_m_s - old_velocity_m_s;
    touching_.sweep([&](int i) {
      if (mass_change == 0.0 && defer_touching(i, velocity_change_m_s)) {
        ++stats_.touching_deferrals;
        touching_.insert(i);
        return;
      }
      ++stats_.touching_repredictions;
      predict_host_relative(i, tiers_.size() - 1);
    });
  }
  predict_bed_release();
}

bool HardEngine::presses(double normal_z_from_support) const {
  // The support pushes the sphere while the relative gravity g − z_h'' points into it.
  const double relative_gravity_z = gravity_m_s2_.z() - host_.acceleration_m_s2(t_s_);
  return normal_z_from_support * relative_gravity_z < 0.0;
}

void HardEngine::rest_if_slow(int i, const Eigen::Vector3d& normal_from_support, const HostState& host) {
  const double side = normal_from_support.z() > 0 ? 1 : -1;
  const double leaving = (particles_.velocity_m_s.col(i) - host.v_m_s * e_z).dot(normal_from_support);
  if (leaving < resting_.rest_speed_m_s && presses(normal_from_support.z()) &&
      (riding_count_ == 0 || bed_side_ == side)) {
    bed_side_ = static_cast<int>(side);
    attach(i);
  } else {
    predict(i);
  }
}

void HardEngine::attach(int i) {
  ++stats_.rests;
  book_host(t_s_);  // with the riding mass of the interval that ends now
  const HostState host = host_.at(t_s_);
  const double m = particles_.mass_kg[i];
  const Eigen::Vector3d v = particles_.velocity_m_s.col(i);
  const double relative_vz = v.z() - host.v_m_s;
  // A perfectly inelastic, sticking collision with the host: the normal part of the loss
  // is impact, the sliding and spinning that stop are friction.
  const double friction_J =
      0.5 * m * (v.x() * v.x() + v.y() * v.y()) +
      0.5 * particles_.moment_of_inertia(i) * particles_.angular_velocity_rad_s.col(i).squaredNorm();
  HostState after = host;
  double impact_J;
  if (host_model_.has_infinite_mass()) {
    impact_J = 0.5 * m * relative_vz * relative_vz;
    excitation_J_ += m * (host.v_m_s - v.z()) * host.v_m_s;
  } else {
    const double carried = host_model_.mass_kg() + riding_mass_kg_;
    impact_J = 0.5 * m * carried / (m + carried) * relative_vz * relative_vz;
    after.v_m_s = (carried * host.v_m_s + m * v.z()) / (carried + m);
  }
  friction_J_ += friction_J;
  impact_J_ += impact_J;
  book_sphere_loss(i, impact_J, friction_J);
  const Eigen::Vector3d lab_position = particles_.position_m.col(i);
  free_cells_.remove(i);
  leave_host_sets(i);
  new_trajectory(i);
  sphere_[i].riding = 1;
  const Eigen::Vector3d host_frame = particles_.position_m.col(i) - host.z_m * e_z;
  particles_.position_m.col(i) = host_frame;
  particles_.velocity_m_s.col(i).setZero();
  particles_.angular_velocity_rad_s.col(i).setZero();
  rider_cells_.insert(i, grid_.cell_of(host_frame));
  riding_mass_kg_ += m;
  ++riding_count_;
  const double r = particles_.radius_m[i];
  const double depth = bed_side_ > 0 ? host_frame.z() + r : cavity_.height_m() - host_frame.z() + r;
  const bool deeper = depth > bed_depth_bound_m_;
  if (deeper) bed_depth_bound_m_ = depth + grid_.cell_size_m();
  restart_host(after);
  if (deeper) {
    rebuild_predictions();
  } else {
    repredict_near_around(lab_position);
  }
}

void HardEngine::detach(int i, const HostState& host) {
  book_host(t_s_);  // with the riding mass of the interval that ends now
  rider_cells_.remove(i);
  sphere_[i].riding = 0;
  new_trajectory(i);
  particles_.position_m.col(i) += host.z_m * e_z;
  particles_.velocity_m_s.col(i) = host.v_m_s * e_z;
  particles_.t_ref_s[i] = t_s_;
  enter_cell(i, grid_.coord_of(particles_.position_m.col(i)));
  --riding_count_;
  riding_mass_kg_ = riding_count_ > 0 ? riding_mass_kg_ - particles_.mass_kg[i] : 0.0;
}

void HardEngine::release_bed() {
  ++stats_.bed_releases;
  const HostState host = host_.at(t_s_);
  std::vector<int> released;
  for (int i = 0; i < static_cast<int>(particles_.size()); ++i) {
    if (sphere_[i].riding) released.push_back(i);
  }
  for (const int i : released) detach(i, host);
  restart_host(host);
  for (const int i : released) predict(i);
}

}  // namespace pdamp::hard
