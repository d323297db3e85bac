#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

#include "hard/hard_engine_class.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/model/placement.hpp"

namespace pdamp::hard {

namespace {

const Eigen::Vector3d e_z = Eigen::Vector3d::UnitZ();

}  // namespace

HardEngine::HardEngine(const Scenario& scenario, const Particles& initial, const RestitutionTable* calibration)
    : flight_(scenario, initial),
      books_(static_cast<int>(initial.size()), HostModel(scenario).excitation_phase()),
      host_(scenario, initial, flight_, books_),
      jams_(static_cast<int>(initial.size())),
      clusters_(static_cast<int>(initial.size()), scenario.hard_resting.cluster_speed_m_s),
      laws_(scenario, calibration),
      // A collision cascade through a touching bed can take a few events per contact at
      // one instant; far more than that means no progress.
      stall_limit_(1000 * static_cast<std::int64_t>(initial.size()) + 100000),
      max_events_(scenario.run.max_events),
      next_poll_(std::min(poll_interval, max_events_ + 1)),
      next_check_event_(check_events()) {
  // A bed settled with soft contacts overlaps by a tiny fraction of a radius: the hard
  // engine starts from it with the spheres pushed just apart.
  Particles separated = initial;
  const Eigen::Vector3d& g = scenario.gravity_m_s2;
  const Eigen::Vector3d up = g.norm() > 0.0 ? Eigen::Vector3d(-g.normalized()) : Eigen::Vector3d::UnitZ();
  separation_m_ = separate_overlaps(separated, scenario.cavity, host_.trajectory().at(0.0).z_m, up);
  flight_.start(separated);
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
  EventQueue& queue = flight_.queue();
  const auto current = [this](const Event& e) { return flight_.is_current(e, host_.epoch()); };
  for (const Event* next = queue.top(current); next && next->t_s <= t_s; next = queue.top(current)) {
    const Event event = *next;
    queue.pop();
    if (++events_ >= next_poll_) poll();
    if (!current(event)) {
      ++books_.counts.stale;
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
  host_.book(t_s);
  check_overlaps(t_s);
}

void HardEngine::check_overlaps(double t_s) {
  // In every build: a missed event lets a sphere pass through a wall or another sphere,
  // and the run would go on to a plausible-looking wrong result.
#ifdef NDEBUG
  if (events_ < next_check_event_ && ++calls_since_check_ < check_calls) return;
#endif
  next_check_event_ = events_ + check_events();
  calls_since_check_ = 0;
  if (const Overlap overlap = deepest_overlap(); overlap.depth_m > overlap_tolerance_m()) {
    std::ostringstream why;
    why << "hard engine invariant broken at t = " << t_s << " s: " << describe(overlap) << " overlap by "
        << overlap.depth_m << " m (tolerance " << overlap_tolerance_m() << " m); the engine missed an event";
    why << known_cause(overlap);
    throw RuntimeFailure(why.str());
  }
}

std::string HardEngine::known_cause(const Overlap& overlap) const {
  // Known limitations (docs/hard-engine.md, "Resting beds and inelastic collapse"), not new
  // defects: say what to run instead.
  std::ostringstream why;
  const double across_axis_m_s2 = flight_.gravity_m_s2().head<2>().norm();
  if (overlap.j < 0 && overlap.wall == Wall::side && across_axis_m_s2 > 0.0) {
    why << ". The hard model cannot rest spheres that gravity presses against the side wall (here " << across_axis_m_s2
        << " m/s^2 of it across the cylinder's axis): run this scenario with --model soft";
  } else if (!host_.resting_on()) {
    why << ". Resting is off (hard.rest_speed_m_s = 0 without hard.rest_tc_window): spheres that the host "
           "presses against its walls keep bouncing on them, where the hard model is known to fail; turn resting on";
  } else {
    return ", a defect to report";
  }
  why << " (docs/hard-engine.md, \"Resting beds and inelastic collapse\")";
  return why.str();
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
  if (flight_.sphere(i).riding) return flight_.particles().position_m.col(i) + host.z_m * e_z;
  return flight_.flight(i).position_at(t_s_, flight_.gravity_m_s2());
}

State HardEngine::state() const {
  const PackedParticles& particles = flight_.particles();
  State s{observe(), particles.unpacked()};
  const HostState host = s.observation.host;
  for (Eigen::Index i = 0; i < particles.size(); ++i) {
    const int k = static_cast<int>(i);
    s.particles.position_m.col(i) = position_now(k, host);
    s.particles.velocity_m_s.col(i) = flight_.sphere(k).riding
                                          ? Eigen::Vector3d(host.v_m_s * e_z)
                                          : flight_.flight(k).velocity_at(t_s_, flight_.gravity_m_s2());
  }
  return s;
}

Observation HardEngine::observe() const {
  const PackedParticles& particles = flight_.particles();
  const HostModel& model = host_.model();
  Observation o;
  o.t_s = t_s_;
  o.host = host_.trajectory().at(t_s_);
  EnergyLedger& e = o.energy;
  ParticleEnergySums sums;
  for (Eigen::Index i = 0; i < particles.size(); ++i) {
    const int k = static_cast<int>(i);
    const Eigen::Vector3d v = flight_.sphere(k).riding ? Eigen::Vector3d(o.host.v_m_s * e_z)
                                                       : flight_.flight(k).velocity_at(t_s_, flight_.gravity_m_s2());
    sums.add(particles.mass_kg[i], particles.moment_of_inertia(i), position_now(k, o.host), v,
             particles.angular_velocity_rad_s.col(i), flight_.gravity_m_s2());
  }
  sums.write_to(e);
  model.write_energy_to(e, t_s_, o.host);
  // Everything is booked up to t_s_ after advance_to; the books add the rest for an
  // observation taken before the first advance.
  books_.write_to(o, host_.trajectory(), t_s_, host_.riders());
  o.counters.collisions = collisions();
  o.counters.riding_spheres = host_.riding_count();
  return o;
}

std::vector<std::string> HardEngine::warnings() const {
  // A few percent of a radius is where soft overlaps stop being a resting bed's (the
  // soft engine warns there too); a push that large changes the start noticeably.
  if (separation_m_ <= 0.05 * flight_.max_radius_m()) return {};
  std::ostringstream text;
  text << "the initial spheres overlapped: separating them moved a sphere by up to " << separation_m_ << " m";
  return {text.str()};
}

EngineStatistics HardEngine::statistics() const {
  EngineStatistics named = books_.counts.named();
  if (diagnosis_) {
    const EngineStatistics diagnosed = diagnosis_->named();
    named.insert(named.end(), diagnosed.begin(), diagnosed.end());
  }
  if (clusters_.enabled()) {
    const EngineStatistics clustered = clusters_.named();
    named.insert(named.end(), clustered.begin(), clustered.end());
  }
  return named;
}

void HardEngine::diagnose(EventDiagnosis::Kind kind, int i, int partner, double approach_m_s) {
  const PackedParticles& particles = flight_.particles();
  const double mi = particles.mass_kg[i];
  const double effective_mass_kg =
      partner < 0 ? mi : mi * particles.mass_kg[partner] / (mi + particles.mass_kg[partner]);
  const double partner_previous_s = kind == EventDiagnosis::sphere_sphere ? flight_.sphere(partner).last_collision_s
                                                                          : std::numeric_limits<double>::quiet_NaN();
  diagnosis_->note(kind, t_s_, approach_m_s, effective_mass_kg, flight_.sphere(i).last_collision_s, partner_previous_s);
}

std::string HardEngine::describe(const Overlap& overlap) const {
  const auto sphere = [&](int k) {
    return "sphere " + std::to_string(k) + (flight_.sphere(k).riding ? " (riding)" : " (free)");
  };
  if (overlap.j >= 0) return sphere(overlap.i) + " and " + sphere(overlap.j);
  static constexpr std::array<const char*, 3> walls{"the side wall", "the floor", "the top cap"};
  return sphere(overlap.i) + " and " + walls[static_cast<std::size_t>(overlap.wall)];
}

HardEngine::Overlap HardEngine::deepest_overlap() const {
  const HostState host = host_.trajectory().at(t_s_);
  const PackedParticles& particles = flight_.particles();
  const CellGrid& grid = flight_.grid();
  const auto n = particles.size();
  Eigen::Matrix3Xd positions(3, n);
  for (Eigen::Index i = 0; i < n; ++i) positions.col(i) = position_now(static_cast<int>(i), host);
  CellList cells;
  cells.build(grid, positions);
  Overlap deepest;
  const auto note = [&](double depth_m, Eigen::Index i, int j, Wall wall = Wall::side) {
    if (depth_m > deepest.depth_m) deepest = {depth_m, static_cast<int>(i), j, wall};
  };
  std::array<int, 27> around{};
  const Cavity& cavity = flight_.cavity();
  for (Eigen::Index i = 0; i < n; ++i) {
    const double r = particles.radius_m[i];
    for (const Wall wall : {Wall::side, Wall::bottom, Wall::top}) {
      note(-cavity.gap(wall, positions.col(i), r, host.z_m).gap_m, i, -1, wall);
    }
    const int count = grid.neighbours(grid.coord_of(positions.col(i)), around);
    for (int c = 0; c < count; ++c) {
      for (const int j : cells.particles_in(around[c])) {
        if (j <= i) continue;
        note(r + particles.radius_m[j] - (positions.col(i) - positions.col(j)).norm(), i, j);
      }
    }
  }
  return deepest;
}

// ---------------------------------------------------------------------------------------------
// Prediction

void HardEngine::predict(int i, std::span<const int> new_cells) {
  if (flight_.predict(i, new_cells, t_s_, host_.reach(t_s_))) {
    host_.enter_near(i, t_s_);
  } else {
    host_.leave_sets(i);
  }
}

void HardEngine::rebuild_predictions() {
  ++books_.counts.rebuilds;
  flight_.queue().clear();
  host_.forget_predictions();
  for (int i = 0; i < flight_.size(); ++i) {
    if (!flight_.sphere(i).riding) predict(i);
  }
  host_.predict_bed_release(t_s_);
}

// ---------------------------------------------------------------------------------------------
// Events

void HardEngine::handle(const Event& e) {
  HardStatistics& counts = books_.counts;
  switch (e.kind) {
    case EventKind::sphere_sphere:
      ++counts.sphere_sphere;
      collide_spheres(e.i, e.j);
      return;
    case EventKind::side_wall:
      ++counts.side_wall;
      collide_wall(e.i, e.kind);
      return;
    case EventKind::bottom_cap:
    case EventKind::top_cap:
      ++counts.cap;
      collide_wall(e.i, e.kind);
      return;
    case EventKind::rider:
      ++counts.rider;
      collide_rider(e.i, e.j);
      return;
    case EventKind::cell_crossing:
      ++counts.cell_crossing;
      predict(e.i, flight_.cross_face(e.i, static_cast<FreeFlight::Face>(e.j)));
      return;
    case EventKind::host_check:
      ++counts.host_check;
      host_.enter_near(e.i, t_s_);
      return;
    case EventKind::host_margin:
      ++counts.host_margin;
      host_.predict_relative(e.i, static_cast<std::size_t>(e.j), t_s_);
      return;
    case EventKind::bed_release:
      if (e.j == 1) {
        release_bed();
      } else {
        host_.predict_bed_release(t_s_);
      }
      return;
  }
}

inline HardContactLaw HardEngine::law_for(double approach_speed_m_s, Partner partner, int i, int j, int rider) {
  // A sphere wedged between two bodies collides again at the same instant (ContactLaws).
  SphereState& a = flight_.sphere(i);
  const bool repeat = a.last_collision_s == t_s_ || (j >= 0 && flight_.sphere(j).last_collision_s == t_s_);
  const bool lasting =
      laws_.tc_model() && within_tc_window(approach_speed_m_s, partner != Partner::sphere, i, j, rider);
  a.last_collision_s = t_s_;
  if (j >= 0) flight_.sphere(j).last_collision_s = t_s_;
  return laws_.at(approach_speed_m_s, partner, repeat, lasting);
}

bool HardEngine::within_tc_window(double approach_speed_m_s, bool wall, int i, int j, int rider) const {
  const PackedParticles& particles = flight_.particles();
  const int partner = j >= 0 ? j : rider;
  const double mi = particles.mass_kg[i];
  const double effective_mass_kg =
      partner < 0 ? mi : mi * particles.mass_kg[partner] / (mi + particles.mass_kg[partner]);
  const double previous_s = j >= 0 ? std::max(flight_.sphere(i).last_collision_s, flight_.sphere(j).last_collision_s)
                                   : flight_.sphere(i).last_collision_s;
  return laws_.within_tc_window(t_s_ - previous_s, effective_mass_kg, wall, approach_speed_m_s);
}

void HardEngine::collide_spheres(int i, int j) {
  // The cells around both spheres are asked for first: with many spheres they are out of
  // cache, and their loads then overlap the collision instead of stalling the predictions.
  const FreeFlight::Around around_i = flight_.around(i), around_j = flight_.around(j);
  flight_.prefetch_cells(around_i);
  flight_.prefetch_cells(around_j);
  flight_.bring_to_now(i, t_s_);
  flight_.bring_to_now(j, t_s_);
  if (jams_.note_collision(i, j, t_s_)) {
    merge_jam(i);
    return;
  }
  PackedParticles& particles = flight_.particles();
  const double ri = particles.radius_m[i], rj = particles.radius_m[j];
  const Eigen::Vector3d n = (particles.position_m.col(j) - particles.position_m.col(i)).normalized();
  const Eigen::Vector3d dv = particles.velocity_m_s.col(i) - particles.velocity_m_s.col(j);
  const Eigen::Vector3d u =
      dv + (ri * particles.angular_velocity_rad_s.col(i) + rj * particles.angular_velocity_rad_s.col(j)).cross(n);
  const double mi = particles.mass_kg[i], mj = particles.mass_kg[j];
  const double approach = dv.dot(n);
  if (diagnosis_) [[unlikely]]
    diagnose(EventDiagnosis::sphere_sphere, i, j, approach);
  if (clusters_.enabled() && join_clusters(i, j, approach)) [[unlikely]]
    return;
  const HardContactLaw law = law_for(approach, Partner::sphere, i, j);
  const CollisionOutcome out = walton_collision(u, n, approach, sphere_mobility(mi) + sphere_mobility(mj), law);
  const Eigen::Vector3d& p = out.impulse_N_s;
  const Eigen::Vector3d torque_arm = n.cross(p);
  particles.velocity_m_s.col(i) += p / mi;
  particles.velocity_m_s.col(j) -= p / mj;
  particles.angular_velocity_rad_s.col(i) += ri * torque_arm / particles.moment_of_inertia(i);
  particles.angular_velocity_rad_s.col(j) += rj * torque_arm / particles.moment_of_inertia(j);
  books_.book(out, i, j);
  flight_.new_trajectory(i);
  flight_.new_trajectory(j);
  predict(i, around_i);
  predict(j, around_j);
}

bool HardEngine::join_clusters(int i, int j, double approach_m_s) {
  if (!clusters_.merges(approach_m_s)) {
    clusters_.leave(i);
    clusters_.leave(j);
    return false;
  }
  // The loss splits as the motion at this contact: the other contacts of the two
  // clusters have none (each moved rigidly).
  ContactMotion motion;
  motion.add(i, j, flight_.particles());
  flight_.sphere(i).last_collision_s = t_s_;
  flight_.sphere(j).last_collision_s = t_s_;
  const std::span<const int> members = clusters_.join(i, j);
  for (const int k : members) {
    flight_.bring_to_now(k, t_s_);
    flight_.new_trajectory(k);
  }
  merge_into_rigid_body(members, motion.impact_share(), flight_.particles(), books_);
  for (const int k : members) predict(k);
  return true;
}

void HardEngine::merge_jam(int i) {
  const JamResolver::Cluster cluster = jams_.cluster_of(i, [this](int j) { return flight_.sphere(j).riding != 0; });
  for (const int k : cluster.members) {
    clusters_.leave(k);
    flight_.bring_to_now(k, t_s_);
    flight_.new_trajectory(k);
  }
  jams_.merge_rigidly(cluster, flight_.particles(), books_);
  if (cluster.hold) {
    const HostState host = host_.now(t_s_);
    const VerticalSticking stuck =
        jams_.stick_to_host(cluster, host, host_.prescribed(), host_.carried_mass_kg(), flight_.particles(), books_);
    host_.take_impulse(-stuck.body_impulse_N_s, t_s_);
    for (const int k : cluster.members) host_.leave_sets(k);
    if (stuck.host_v_m_s != host.v_m_s) restart_host({host.z_m, stuck.host_v_m_s});
    ++books_.counts.jam_stuck_to_host;
  }
  ++books_.counts.jam_merges;
  books_.counts.jam_merged_spheres += static_cast<std::int64_t>(cluster.members.size());
  for (const int k : cluster.members) predict(k);
}

HostState HardEngine::apply_host_impulse(int i, const Eigen::Vector3d& n, const CollisionOutcome& out,
                                         const HostState& host, int rider) {
  PackedParticles& particles = flight_.particles();
  const Eigen::Vector3d& p = out.impulse_N_s;
  const double r = particles.radius_m[i];
  particles.velocity_m_s.col(i) += p / particles.mass_kg[i];
  particles.angular_velocity_rad_s.col(i) += r * n.cross(p) / particles.moment_of_inertia(static_cast<Eigen::Index>(i));
  books_.book(out, i, rider);
  flight_.new_trajectory(i);
  clusters_.leave(i);
  host_.leave_sets(i);
  host_.take_impulse(-p.z(), t_s_);
  if (host_.prescribed()) {
    books_.excitation_J += p.z() * host.v_m_s;  // the wall's work on the sphere
    return host;
  }
  return {host.z_m, host.v_m_s - p.z() * host_.inverse_mass_1_kg()};
}

void HardEngine::collide_wall(int i, EventKind wall) {
  flight_.bring_to_now(i, t_s_);
  const bool side_wall = wall == EventKind::side_wall;
  if (jams_.note_collision(i, -1, t_s_, side_wall ? JamResolver::held_by_side_wall : JamResolver::held_by_cap_or_bed)) {
    merge_jam(i);
    return;
  }
  PackedParticles& particles = flight_.particles();
  const HostState host = host_.now(t_s_);
  const Eigen::Vector3d x = particles.position_m.col(i);
  Eigen::Vector3d n;  // from the sphere towards the wall
  if (side_wall) {
    n = Eigen::Vector3d(x.x(), x.y(), 0.0).normalized();
  } else {
    n = wall == EventKind::bottom_cap ? -e_z : e_z;
  }
  const double r = particles.radius_m[i];
  const Eigen::Vector3d dv = particles.velocity_m_s.col(i) - host.v_m_s * e_z;
  const Eigen::Vector3d u = dv + (r * particles.angular_velocity_rad_s.col(i)).cross(n);
  const Mobility mobility = sphere_mobility(particles.mass_kg[i]) + Mobility{0, 0, host_.inverse_mass_1_kg()};
  // As predicted: the cap's gap rate ∓(v_z − v_h), the side wall's x·v in the plane.
  const double approach = side_wall ? x.head<2>().dot(dv.head<2>()) / x.head<2>().norm()
                                    : n.z() * (particles.velocity_m_s(2, i) - host.v_m_s);
  if (diagnosis_) [[unlikely]]
    diagnose(side_wall ? EventDiagnosis::side_wall : EventDiagnosis::cap, i, -1, approach);
  const HardContactLaw law = law_for(approach, side_wall ? Partner::side_wall : Partner::cap, i, -1);
  const CollisionOutcome out = walton_collision(u, n, approach, mobility, law);
  const HostState after = apply_host_impulse(i, n, out, host);
  if (side_wall) {
    particles.velocity_m_s.col(i).head<2>() = turned_along_side_wall(particles.velocity_m_s.col(i).head<2>(),
                                                                     n.head<2>(), laws_.side_wall_elastic_speed_m_s());
    if (after.v_m_s != host.v_m_s) restart_host(after);
    predict(i);
  } else {
    rest_if_slow(i, -n, -1, host, after);
  }
}

void HardEngine::collide_rider(int i, int j) {
  flight_.bring_to_now(i, t_s_);
  PackedParticles& particles = flight_.particles();
  const HostState host = host_.trajectory().at(t_s_);
  const double ri = particles.radius_m[i];
  // dx and dv exactly as rider_contact computes them, so the approach agrees with the prediction.
  Eigen::Vector3d dx = particles.position_m.col(i) - particles.position_m.col(j);
  dx.z() -= host.z_m;
  Eigen::Vector3d dv = particles.velocity_m_s.col(i);
  dv.z() -= host.v_m_s;
  const Eigen::Vector3d n = -dx.normalized();
  const double approach = -dx.dot(dv) / dx.norm();
  const Eigen::Vector3d u = dv + (ri * particles.angular_velocity_rad_s.col(i)).cross(n);
  const bool jammed = jams_.note_collision(i, -1, t_s_, JamResolver::held_by_cap_or_bed);
  // How slowly it must come to stay on the rider: as slowly as it would rest there.
  const double rest_speed = host_.rest_speed_m_s(i, j, -n.z(), host, t_s_);
  if (jammed && approach <= rest_speed) {
    // Wedged among riders and still colliding at this one instant: friction can turn the
    // slip along one contact into approach towards the next for ever. The sphere is
    // jammed in the bed, so it comes to rest in it.
    ++books_.counts.jammed;
    attach(i, host_.bed_side(), j, host);
    return;
  }
  if (approach > rest_speed) {
    // Hit hard enough to knock the rider off: it leaves the bed with the host's velocity
    // (no momentum changes hands) and the collision is between two free spheres.
    ++books_.counts.knocked_off;
    host_.detach(j, host, t_s_);
    restart_host(host);
    collide_spheres(i, j);
    return;
  }
  const Mobility mobility = sphere_mobility(particles.mass_kg[i]) + Mobility{0, 0, host_.inverse_mass_1_kg()};
  if (diagnosis_) [[unlikely]]
    diagnose(EventDiagnosis::rider, i, j, approach);
  const HardContactLaw law = law_for(approach, Partner::sphere, i, -1, j);
  const CollisionOutcome out = walton_collision(u, n, approach, mobility, law);
  rest_if_slow(i, -n, j, host, apply_host_impulse(i, n, out, host, j));
}

// ---------------------------------------------------------------------------------------------
// The host and the resting bed

void HardEngine::restart_host(HostState start) {
  if (!host_.restart(start, t_s_)) rebuild_predictions();
}

void HardEngine::rest_if_slow(int i, const Eigen::Vector3d& normal_from_support, int support, const HostState& before,
                              const HostState& after) {
  const double leaving = (flight_.particles().velocity_m_s.col(i) - after.v_m_s * e_z).dot(normal_from_support);
  if (host_.rests(i, support, leaving, normal_from_support.z(), after, t_s_)) {
    attach(i, normal_from_support.z() > 0 ? 1 : -1, support, after);
    return;
  }
  if (after.v_m_s != before.v_m_s) restart_host(after);
  predict(i);
}

void HardEngine::attach(int i, int side, int support, const HostState& host) {
  clusters_.leave(i);
  const HostCoupling::Attached attached = host_.attach(i, side, support, host, t_s_);
  restart_host(attached.host_after);
  if (attached.bed_deeper) {
    rebuild_predictions();
  } else {
    host_.repredict_near_around(attached.lab_position_m, t_s_);
  }
}

void HardEngine::release_bed() {
  ++books_.counts.bed_releases;
  const HostState host = host_.trajectory().at(t_s_);
  std::vector<int> released;
  for (int i = 0; i < flight_.size(); ++i) {
    if (flight_.sphere(i).riding) released.push_back(i);
  }
  for (const int i : released) host_.detach(i, host, t_s_);
  restart_host(host);
  for (const int i : released) predict(i);
}

std::unique_ptr<Engine> make_hard_engine(const Scenario& scenario, const Particles& initial,
                                         const RestitutionTable* calibration, bool diagnose_events) {
  auto engine = std::make_unique<HardEngine>(scenario, initial, calibration);
  if (diagnose_events) engine->diagnose_events(scenario);
  return engine;
}

}  // namespace pdamp::hard
