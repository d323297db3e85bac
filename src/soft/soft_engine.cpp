#include <omp.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <numeric>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/soft/time_step.hpp"
#include "soft/soft_engine_class.hpp"

namespace pdamp::soft {
namespace {

constexpr int side = 0, bottom = 1, top = 2;

CellGrid make_grid(const Scenario& scenario, const Particles& particles, double skin_m) {
  return CellGrid(scenario.cavity.radius_m(), scenario.cavity.height_m, 2.0 * particles.max_radius_m() + skin_m);
}

// A pass's kernel for chunk c, compiled for one instruction set: flattened, so that
// everything the kernel calls is compiled into it, for that instruction set.
template <class Pass>
[[gnu::flatten]] void run_sse2(Pass& pass, int c) {
  pass.template run<Lanes2>(c);
}
template <class Pass>
[[gnu::target("avx2,popcnt"), gnu::flatten]] void run_avx2(Pass& pass, int c) {
  pass.template run<Lanes4>(c);
}
template <class Pass>
[[gnu::target("avx512f,popcnt"), gnu::flatten]] void run_avx512(Pass& pass, int c) {
  pass.template run<Lanes8>(c);
}

/// One sphere's ball per lane: x, y, z, radius.
template <class Real>
[[gnu::always_inline]] inline Fields4<Real> gather_balls(const double* balls, const int* sphere) {
  return load_records<Real>([&](int l) { return balls + 4 * std::ptrdiff_t{sphere[l]}; });
}

/// One sphere's vector (velocity or spin) per lane.
template <class Real>
[[gnu::always_inline]] inline Vec3<Real> gather_vectors(const SphereMotions& motions, const int* sphere) {
  const Fields4<Real> f = load_records<Real>([&](int l) { return motions.data() + 4 * std::ptrdiff_t{sphere[l]}; });
  return {f.a, f.b, f.c};
}

/// The owners and partners of a register's worth of pairs (NeighbourList::owner_of and
/// partner_of, all lanes at once).
template <class Real>
[[gnu::always_inline]] inline void unpack_pairs(const int* pairs, int group_first, int* owners, int* partners) {
  using Ints = IntLanes<Real>;
  Ints packed;
  std::memcpy(&packed, pairs, sizeof packed);
  const Ints owner = group_first + (packed & (NeighbourList::group_size - 1)),
             partner = packed >> NeighbourList::group_bits;
  std::memcpy(owners, &owner, sizeof owner);
  std::memcpy(partners, &partner, sizeof partner);
}

/// Repeats the last of out[0, count) over a register's worth past it, so that the last
/// register evaluated reads real entries (whose results it drops).
template <class Real>
[[gnu::always_inline]] inline void pad_lanes(int* out, int count) {
  for (int l = 0; l < lane_count<Real> && count > 0; ++l) out[count + l] = out[count - 1];
}

}  // namespace

struct SoftEngine::DriftPass {
  SoftEngine& engine;
  double kick_s, dt_s;
  std::atomic<bool> beyond_skin{false};

  template <class Real>
  [[gnu::always_inline]] void run(int c) {
    if (engine.drift_chunk<Real>(c, kick_s, dt_s)) beyond_skin.store(true, std::memory_order_relaxed);
  }
};

struct SoftEngine::ForcePass {
  SoftEngine& engine;
  double dt_s;

  template <class Real>
  [[gnu::always_inline]] void run(int c) {
    engine.force_chunk<Real>(c, dt_s);
  }
};

struct SoftEngine::BuildPass {
  SoftEngine& engine;

  template <class Real>
  [[gnu::always_inline]] void run(int part) {
    engine.neighbours_.build_part<Real>(part, engine.balls_);
  }
};

bool SoftEngine::runs_in_parallel() const {
  // Not even through a parallel region of one thread: entering one costs.
  return sphere_count() >= options_.parallel_minimum_spheres && omp_get_max_threads() > 1;
}

template <class Pass>
auto SoftEngine::kernel() const -> void (*)(Pass&, int) {
  switch (simd_path_) {
    case SimdPath::sse2:
      return &run_sse2<Pass>;
    case SimdPath::avx2:
      return &run_avx2<Pass>;
    case SimdPath::avx512:
      break;
  }
  return &run_avx512<Pass>;
}

template <class Pass>
void SoftEngine::run_kernel(Pass& pass, int count) {
  void (*const run)(Pass&, int) = kernel<Pass>();
  if (!runs_in_parallel()) {
    for (int c = 0; c < count; ++c) run(pass, c);
    return;
  }
#pragma omp parallel for schedule(static)
  for (int c = 0; c < count; ++c) run(pass, c);
}

SoftEngine::SoftEngine(const Scenario& scenario, const Particles& initial, SoftEngineOptions options)
    : scenario_(scenario),
      options_(options),
      simd_path_(options.simd_path.value_or(default_simd_path())),
      host_model_(scenario),
      cavity_(scenario.cavity),
      dt_s_(choose_time_step_s(scenario)),
      neighbours_(make_grid(scenario, initial, options.skin_fraction * 2.0 * initial.max_radius_m()),
                  options.skin_fraction * 2.0 * initial.max_radius_m()) {
  require_available(simd_path_, "the soft engine's simd_path");
  if (initial.size() > NeighbourList::max_spheres) {
    throw InputError("the soft engine holds at most " + std::to_string(NeighbourList::max_spheres) + " spheres");
  }
  const int n = static_cast<int>(initial.size());
  balls_.assign(n);
  v_.assign(n);
  w_.assign(n);
  for (SphereVectors* field : {&force_, &torque_, &x_at_rebuild_}) field->assign(n, 0.0);
  for (SphereScalars* field : {&mass_, &impact_J_, &friction_J_}) field->assign(n, 0.0);
  original_index_.resize(n);
  for (int i = 0; i < n; ++i) {
    balls_[i] = {initial.position_m(0, i), initial.position_m(1, i), initial.position_m(2, i), initial.radius_m[i]};
    const auto v = initial.velocity_m_s.col(i), w = initial.angular_velocity_rad_s.col(i);
    mass_[i] = initial.mass_kg[i];
    v_[i] = {v.x(), v.y(), v.z(), 1.0 / mass_[i]};
    w_[i] = {w.x(), w.y(), w.z(), 1.0 / initial.moment_of_inertia(i)};
    original_index_[i] = i;
  }
  for (std::vector<int>& at_wall : wall_contacts_) at_wall.assign(n, ContactTable::none);
  contact_tables_.resize(chunk_count());
  next_contact_tables_.resize(chunk_count());
  reactions_.resize(chunk_count());
  chunk_totals_.resize(chunk_count());

  host_ = host_model_.initial_state();
  if (options_.hold_host) host_.v_m_s = 0.0;
  host_load_ = HostLoadBooks(host_model_.excitation_phase());

  refresh_neighbours();
  compute_forces(0.0);
  // Contacts present at the start (a settled bed) store elastic energy that belongs to
  // E(0); nothing has been dissipated yet.
  ledger_.dissipated_impact_J = ledger_.dissipated_friction_J = ledger_.dissipated_viscous_J = 0.0;
  ledger_.excitation_work_J = 0.0;
  impact_J_.assign(n, 0.0);
  friction_J_.assign(n, 0.0);
}

void SoftEngine::advance_to(double t_s) {
  // Velocity Verlet, with the second half-kick of each step and the first of the next
  // fused into one pass; between calls the velocities are at full steps.
  double owed_kick_s = 0.0;
  while (t_s_ < t_s) {
    throw_if_stop_requested();
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

void SoftEngine::check_state_finite() const {
  auto diverged = [&](const std::string& what) {
    std::ostringstream msg;
    msg << "the soft engine's state stopped being finite at t = " << t_s_ << " s (" << what
        << "): the integration diverged; its time step " << dt_s_ << " s is too long for the forces of this scenario";
    return RuntimeFailure(msg.str());
  };
  if (!std::isfinite(host_.z_m)) throw diverged("the host at " + std::to_string(host_.z_m) + " m");
  for (int i = 0; i < sphere_count(); ++i) {
    if (balls_.vector(i).allFinite()) continue;
    std::ostringstream where;
    where << "particle " << original_index_[i] << " at " << balls_.vector(i).transpose() << " m";
    throw diverged(where.str());
  }
}

void SoftEngine::check_particles_inside() const {
  check_state_finite();
  for (int i = 0; i < sphere_count(); ++i) {
    const Eigen::Vector3d x = balls_.vector(i);
    if (cavity_.clearance_m(x, balls_[i].radius, host_.z_m) < -balls_[i].radius) {
      std::ostringstream msg;
      msg << "particle " << original_index_[i] << " left the cavity at t = " << t_s_ << " s (position " << x.transpose()
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
  for (int i = 0; i < sphere_count(); ++i) {
    v_.set_vector(i, v_.vector(i) + force_[i] * (v_[i].inverse_inertia * dt_s));
    w_.set_vector(i, w_.vector(i) + torque_[i] * (w_[i].inverse_inertia * dt_s));
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
  DriftPass pass{*this, kick_s, dt_s};
  run_kernel(pass, chunk_count());
  needs_rebuild_ = pass.beyond_skin.load();
}

template <class Real>
bool SoftEngine::drift_chunk(int c, double kick_s, double dt_s) {
  // Kick and drift each sphere in one pass, and see whether any has moved more than half
  // the skin relative to the host (whose motion changes no pair distance) since the
  // neighbour list was built. Through local pointers: the stores might alias members.
  const int first = c * chunk_size, end = std::min(sphere_count(), first + chunk_size);
  const double host_shift = host_.z_m - host_z_at_rebuild_;
  const double limit_sq = 0.25 * neighbours_.skin_m() * neighbours_.skin_m();
  double* const balls = balls_.data();
  double *const velocities = v_.data(), *const spins = w_.data();
  const double *const fx = force_.x.data(), *const fy = force_.y.data(), *const fz = force_.z.data();
  const double *const tx = torque_.x.data(), *const ty = torque_.y.data(), *const tz = torque_.z.data();
  const double *const x0 = x_at_rebuild_.x.data(), *const y0 = x_at_rebuild_.y.data(),
                      *const z0 = x_at_rebuild_.z.data();
  bool beyond_skin = false;
  auto drift = [&]<class R>(int s) [[gnu::always_inline]] {
    const auto record = [&](double* records) { return [=](int l) { return records + 4 * std::ptrdiff_t{s + l}; }; };
    const Fields4<R> v = load_records<R>(record(velocities)), w = load_records<R>(record(spins));
    const R linear = v.d * kick_s, angular = w.d * kick_s;  // times 1/m, 1/I
    const R new_vx = v.a + load<R>(fx + s) * linear, new_vy = v.b + load<R>(fy + s) * linear,
            new_vz = v.c + load<R>(fz + s) * linear;
    store_records<R>({new_vx, new_vy, new_vz, v.d}, record(velocities));
    store_records<R>(
        {w.a + load<R>(tx + s) * angular, w.b + load<R>(ty + s) * angular, w.c + load<R>(tz + s) * angular, w.d},
        record(spins));
    const Fields4<R> ball = load_records<R>(record(balls));  // x, y, z, radius
    const R new_x = ball.a + new_vx * dt_s, new_y = ball.b + new_vy * dt_s, new_z = ball.c + new_vz * dt_s;
    store_records<R>({new_x, new_y, new_z, ball.d}, record(balls));
    const R dx = new_x - load<R>(x0 + s), dy = new_y - load<R>(y0 + s), dz = new_z - load<R>(z0 + s) - host_shift;
    const R moved_sq = dx * dx + dy * dy + dz * dz;
    // A position that is not a number asks for a rebuild too, which stops the run (check_state_finite).
    beyond_skin |= (lane_bits(moved_sq > limit_sq) | lane_bits(moved_sq != moved_sq)) != 0;
  };
  for_each_register<Real>(first, end, drift);
  return beyond_skin;
}

void SoftEngine::refresh_neighbours() {
  if (!needs_rebuild_) return;
  needs_rebuild_ = false;
  // The reactions of the last force computation are spent: their memory serves the rebuild
  // (which holds old and new contact tables at once) before the next force computation
  // takes it back.
  for (std::vector<Reaction>& chunk_reactions : reactions_) std::vector<Reaction>().swap(chunk_reactions);
  check_state_finite();  // the cells are found from the positions
  const std::vector<int>& order = neighbours_.sort_by_cell(balls_);
  set_aside_open_contacts(order);
  reorder_spheres(order);
  const int parts = runs_in_parallel() ? omp_get_max_threads() : 1;
  neighbours_.start_build(parts);
  BuildPass build{*this};
  run_kernel(build, parts);
  neighbours_.finish_build();
  hand_over_contacts(order);
  for (int i = 0; i < sphere_count(); ++i) x_at_rebuild_.set(i, balls_.vector(i));
  host_z_at_rebuild_ = host_.z_m;
  const int n = sphere_count();
  most_pairs_in_a_chunk_ = 0;
  farthest_partner_.assign(chunk_count(), -1);
  for (int c = 0; c < chunk_count(); ++c) {
    const int k_begin = neighbours_.first(c * chunk_size), k_end = neighbours_.first(std::min(n, (c + 1) * chunk_size));
    most_pairs_in_a_chunk_ = std::max(most_pairs_in_a_chunk_, k_end - k_begin);
    for (int k = k_begin; k < k_end; ++k) farthest_partner_[c] = std::max(farthest_partner_[c], neighbours_.partner(k));
  }
}

void SoftEngine::set_aside_open_contacts(const std::vector<int>& order) {
  const int n = sphere_count();
  std::vector<int> new_slot(n);  // not kept: its memory serves the rest of the rebuild
  for (int s = 0; s < n; ++s) new_slot[order[s]] = s;
  kept_first_.assign(n + 1, 0);
  kept_.clear();
  if (neighbours_.rebuilds() == 0) return;
  // A counting sort by new owner (the lower of the two new indices).
  auto for_each_open_pair = [&](const auto& f) {
    for (int i = 0; i < n; ++i) {
      for (int k = neighbours_.first(i); k < neighbours_.first(i + 1); ++k) {
        if (neighbours_.contact(k) == ContactTable::none) continue;
        f(i, k, new_slot[i], new_slot[neighbours_.partner(k)]);
      }
    }
  };
  for_each_open_pair([&](int, int, int a, int b) { ++kept_first_[std::min(a, b) + 1]; });
  for (int i = 0; i < n; ++i) kept_first_[i + 1] += kept_first_[i];
  kept_.resize(kept_first_[n]);
  kept_slot_.assign(kept_first_.begin(), kept_first_.end() - 1);  // fill cursors
  for_each_open_pair([&](int i, int k, int a, int b) {
    kept_[kept_slot_[std::min(a, b)]++] = {std::max(a, b), i / chunk_size, neighbours_.contact(k), a > b};
  });
}

void SoftEngine::reorder_spheres(const std::vector<int>& order) {
  // The forces are computed afresh after the renumbering.
  permute(balls_, order, visited_);
  permute(v_, order, visited_);
  permute(w_, order, visited_);
  permute(mass_, order, visited_);
  permute(impact_J_, order, visited_);
  permute(friction_J_, order, visited_);
  for (std::vector<int>* indices :
       {&original_index_, &wall_contacts_[side], &wall_contacts_[bottom], &wall_contacts_[top]}) {
    permute(*indices, order, visited_);
  }
}

void SoftEngine::hand_over_contacts(const std::vector<int>& order) {
  // Each chunk's table rebuilt in the order the force pass visits its contacts (pairs,
  // then walls), so that the pass runs through it front to back. An old table is freed as
  // soon as the new tables have taken what it holds, so that old and new tables together
  // take little more memory than one set.
  const int n = sphere_count(), chunks = chunk_count();
  auto wall_contact_count = [&](int i) {
    return (wall_contacts_[side][i] != ContactTable::none) + (wall_contacts_[bottom][i] != ContactTable::none) +
           (wall_contacts_[top][i] != ContactTable::none);
  };
  // The last new chunk that reads each old table, and the old tables in that order.
  last_reader_.assign(chunks, -1);
  for (int i = 0; i < n; ++i) {
    for (int s = kept_first_[i]; s < kept_first_[i + 1]; ++s) last_reader_[kept_[s].table] = i / chunk_size;
    if (wall_contact_count(i) > 0)
      last_reader_[order[i] / chunk_size] = std::max(last_reader_[order[i] / chunk_size], i / chunk_size);
  }
  release_order_.resize(chunks);
  std::iota(release_order_.begin(), release_order_.end(), 0);
  std::stable_sort(release_order_.begin(), release_order_.end(),
                   [&](int a, int b) { return last_reader_[a] < last_reader_[b]; });
  auto released = release_order_.begin();
  auto release_tables_read_last_by = [&](int c) {
    for (; released != release_order_.end() && last_reader_[*released] <= c; ++released)
      contact_tables_[*released].release();
  };
  release_tables_read_last_by(-1);

  kept_slot_.assign(n, -1);
  for (int c = 0; c < chunks; ++c) {
    ContactTable& table = next_contact_tables_[c];
    const int first = c * chunk_size, end = std::min(n, first + chunk_size);
    int entries = kept_first_[end] - kept_first_[first];
    for (int i = first; i < end; ++i) entries += wall_contact_count(i);
    table.clear(entries);
    for (int i = first; i < end; ++i) {
      for (int s = kept_first_[i]; s < kept_first_[i + 1]; ++s) kept_slot_[kept_[s].partner] = s;
      for (int k = neighbours_.first(i); k < neighbours_.first(i + 1); ++k) {
        const int s = kept_slot_[neighbours_.partner(k)];
        if (s < 0) continue;
        const KeptContact& kept = kept_[s];
        ContactHistory<> history = contact_tables_[kept.table][kept.entry];
        if (kept.flipped) {
          history.tangential_displacement_m = -history.tangential_displacement_m;
          history.tangential_force_N = -history.tangential_force_N;
        }
        neighbours_.contact(k) = table.append(history);
      }
      for (int s = kept_first_[i]; s < kept_first_[i + 1]; ++s) kept_slot_[kept_[s].partner] = -1;
    }
    for (std::vector<int>& at_wall : wall_contacts_) {
      for (int i = first; i < end; ++i) {
        int& contact = at_wall[i];
        if (contact != ContactTable::none) contact = table.append(contact_tables_[order[i] / chunk_size][contact]);
      }
    }
    release_tables_read_last_by(c);
  }
  contact_tables_.swap(next_contact_tables_);
}

void SoftEngine::compute_forces(double dt_s) {
  // Each chunk of spheres is handled by one thread: its own forces, its pairs (whose
  // reactions on partners are set aside) and its walls. The reactions are then added to
  // the partners, and the chunks' totals summed, in chunk order — so the result is the
  // same bits whatever the number of threads.
  scratch_.resize(std::max<std::size_t>(scratch_.size(), omp_get_max_threads()));
  for (PassScratch& scratch : scratch_) {
    const auto size = static_cast<std::size_t>(most_pairs_in_a_chunk_) + NeighbourList::padding;
    if (scratch.pairs.size() < size) scratch.pairs.resize(size);
  }
  ForcePass pass{*this, dt_s};
  run_kernel(pass, chunk_count());
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
  add_host_forces(dt_s);
}

template <class Real>
void SoftEngine::force_chunk(int c, double dt_s) {
  constexpr int lanes = lane_count<Real>;
  const int first = c * chunk_size, end = std::min(sphere_count(), first + chunk_size);
  ChunkWrenches on_chunk;
  start_forces<Real>(first, end, on_chunk);
  ChunkTotals totals;
  // The contacts to evaluate are sifted out first, without a branch, and evaluated a
  // register's worth at a time.
  PassScratch& scratch = scratch_[omp_get_thread_num()];
  const int pairs = list_pairs_to_evaluate<Real>(first, end, scratch.pairs.data());
  // Room for a reaction per pair evaluated; cut to those touching after.
  std::vector<Reaction>& reactions = reactions_[c];
  if (reactions.capacity() < static_cast<std::size_t>(pairs)) reactions.reserve(pairs + pairs / 8);
  reactions.resize(pairs);
  int reaction_count = 0;
  for (int p = 0; p < pairs; p += lanes) {
    add_pair_contacts<Real>(scratch.pairs.data() + p, std::min(lanes, pairs - p), dt_s, c, totals, on_chunk,
                            reactions.data(), reaction_count);
  }
  reactions.resize(reaction_count);
  const std::array<int, 3> at_walls = list_wall_contacts_to_evaluate<Real>(first, end, scratch.wall_spheres);
  auto add_contacts_with = [&]<int wall>(std::integral_constant<int, wall>) [[gnu::always_inline]] {
    const int* const spheres = scratch.wall_spheres[wall].data();
    for (int p = 0; p < at_walls[wall]; p += lanes) {
      add_wall_contacts<Real, wall>(spheres + p, std::min(lanes, at_walls[wall] - p), dt_s, c, totals, on_chunk);
    }
  };
  add_contacts_with(std::integral_constant<int, side>{});
  add_contacts_with(std::integral_constant<int, bottom>{});
  add_contacts_with(std::integral_constant<int, top>{});
  const int size = end - first;
  std::copy_n(on_chunk.fx, size, force_.x.data() + first);
  std::copy_n(on_chunk.fy, size, force_.y.data() + first);
  std::copy_n(on_chunk.fz, size, force_.z.data() + first);
  std::copy_n(on_chunk.tx, size, torque_.x.data() + first);
  std::copy_n(on_chunk.ty, size, torque_.y.data() + first);
  std::copy_n(on_chunk.tz, size, torque_.z.data() + first);
  for (int slot = 0; slot < size; ++slot) {
    impact_J_[first + slot] += on_chunk.impact_J[slot];
    friction_J_[first + slot] += on_chunk.friction_J[slot];
  }
  chunk_totals_[c] = totals;
}

template <class Real>
void SoftEngine::start_forces(int first, int end, ChunkWrenches& on_chunk) const {
  const double gx = scenario_.gravity_m_s2.x(), gy = scenario_.gravity_m_s2.y(), gz = scenario_.gravity_m_s2.z();
  const double drag = options_.settling_drag_1_s;
  const double* const mass = mass_.data();
  if (drag == 0.0) {  // a run, not settling
    for_each_register<Real>(first, end, [&]<class R>(int i) [[gnu::always_inline]] {
      const R m = load<R>(mass + i);
      const int slot = i - first;
      store(on_chunk.fx + slot, m * gx);
      store(on_chunk.fy + slot, m * gy);
      store(on_chunk.fz + slot, m * gz);
      store(on_chunk.tx + slot, R{});
      store(on_chunk.ty + slot, R{});
      store(on_chunk.tz + slot, R{});
      store(on_chunk.impact_J + slot, R{});
      store(on_chunk.friction_J + slot, R{});
    });
    return;
  }
  for (int i = first; i < end; ++i) {
    const int slot = i - first;
    const double spin_drag = -drag / w_[i].inverse_inertia;
    on_chunk.fx[slot] = mass[i] * (gx - drag * v_[i].x);
    on_chunk.fy[slot] = mass[i] * (gy - drag * v_[i].y);
    on_chunk.fz[slot] = mass[i] * (gz - drag * v_[i].z);
    on_chunk.tx[slot] = spin_drag * w_[i].x;
    on_chunk.ty[slot] = spin_drag * w_[i].y;
    on_chunk.tz[slot] = spin_drag * w_[i].z;
    on_chunk.impact_J[slot] = on_chunk.friction_J[slot] = 0.0;
  }
}

void SoftEngine::ChunkTotals::record_contact(double overlap_ratio) {
  ++contacts;
  max_overlap_ratio = std::max(max_overlap_ratio, overlap_ratio);
}

template <class Real>
int SoftEngine::list_pairs_to_evaluate(int first, int end, int* out) const {
  // One loop over the chunk's pairs, not one per sphere: a sphere's few pairs would make
  // the loop's exit a branch mispredicted once per sphere. The last lanes may read past
  // the chunk's pairs (the list is padded) and are not counted.
  constexpr int lanes = lane_count<Real>;
  const int *const pairs = neighbours_.pairs(), *const contact = neighbours_.contacts();
  const double* const balls = balls_.data();
  const int k_begin = neighbours_.first(first), k_end = neighbours_.first(end);
  int count = 0;
  for (int k = k_begin; k < k_end; k += lanes) {
    int i[lanes], j[lanes];
    unpack_pairs<Real>(pairs + k, first, i, j);
    const Fields4<Real> bi = gather_balls<Real>(balls, i), bj = gather_balls<Real>(balls, j);
    const Real dx = bi.a - bj.a, dy = bi.b - bj.b, dz = bi.c - bj.c;
    const Real reach = bi.d + bj.d;
    unsigned evaluate = lane_bits(dx * dx + dy * dy + dz * dz < reach * reach) | nonzero_bits<Real>(contact + k);
    if (k_end - k < lanes) evaluate &= (1u << (k_end - k)) - 1;
    append_lanes<Real>(k, evaluate, out, count);
  }
  pad_lanes<Real>(out, count);
  return count;
}

template <class Real>
std::array<int, 3> SoftEngine::list_wall_contacts_to_evaluate(int first, int end, WallLists& out) const {
  const double* const balls = balls_.data();
  const double bottom_z = host_.z_m, top_z = host_.z_m + cavity_.height_m();
  std::array<int, 3> count{};
  for_each_register<Real>(first, end, [&]<class R>(int s) [[gnu::always_inline]] {
    const Fields4<R> ball = load_records<R>([&](int l) { return balls + 4 * std::ptrdiff_t{s + l}; });
    const R xs = ball.a, ys = ball.b, zs = ball.c, r = ball.d;
    const R side_limit = cavity_.radius_m() - r;
    const unsigned touching[3] = {lane_bits(xs * xs + ys * ys > side_limit * side_limit), lane_bits(zs - bottom_z < r),
                                  lane_bits(top_z - zs < r)};
    for (int wall = side; wall <= top; ++wall) {
      append_lanes<R>(s, touching[wall] | nonzero_bits<R>(wall_contacts_[wall].data() + s), out[wall].data(),
                      count[wall]);
    }
  });
  for (int wall = side; wall <= top; ++wall) pad_lanes<Real>(out[wall].data(), count[wall]);
  return count;
}

template <class Real>
void SoftEngine::add_pair_contacts(const int* pairs, int count, double dt_s, int c, ChunkTotals& totals,
                                   ChunkWrenches& on_chunk, Reaction* reactions, int& reaction_count) {
  constexpr int lanes = lane_count<Real>;
  ContactTable& contacts = contact_tables_[c];
  const int first = c * chunk_size;
  int i[lanes], j[lanes], entry[lanes];
  for (int l = 0; l < lanes; ++l) {
    i[l] = neighbours_.owner(pairs[l], first);
    j[l] = neighbours_.partner(pairs[l]);
    entry[l] = neighbours_.contact(pairs[l]);
  }
  const Fields4<Real> bi = gather_balls<Real>(balls_.data(), i), bj = gather_balls<Real>(balls_.data(), j);
  const Vec3<Real> d{bi.a - bj.a, bi.b - bj.b, bi.c - bj.c};
  const Real ri = bi.d, rj = bj.d;
  const Real reach = ri + rj;
  const Real distance = sqrt_of(squared_norm(d));
  // The contact point splits the centre distance in the ratio of the radii, so the
  // lever arms add up to the distance and angular momentum is conserved exactly.
  const Real share = distance / reach, lever_i = ri * share, lever_j = rj * share;
  const Vec3<Real> normal = d * (1.0 / distance);
  const Vec3<Real> spin_part = lever_i * gather_vectors<Real>(w_, i) + lever_j * gather_vectors<Real>(w_, j);
  const ContactKinematics<Real> contact{
      normal, reach - distance, gather_vectors<Real>(v_, i) - gather_vectors<Real>(v_, j) - cross(spin_part, normal)};
  ContactHistory<Real> h = gather_histories<Real>(contacts, entry);
  const ContactForce<Real> f = evaluate_contact(scenario_.soft_particle, contact, dt_s, h);
  const Vec3<Real> twist = cross(normal, f.tangential_N);
  const Vec3<Real> torque_on_i = lever_i * twist, torque_on_j = -lever_j * twist;
  const unsigned touching = lane_bits(contact.overlap_m > 0.0);
  const Real overlap_ratio = contact.overlap_m / select(ri < rj, ri, rj);
  for_each_lane<Real>([&](auto l) [[gnu::always_inline]] {
    if (l >= count) return;
    const bool touches = (touching >> l) & 1;
    book_contact(f, torque_on_i, h, l, touches, lane(overlap_ratio, l), 0.5, neighbours_.contact(pairs[l]), contacts,
                 totals, on_chunk, i[l] - first);
    reactions[reaction_count++] = {-lane(f.force_N, l),
                                   lane(torque_on_j, l),
                                   0.5 * lane(f.dissipated_normal_J, l),
                                   0.5 * lane(f.dissipated_tangential_J, l),
                                   j[l],
                                   touches};
  });
}

template <class Real, int wall>
void SoftEngine::add_wall_contacts(const int* spheres, int count, double dt_s, int c, ChunkTotals& totals,
                                   ChunkWrenches& on_chunk) {
  constexpr int lanes = lane_count<Real>;
  ContactTable& contacts = contact_tables_[c];
  int i[lanes], entry[lanes];
  for (int l = 0; l < lanes; ++l) {
    i[l] = spheres[l];
    entry[l] = wall_contacts_[wall][i[l]];
  }
  const Fields4<Real> ball = gather_balls<Real>(balls_.data(), i);
  const Vec3<Real> x{ball.a, ball.b, ball.c};
  const Real r = ball.d;
  // The cavity's geometry (Cavity::gap), in lanes: the gap and the wall's inward normal.
  Vec3<Real> normal;
  Real gap;
  if constexpr (wall == side) {
    const Real rho = sqrt_of(x.x * x.x + x.y * x.y);
    // On the axis every direction is as good; a sphere there cannot touch the side anyway.
    const auto off_axis = rho > 0.0;
    normal = {select(off_axis, -x.x / rho, broadcast<Real>(-1.0)), select(off_axis, -x.y / rho, Real{}), Real{}};
    gap = cavity_.radius_m() - rho - r;
  } else if constexpr (wall == bottom) {
    normal = {Real{}, Real{}, broadcast<Real>(1.0)};
    gap = x.z - host_.z_m - r;
  } else {
    normal = {Real{}, Real{}, broadcast<Real>(-1.0)};
    gap = host_.z_m + cavity_.height_m() - x.z - r;
  }
  const Real lever = r + select(gap < 0.0, gap, Real{});  // the contact point is on the wall
  Vec3<Real> velocity = gather_vectors<Real>(v_, i) - lever * cross(gather_vectors<Real>(w_, i), normal);
  velocity.z = velocity.z - host_.v_m_s;  // relative to the wall
  const ContactKinematics<Real> contact{normal, -gap, velocity};
  ContactHistory<Real> h = gather_histories<Real>(contacts, entry);
  const ContactForce<Real> f = evaluate_contact(scenario_.soft_wall, contact, dt_s, h);
  const Vec3<Real> torque = lever * cross(normal, f.tangential_N);
  const unsigned touching = lane_bits(gap < 0.0);
  const Real overlap_ratio = -gap / r;
  const int first = c * chunk_size;
  // Booked in a loop, not unrolled per lane as for pairs: wall contacts are fewer, and
  // three unrolled copies would be much of the kernel's code.
  for (int l = 0; l < count; ++l) {
    book_contact(f, torque, h, l, (touching >> l) & 1, lane(overlap_ratio, l), 1.0, wall_contacts_[wall][i[l]],
                 contacts, totals, on_chunk, i[l] - first);
    totals.on_host_N -= lane(f.force_N.z, l);
  }
}

template <class Real>
ContactHistory<Real> SoftEngine::gather_histories(const ContactTable& contacts, const int* entry) {
  int offset[lane_count<Real>];
  for (int l = 0; l < lane_count<Real>; ++l) offset[l] = entry[l] * 7;  // an entry is seven doubles
  const double* const history = contacts.data();
  return {{gather<Real>(history + 0, offset), gather<Real>(history + 1, offset), gather<Real>(history + 2, offset)},
          {gather<Real>(history + 3, offset), gather<Real>(history + 4, offset), gather<Real>(history + 5, offset)},
          gather<Real>(history + 6, offset)};
}

template <class Real>
void SoftEngine::book_contact(const ContactForce<Real>& f, const Vec3<Real>& torque, const ContactHistory<Real>& h,
                              int l, bool touching, double overlap_ratio, double loss_share, int& open,
                              ContactTable& contacts, ChunkTotals& totals, ChunkWrenches& on_chunk, int slot) {
  const Vec3<double> force = lane(f.force_N, l), on_sphere = lane(torque, l);
  on_chunk.fx[slot] += force.x;
  on_chunk.fy[slot] += force.y;
  on_chunk.fz[slot] += force.z;
  on_chunk.tx[slot] -= on_sphere.x;
  on_chunk.ty[slot] -= on_sphere.y;
  on_chunk.tz[slot] -= on_sphere.z;
  const double impact_J = lane(f.dissipated_normal_J, l), friction_J = lane(f.dissipated_tangential_J, l);
  totals.impact_J += impact_J;
  totals.friction_J += friction_J;
  on_chunk.impact_J[slot] += loss_share * impact_J;
  on_chunk.friction_J[slot] += loss_share * friction_J;
  totals.elastic_J += lane(f.elastic_J, l);
  if (touching) {
    if (open == ContactTable::none) open = contacts.open();
    contacts[open] = {lane(h.tangential_displacement_m, l), lane(h.tangential_force_N, l),
                      lane(h.normal_damping_force_N, l)};
    totals.record_contact(overlap_ratio);
  } else if (open != ContactTable::none) {
    contacts.close(open);  // came apart: no reaction, and the spring has let go
    open = ContactTable::none;
  }
}

void SoftEngine::add_reactions() {
  // Each thread adds the reactions on a range of chunks, chunk by chunk in order: every
  // sphere takes its reactions in the same order on any number of threads. A chunk's
  // partners come after its own spheres and no further than its farthest partner.
  auto add_on = [&](int begin, int end) {
    for (int c = 0; c < chunk_count() && c * chunk_size < end; ++c) {
      if (farthest_partner_[c] < begin) continue;
      for (const Reaction& r : reactions_[c]) {
        if (r.partner < begin || r.partner >= end) continue;
        impact_J_[r.partner] += r.impact_J;
        friction_J_[r.partner] += r.friction_J;
        if (!r.touching) continue;
        force_.x[r.partner] += r.force_N.x;
        force_.y[r.partner] += r.force_N.y;
        force_.z[r.partner] += r.force_N.z;
        torque_.x[r.partner] += r.torque_N_m.x;
        torque_.y[r.partner] += r.torque_N_m.y;
        torque_.z[r.partner] += r.torque_N_m.z;
      }
    }
  };
  const int n = sphere_count();
  if (!runs_in_parallel()) {
    add_on(0, n);
    return;
  }
#pragma omp parallel
  {
    const int threads = omp_get_num_threads(), thread = omp_get_thread_num();
    add_on(chunk_count() * thread / threads * chunk_size,
           std::min(n, chunk_count() * (thread + 1) / threads * chunk_size));
  }
}

void SoftEngine::add_host_forces(double dt_s) {
  if (options_.hold_host) return;
  // The forces act at the end of the step; the books take the trapezoid of each over the
  // step's displacements. The damper acts on the velocity at the step's end, which the
  // coming half-kick gives: v = v_half + h (F(z, v) + F_p) / M, h = dt/2, linear in v, so
  // solved exactly. On the half-step velocity, as the contacts' dashpots, it would lag
  // by dt/2 and shift the host's response by C ω² dt / (2 |D|) (docs/soft-engine.md).
  const double y = host_model_.base_position_m(t_s_);
  const double h_s = 0.5 * dt_s, mass_kg = host_model_.mass_kg(), damping_N_s_m = host_model_.damping_N_s_m();
  const double without_damper_N = host_model_.force_N(t_s_, {host_.z_m, 0.0});
  const double v_end_m_s = host_model_.has_infinite_mass()
                               ? host_.v_m_s
                               : (host_.v_m_s + h_s * (without_damper_N + host_particle_force_N_) / mass_kg) /
                                     (1.0 + h_s * damping_N_s_m / mass_kg);
  host_other_force_N_ = host_model_.force_N(t_s_, {host_.z_m, v_end_m_s});
  const HostForces now{host_.z_m - y,
                       v_end_m_s - host_model_.base_velocity_m_s(t_s_),
                       host_model_.applied_force_N(t_s_),
                       host_particle_force_N_,
                       host_.z_m,
                       y,
                       host_model_.has_infinite_mass() ? 0.0 : host_other_force_N_,
                       host_load_.phase().at(t_s_)};
  const HostForces& before = previous_host_forces_;
  book_host_load(before, now, dt_s);
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

void SoftEngine::book_host_load(const HostForces& before, const HostForces& now, double dt_s) {
  // The kicks give the host ½ dt (F_before + F_now) over a step: the trapezoid, whose
  // weighted integrals take each end's weight (dt the kicks' own, not a difference of times).
  const double half_dt = 0.5 * dt_s;
  auto trapezoid = [&](double at_before, double at_now) { return half_dt * (at_before + at_now); };
  const ExcitationPhase::Weights &wb = before.weights, &wn = now.weights;
  host_load_.add({trapezoid(before.particles_N, now.particles_N),
                  trapezoid(before.particles_N * wb.sin, now.particles_N * wn.sin),
                  trapezoid(before.particles_N * wb.cos, now.particles_N * wn.cos), trapezoid(before.own_N, now.own_N),
                  trapezoid(before.z_m, now.z_m), trapezoid(before.z_m * wb.sin, now.z_m * wn.sin),
                  trapezoid(before.z_m * wb.cos, now.z_m * wn.cos)});
}

double SoftEngine::host_acceleration_m_s2() const {
  return (host_other_force_N_ + host_particle_force_N_) / host_model_.mass_kg();
}

ParticleEnergySums SoftEngine::particle_energies() const {
  ParticleEnergySums sums;
  for (int i = 0; i < sphere_count(); ++i) {
    sums.add(mass_[i], 1.0 / w_[i].inverse_inertia, balls_.vector(i), v_.vector(i), w_.vector(i),
             scenario_.gravity_m_s2);
  }
  return sums;
}

double SoftEngine::particle_kinetic_J() const {
  const ParticleEnergySums sums = particle_energies();
  return sums.translational_J() + sums.rotational_J();
}

Observation SoftEngine::observe() const {
  Observation o;
  o.t_s = t_s_;
  o.host = host_;
  o.energy = ledger_;
  particle_energies().write_to(o.energy);
  host_model_.write_energy_to(o.energy, t_s_, host_);
  o.energy.contact_elastic_J = contact_elastic_J_;
  o.host_load = host_load_.value();
  o.counters.time_steps = steps_;
  o.counters.contacts = contacts_;
  return o;
}

State SoftEngine::state() const {
  State s{observe(), Particles(static_cast<Eigen::Index>(sphere_count()))};
  for (int i = 0; i < sphere_count(); ++i) {
    const Eigen::Index k = original_index_[i];
    s.particles.position_m.col(k) = balls_.vector(i);
    s.particles.velocity_m_s.col(k) = v_.vector(i);
    s.particles.angular_velocity_rad_s.col(k) = w_.vector(i);
    s.particles.radius_m[k] = balls_[i].radius;
    s.particles.mass_kg[k] = mass_[i];
  }
  return s;
}

SphereDissipation SoftEngine::dissipation_by_sphere() const {
  SphereDissipation d{Eigen::VectorXd(sphere_count()), Eigen::VectorXd(sphere_count())};
  for (int i = 0; i < sphere_count(); ++i) {
    d.impact_J[original_index_[i]] = impact_J_[i];
    d.friction_J[original_index_[i]] = friction_J_[i];
  }
  return d;
}

EngineStatistics SoftEngine::statistics() const {
  return {{"steps", steps_},
          {"neighbour_rebuilds", neighbours_.rebuilds()},
          {"neighbour_pairs", neighbours_.size()},
          {"max_overlap_ppm_of_radius", std::llround(max_overlap_ratio_ * 1e6)},
          {"simd_lanes", simd_path_ == SimdPath::avx512 ? 8
                         : simd_path_ == SimdPath::avx2 ? 4
                                                        : 2},
          {"threads_used", runs_in_parallel() ? omp_get_max_threads() : 1}};
}

std::vector<std::string> SoftEngine::warnings() const {
  constexpr double overlap_warning_ratio = 0.02;
  if (max_overlap_ratio_ <= overlap_warning_ratio) return {};
  std::ostringstream msg;
  msg.precision(3);
  msg << "contacts overlapped up to " << 100.0 * max_overlap_ratio_
      << " % of a sphere radius (t = " << max_overlap_time_s_
      << " s): the contact law is soft for these impacts, so results depend on k_n there";
  return {msg.str()};
}

std::unique_ptr<Engine> make_soft_engine(const Scenario& scenario, const Particles& initial,
                                         SoftEngineOptions options) {
  return std::make_unique<SoftEngine>(scenario, initial, options);
}

}  // namespace pdamp::soft
