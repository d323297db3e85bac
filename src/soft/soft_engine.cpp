#include "pdamp/soft/soft_engine.hpp"

#include <omp.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/soft/time_step.hpp"

namespace pdamp::soft {
namespace {

constexpr int side = 0, bottom = 1, top = 2;

CellGrid make_grid(const Scenario& scenario, const Particles& particles, double skin_m) {
  return CellGrid(scenario.cavity.radius_m(), scenario.cavity.height_m, 2.0 * particles.max_radius_m() + skin_m);
}

}  // namespace

SoftEngine::SoftEngine(const Scenario& scenario, const Particles& initial, SoftEngineOptions options)
    : scenario_(scenario),
      options_(options),
      host_model_(scenario),
      cavity_(scenario.cavity),
      dt_s_(choose_time_step_s(scenario)),
      neighbours_(make_grid(scenario, initial, options.skin_fraction * 2.0 * initial.max_radius_m()),
                  options.skin_fraction * 2.0 * initial.max_radius_m()) {
  const auto n = static_cast<std::size_t>(initial.size());
  x_.resize(n);
  v_.resize(n);
  w_.resize(n);
  force_.assign(n, Eigen::Vector3d::Zero());
  torque_.assign(n, Eigen::Vector3d::Zero());
  radius_.resize(n);
  mass_.resize(n);
  inv_mass_.resize(n);
  inv_inertia_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    x_[i] = initial.position_m.col(k);
    v_[i] = initial.velocity_m_s.col(k);
    w_[i] = initial.angular_velocity_rad_s.col(k);
    radius_[i] = initial.radius_m[k];
    mass_[i] = initial.mass_kg[k];
    inv_mass_[i] = 1.0 / mass_[i];
    inv_inertia_[i] = 1.0 / initial.moment_of_inertia(k);
  }
  wall_contacts_.assign(n, {ContactTable::none, ContactTable::none, ContactTable::none});
  contact_tables_.resize((n + chunk_size - 1) / chunk_size);

  host_ = host_model_.initial_state();
  if (options_.hold_host) host_.v_m_s = 0.0;
  ledger_.host_counts = !host_model_.has_infinite_mass();

  refresh_neighbours();
  compute_forces(0.0);
  // Contacts present at the start (a settled bed) store elastic energy that belongs to
  // E(0); nothing has been dissipated yet.
  ledger_.dissipated_impact_J = ledger_.dissipated_friction_J = ledger_.dissipated_viscous_J = 0.0;
  ledger_.excitation_work_J = 0.0;
}

void SoftEngine::advance_to(double t_s) {
  // Velocity Verlet, with the second half-kick of each step and the first of the next
  // fused into one pass; between calls the velocities are at full steps.
  double owed_kick_s = 0.0;
  while (t_s_ < t_s) {
    const double dt = next_step_s(t_s);
    move(owed_kick_s + 0.5 * dt, dt);
    refresh_neighbours();
    compute_forces(dt);
    owed_kick_s = 0.5 * dt;
    ++steps_;
  }
  kick(owed_kick_s);
  check_particles_inside();
}

double SoftEngine::next_step_s(double t_s) {
  // Take the remainder as the last step if a full step would overshoot (or leave a sliver).
  const double remaining = t_s - t_s_;
  if (remaining > dt_s_ * (1.0 + 1e-9)) return dt_s_;
  end_of_advance_s_ = t_s;
  return remaining;
}

void SoftEngine::check_particles_inside() const {
  for (std::size_t i = 0; i < x_.size(); ++i) {
    if (!x_[i].allFinite() || cavity_.clearance_m(x_[i], radius_[i], host_.z_m) < -radius_[i]) {
      std::ostringstream msg;
      msg << "particle " << i << " left the cavity at t = " << t_s_ << " s (position " << x_[i].transpose()
          << " m): a contact let it through. Contacts overlapped up to " << 100.0 * max_overlap_ratio_
          << " % of a radius: ";
      if (max_overlap_ratio_ > 0.5) {
        msg << "the contact law is too soft to stop impacts this fast (a stiffer k_n or a gentler excitation would)";
      } else {
        msg << "the time step " << dt_s_ << " s is too long for these contacts";
      }
      throw RuntimeFailure(msg.str());
    }
  }
}

void SoftEngine::kick(double dt_s) {
  for (std::size_t i = 0; i < x_.size(); ++i) {
    v_[i] += force_[i] * (inv_mass_[i] * dt_s);
    w_[i] += torque_[i] * (inv_inertia_[i] * dt_s);
  }
  if (options_.hold_host) return;
  if (host_model_.has_infinite_mass()) {
    host_.v_m_s = host_model_.prescribed_state(t_s_).v_m_s;
  } else {
    host_.v_m_s += host_acceleration_m_s2() * dt_s;
  }
}

void SoftEngine::move(double kick_s, double dt_s) {
  const double t_end = end_of_advance_s_ >= 0.0 ? end_of_advance_s_ : t_s_ + dt_s;
  end_of_advance_s_ = -1.0;
  if (options_.hold_host) {
    // Held still (settling): nothing moves the walls.
  } else if (host_model_.has_infinite_mass()) {
    // The walls move exactly as prescribed; their mean velocity over the step keeps the
    // contacts' slip consistent with that motion.
    const HostState prescribed = host_model_.prescribed_state(t_end);
    host_.v_m_s = (prescribed.z_m - host_.z_m) / dt_s;
    host_.z_m = prescribed.z_m;
  } else {
    host_.v_m_s += host_acceleration_m_s2() * kick_s;
    host_.z_m += host_.v_m_s * dt_s;
  }
  t_s_ = t_end;
  // Kick and drift each sphere in one pass, and see whether any has moved more
  // than half the skin relative to the host (whose motion changes no pair distance) since
  // the neighbour list was built.
  const Eigen::Vector3d host_shift(0.0, 0.0, host_.z_m - host_z_at_rebuild_);
  const double limit_sq = 0.25 * neighbours_.skin_m() * neighbours_.skin_m();
  bool beyond_skin = false;
  const int n = static_cast<int>(x_.size());
  // Through local pointers: Eigen's stores may alias anything, members would be reloaded
  // for every sphere.
  Eigen::Vector3d *const x = x_.data(), *const v = v_.data(), *const w = w_.data();
  const Eigen::Vector3d *const force = force_.data(), *const torque = torque_.data(), *const x0 = x_at_rebuild_.data();
  const double *const inv_mass = inv_mass_.data(), *const inv_inertia = inv_inertia_.data();
#pragma omp parallel for schedule(static) reduction(|| : beyond_skin) if (n >= parallel_minimum)
  for (int i = 0; i < n; ++i) {
    v[i] += force[i] * (inv_mass[i] * kick_s);
    w[i] += torque[i] * (inv_inertia[i] * kick_s);
    x[i] += v[i] * dt_s;
    beyond_skin |= (x[i] - x0[i] - host_shift).squaredNorm() > limit_sq;
  }
  needs_rebuild_ = beyond_skin;
}

void SoftEngine::refresh_neighbours() {
  if (!needs_rebuild_) return;
  needs_rebuild_ = false;
  neighbours_.rebuild(x_, radius_);
  compact_contact_tables();
  x_at_rebuild_ = x_;
  host_z_at_rebuild_ = host_.z_m;
  const int n = static_cast<int>(x_.size());
  most_pairs_in_a_chunk_ = 0;
  for (int first = 0; first < n; first += chunk_size) {
    const int pairs = neighbours_.first(std::min(n, first + chunk_size)) - neighbours_.first(first);
    most_pairs_in_a_chunk_ = std::max(most_pairs_in_a_chunk_, pairs);
  }
}

void SoftEngine::compact_contact_tables() {
  // Each chunk's open contacts renumbered in the order the force pass visits them, the
  // entries of closed ones dropped: the pass and the reactions then run through the table
  // front to back.
  const int n = static_cast<int>(x_.size());
  for (int c = 0; c < static_cast<int>(contact_tables_.size()); ++c) {
    ContactTable& table = contact_tables_[c];
    compacted_table_.clear();
    auto move_over = [&](int& contact) {
      if (contact != ContactTable::none) contact = compacted_table_.append(table[contact]);
    };
    const int first = c * chunk_size, end = std::min(n, first + chunk_size);
    for (int k = neighbours_.first(first); k < neighbours_.first(end); ++k) move_over(neighbours_.contact(k));
    for (int i = first; i < end; ++i) {
      for (int& contact : wall_contacts_[i]) move_over(contact);
    }
    table.copy_from(compacted_table_);  // not swapped: each table keeps a capacity fit for its chunk
  }
}

void SoftEngine::compute_forces(double dt_s) {
  // Each chunk of spheres is handled by one thread: its own forces, its pairs (whose
  // reactions on partners are set aside) and its walls. The reactions are then added to
  // the partners, and the chunks' totals summed, in chunk order — so the result is the
  // same bits whatever the number of threads.
  const int n = static_cast<int>(x_.size());
  const int chunks = (n + chunk_size - 1) / chunk_size;
  chunk_totals_.resize(chunks);
  pairs_to_evaluate_.resize(std::max<std::size_t>(pairs_to_evaluate_.size(), omp_get_max_threads()));
  for (auto& pairs : pairs_to_evaluate_) {
    if (pairs.size() < static_cast<std::size_t>(most_pairs_in_a_chunk_)) pairs.resize(most_pairs_in_a_chunk_);
  }
#pragma omp parallel for schedule(static) if (n >= parallel_minimum)
  for (int c = 0; c < chunks; ++c) {
    const int first = c * chunk_size, end = std::min(n, first + chunk_size);
    Wrench on_chunk[chunk_size];
    for (int i = first; i < end; ++i) on_chunk[i - first] = start_forces(i);
    // The pairs to evaluate are sifted out first, without a branch, and evaluated two at
    // a time in SIMD lanes.
    PairToEvaluate* pairs = pairs_to_evaluate_[omp_get_thread_num()].data();
    const int count = list_pairs_to_evaluate(first, end, pairs);
    ContactTable& contacts = contact_tables_[c];
    ChunkTotals totals;
    int evaluated = 0;
    for (; evaluated + 1 < count; evaluated += 2) {
      add_pair_contacts<Lanes>(pairs + evaluated, dt_s, first, contacts, totals, on_chunk);
    }
    if (evaluated < count) add_pair_contacts<double>(pairs + evaluated, dt_s, first, contacts, totals, on_chunk);
    for (int i = first; i < end; ++i) {
      Wrench& on_i = on_chunk[i - first];
      add_wall_contacts(i, dt_s, contacts, totals, on_i);
      force_[i] = on_i.force_N;
      torque_[i] = on_i.torque_N_m;
    }
    chunk_totals_[c] = totals;
  }
  add_reactions();

  contact_elastic_J_ = 0.0;
  contacts_ = 0;
  host_particle_force_N_ = 0.0;
  for (const ChunkTotals& t : chunk_totals_) {
    ledger_.dissipated_impact_J += t.impact_J;
    ledger_.dissipated_friction_J += t.friction_J;
    contact_elastic_J_ += t.elastic_J;
    host_particle_force_N_ += t.on_host_N;
    contacts_ += t.contacts;
    if (t.max_overlap_ratio > max_overlap_ratio_) {
      max_overlap_ratio_ = t.max_overlap_ratio;
      max_overlap_time_s_ = t_s_;
    }
  }
  add_host_forces();
}

SoftEngine::Wrench SoftEngine::start_forces(int i) const {
  const double drag = options_.settling_drag_1_s;
  if (drag == 0.0) return {mass_[i] * scenario_.gravity_m_s2, Eigen::Vector3d::Zero()};  // a run, not settling
  return {mass_[i] * (scenario_.gravity_m_s2 - drag * v_[i]), -drag / inv_inertia_[i] * w_[i]};
}

void SoftEngine::ChunkTotals::record_contact(double overlap_m, double radius_m) {
  ++contacts;
  max_overlap_ratio = std::max(max_overlap_ratio, overlap_m / radius_m);
}

int SoftEngine::list_pairs_to_evaluate(int first, int end, PairToEvaluate* out) const {
  // One loop over the chunk's pairs, not one per sphere: a sphere's few pairs would make
  // the loop's exit a branch mispredicted once per sphere.
  int count = 0;
  for (int k = neighbours_.first(first), last = neighbours_.first(end); k < last; ++k) {
    const int i = neighbours_.owner(k), j = neighbours_.partner(k);
    const double reach = radius_[i] + radius_[j];
    out[count] = {i, k};
    count += ((x_[i] - x_[j]).squaredNorm() < reach * reach) | (neighbours_.contact(k) != ContactTable::none);
  }
  return count;
}

template <class Real>
void SoftEngine::add_pair_contacts(const PairToEvaluate* pairs, double dt_s, int first, ContactTable& contacts,
                                   ChunkTotals& totals, Wrench* on_chunk) {
  constexpr int lanes = lane_count<Real>;
  int i[lanes], j[lanes], k[lanes];
  for (int l = 0; l < lanes; ++l) {
    i[l] = pairs[l].owner;
    k[l] = pairs[l].pair;
    j[l] = neighbours_.partner(k[l]);
  }
  const Vec3<Real> d = gather3<Real>([&](int l) { return x_[i[l]]; }) - gather3<Real>([&](int l) { return x_[j[l]]; });
  const Real ri = gather<Real>([&](int l) { return radius_[i[l]]; });
  const Real rj = gather<Real>([&](int l) { return radius_[j[l]]; });
  const Real reach = ri + rj;
  const Real distance = sqrt_of(squared_norm(d));
  // The contact point splits the centre distance in the ratio of the radii, so the
  // lever arms add up to the distance and angular momentum is conserved exactly.
  const Real share = distance / reach, lever_i = ri * share, lever_j = rj * share;
  const Vec3<Real> normal = d * (1.0 / distance);
  const Vec3<Real> spin_part = lever_i * gather3<Real>([&](int l) { return w_[i[l]]; }) +
                               lever_j * gather3<Real>([&](int l) { return w_[j[l]]; });
  const ContactKinematics<Real> contact{
      normal, reach - distance,
      gather3<Real>([&](int l) { return v_[i[l]]; }) - gather3<Real>([&](int l) { return v_[j[l]]; }) - cross(spin_part, normal)};
  auto history = [&](int l) -> const ContactHistory<>& { return contacts[neighbours_.contact(k[l])].history; };
  ContactHistory<Real> h{gather3<Real>([&](int l) { return history(l).tangential_displacement_m; }),
                         gather3<Real>([&](int l) { return history(l).tangential_force_N; }),
                         gather<Real>([&](int l) { return history(l).normal_damping_force_N; })};
  const ContactForce<Real> c = evaluate_contact(scenario_.soft_particle, contact, dt_s, h);
  const Vec3<Real> twist = cross(normal, c.tangential_N);
  const Vec3<Real> torque_on_i = lever_i * twist, torque_on_j = -lever_j * twist;
  const auto touching = contact.overlap_m > 0.0;
  for_each_lane<Real>([&](auto l) [[gnu::always_inline]] {
    const Vec3<double> force = lane(c.force_N, l);
    Wrench& on_i = on_chunk[i[l] - first];
    on_i.force_N += to_eigen(force);
    on_i.torque_N_m -= to_eigen(lane(torque_on_i, l));
    totals.impact_J += lane(c.dissipated_normal_J, l);
    totals.friction_J += lane(c.dissipated_tangential_J, l);
    totals.elastic_J += lane(c.elastic_J, l);
    int& open = neighbours_.contact(k[l]);
    if (lane_is_set(touching, l)) {
      if (open == ContactTable::none) open = contacts.open(j[l]);
      ContactTable::Entry& entry = contacts[open];
      entry.history = {lane(h.tangential_displacement_m, l), lane(h.tangential_force_N, l), lane(h.normal_damping_force_N, l)};
      entry.reaction_force_N = -force;
      entry.reaction_torque_N_m = lane(torque_on_j, l);
      totals.record_contact(lane(contact.overlap_m, l), std::min(lane(ri, l), lane(rj, l)));
    } else if (open != ContactTable::none) {
      contacts.close(open);  // came apart: no reaction, and the spring has let go
      open = ContactTable::none;
    }
  });
}

void SoftEngine::add_reactions() {
  for (const ContactTable& table : contact_tables_) {
    for (const ContactTable::Entry& entry : table.entries()) {
      if (entry.partner < 0) continue;
      force_[entry.partner] += to_eigen(entry.reaction_force_N);
      torque_[entry.partner] += to_eigen(entry.reaction_torque_N_m);
    }
  }
}

void SoftEngine::add_wall_contacts(int i, double dt_s, ContactTable& contacts, ChunkTotals& totals, Wrench& on_i) {
  const SoftContactLaw& law = scenario_.soft_wall;
  const double r = radius_[i];
  const double rho_sq = x_[i].x() * x_[i].x() + x_[i].y() * x_[i].y();
  const double side_limit = cavity_.radius_m() - r;
  const bool near[3] = {rho_sq > side_limit * side_limit, x_[i].z() - host_.z_m < r,
                        host_.z_m + cavity_.height_m() - x_[i].z() < r};
  std::array<int, 3>& open = wall_contacts_[i];
  // Most spheres are far from every wall: one test, without branches, lets them go.
  static_assert(ContactTable::none == 0);
  if (!(near[side] | near[bottom] | near[top]) && (open[side] | open[bottom] | open[top]) == 0) return;
  const Eigen::Vector3d wall_velocity(0.0, 0.0, host_.v_m_s);
  for (int wall = side; wall <= top; ++wall) {
    if (!near[wall] && open[wall] == ContactTable::none) continue;
    const WallGap gap = cavity_.gap(static_cast<Wall>(wall), x_[i], r, host_.z_m);
    const double lever = r + std::min(gap.gap_m, 0.0);  // the contact point is on the wall
    const ContactKinematics<double> contact{to_vec3(gap.normal), -gap.gap_m,
                                            to_vec3(v_[i] - lever * w_[i].cross(gap.normal) - wall_velocity)};
    ContactHistory<> history = contacts[open[wall]].history;
    const ContactForce<double> c = evaluate_contact(law, contact, dt_s, history);
    on_i.force_N += to_eigen(c.force_N);
    on_i.torque_N_m -= lever * gap.normal.cross(to_eigen(c.tangential_N));
    totals.on_host_N -= c.force_N.z;
    totals.impact_J += c.dissipated_normal_J;
    totals.friction_J += c.dissipated_tangential_J;
    totals.elastic_J += c.elastic_J;
    if (gap.gap_m < 0.0) {
      if (open[wall] == ContactTable::none) open[wall] = contacts.open(-1);
      contacts[open[wall]].history = history;
      totals.record_contact(-gap.gap_m, r);
    } else if (open[wall] != ContactTable::none) {
      contacts.close(open[wall]);
      open[wall] = ContactTable::none;
    }
  }
}

void SoftEngine::add_host_forces() {
  if (options_.hold_host) return;
  // The forces act at the end of the step (the damper on the half-step velocity, as the
  // contacts' dashpots); the books take the trapezoid of each over the step's displacements.
  const double y = host_model_.base_position_m(t_s_);
  const HostForces now{host_.z_m - y, host_.v_m_s - host_model_.base_velocity_m_s(t_s_),
                       host_model_.applied_force_N(t_s_), host_particle_force_N_, host_.z_m, y};
  host_other_force_N_ = host_model_.force_N(t_s_, host_);
  const HostForces& before = previous_host_forces_;
  const double dz = now.z_m - before.z_m, dy = now.base_m - before.base_m;
  if (host_model_.has_infinite_mass()) {
    // The walls' prescribed motion does work on the particles: the reaction of the
    // particles' force on the host, −F_particles, times the walls' displacement.
    ledger_.excitation_work_J -= 0.5 * (before.particles_N + now.particles_N) * dz;
  } else {
    const double k = host_model_.stiffness_N_m(), c = host_model_.damping_N_s_m();
    const double mean_damper_N = 0.5 * c * (before.stretch_rate_m_s + now.stretch_rate_m_s);
    ledger_.dissipated_viscous_J += mean_damper_N * (dz - dy);
    ledger_.excitation_work_J += 0.5 * (before.applied_N + now.applied_N) * dz -
                                 (0.5 * k * (before.stretch_m + now.stretch_m) + mean_damper_N) * dy;
  }
  previous_host_forces_ = now;
}

double SoftEngine::host_acceleration_m_s2() const {
  return (host_other_force_N_ + host_particle_force_N_) / host_model_.mass_kg();
}

double SoftEngine::particle_kinetic_J() const {
  double kinetic = 0.0;
  for (std::size_t i = 0; i < x_.size(); ++i) {
    kinetic += 0.5 * mass_[i] * v_[i].squaredNorm() + 0.5 * w_[i].squaredNorm() / inv_inertia_[i];
  }
  return kinetic;
}

Observation SoftEngine::observe() const {
  Observation o;
  o.t_s = t_s_;
  o.host = host_;
  o.energy = ledger_;
  for (std::size_t i = 0; i < x_.size(); ++i) {
    o.energy.particle_translational_J += 0.5 * mass_[i] * v_[i].squaredNorm();
    o.energy.particle_rotational_J += 0.5 * w_[i].squaredNorm() / inv_inertia_[i];
    o.energy.gravitational_potential_J -= mass_[i] * scenario_.gravity_m_s2.dot(x_[i]);
  }
  o.energy.host_kinetic_J = 0.5 * host_model_.mass_kg() * host_.v_m_s * host_.v_m_s;
  o.energy.spring_potential_J = host_model_.spring_energy_J(t_s_, host_.z_m);
  o.energy.contact_elastic_J = contact_elastic_J_;
  o.counters.steps = steps_;
  o.counters.contacts = contacts_;
  return o;
}

State SoftEngine::state() const {
  State s{observe(), Particles(static_cast<Eigen::Index>(x_.size()))};
  for (std::size_t i = 0; i < x_.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    s.particles.position_m.col(k) = x_[i];
    s.particles.velocity_m_s.col(k) = v_[i];
    s.particles.angular_velocity_rad_s.col(k) = w_[i];
    s.particles.radius_m[k] = radius_[i];
    s.particles.mass_kg[k] = mass_[i];
  }
  return s;
}

EngineStatistics SoftEngine::statistics() const {
  return {{"steps", steps_},
          {"neighbour_rebuilds", neighbours_.rebuilds()},
          {"neighbour_pairs", neighbours_.size()},
          {"max_overlap_ppm_of_radius", std::llround(max_overlap_ratio_ * 1e6)}};
}

std::vector<std::string> SoftEngine::warnings() const {
  constexpr double overlap_warning_ratio = 0.02;
  if (max_overlap_ratio_ <= overlap_warning_ratio) return {};
  std::ostringstream msg;
  msg.precision(3);
  msg << "contacts overlapped up to " << 100.0 * max_overlap_ratio_ << " % of a sphere radius (t = "
      << max_overlap_time_s_ << " s): the contact law is soft for these impacts, so results depend on k_n there";
  return {msg.str()};
}

}  // namespace pdamp::soft
