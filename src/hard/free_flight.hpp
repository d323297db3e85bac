#pragma once
/// Free flight: the part of the hard engine that needs no host. It holds the spheres (a
/// free one flies on an exact parabola from the time its record refers to and is moved
/// only when an event involves it; a riding one holds its host-frame position), the
/// lab-frame cells of the free ones and the event queue, and it predicts what a free
/// sphere meets without the host: other free spheres, the faces of its cell and the side
/// wall. Where the sphere could come within reach of the host's caps or bed it only
/// bounds, from the host's reach (a `host_check` event); the rest is HostCoupling's.

#include <array>
#include <cstdint>
#include <span>
#include <tuple>
#include <vector>

#include "hard/cell_members.hpp"
#include "hard/event_prediction.hpp"
#include "hard/event_queue.hpp"
#include "hard/neighbour_screen.hpp"
#include "hard/packed_particles.hpp"
#include "pdamp/model/cavity.hpp"
#include "pdamp/model/cell_grid.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp::hard {

/// What the events touch of each sphere besides its flight, kept together: one cache
/// line a sphere, not one per array.
struct SphereState {
  CellCoord cell{};                  ///< lab cell of a free sphere (unwrapped z)
  std::uint32_t host_stamp = 0;      ///< bumped whenever its host-dependent event is replaced
  double t_cross_s = never;          ///< when a free sphere next crosses a cell face
  double last_collision_s = -never;  ///< when it last collided
  std::uint8_t riding = 0;           ///< it rides with the host
};

/// The host as a free sphere's prediction sees it: how near the host's caps and bed can
/// come before the host-dependent predictions must take over.
struct HostReach {
  double z_m;                 ///< the host's position now
  double speed_envelope_m_s;  ///< no host trajectory until the next rebuild moves faster
  double bed_depth_m;         ///< riders never reach farther from their cap than this
};

class FreeFlight {
 public:
  enum Face : int { x_lower, x_upper, y_lower, y_upper, z_lower, z_upper };
  /// The 3 × 3 × 3 cells around a free sphere's cell (CellGrid::block), worked out at
  /// each prediction. Beyond the grid's sides an empty cell stands in, so that gathering
  /// the neighbours is a loop of fixed length and the layer entered at a face crossing is
  /// at fixed places.
  using Around = std::array<int, 27>;
  /// The 3 × 3 cells of Around beyond one face: those a face crossing brings in.
  using Layer = std::array<int, 9>;

  /// Room for `initial`'s spheres, in no cell yet (see start).
  FreeFlight(const Scenario& scenario, const Particles& initial);

  /// Takes over `spheres` (non-overlapping, all free, their records referring to time 0)
  /// and puts each into its cell.
  void start(const Particles& spheres);

  // The spheres.
  PackedParticles& particles() { return particles_; }
  const PackedParticles& particles() const { return particles_; }
  int size() const { return static_cast<int>(sphere_.size()); }
  SphereState& sphere(int i) { return sphere_[i]; }
  const SphereState& sphere(int i) const { return sphere_[i]; }
  const Eigen::Vector3d& gravity_m_s2() const { return gravity_m_s2_; }
  const Cavity& cavity() const { return cavity_; }
  Ballistic flight(int i) const {
    return {particles_.position_m.col(i), particles_.velocity_m_s.col(i), particles_.t_ref_s[i]};
  }
  /// Moves free sphere i's record to t_s (inlined into the collisions, as the cells
  /// around a sphere below: each costs the gas instructions as a call).
  [[gnu::always_inline]] void bring_to_now(int i, double t_s) {
    const Ballistic f = flight(i);
    particles_.position_m.col(i) = f.position_at(t_s, gravity_m_s2_);
    particles_.velocity_m_s.col(i) = f.velocity_at(t_s, gravity_m_s2_);
    particles_.t_ref_s[i] = t_s;
  }
  /// Sphere i's trajectory changed: every event predicted for it is out of date.
  void new_trajectory(int i) {
    ++trajectory_counter_[i];
    queue_.forget(i);
  }
  /// Whatever host-dependent event sphere i had is replaced: returns its new host stamp.
  std::uint32_t replace_host_events(int i) {
    queue_.host_stamp_changed(i);
    return ++sphere_[i].host_stamp;
  }
  /// Root finders stop this close to contact (m).
  double contact_tolerance_m() const { return contact_tolerance_m_; }
  double max_radius_m() const { return max_radius_m_; }

  // The cells of the free spheres.
  const CellGrid& grid() const { return grid_; }
  /// Puts free sphere i into cell c (it must be in none).
  void enter_cell(int i, const CellCoord& c) {
    sphere_[i].cell = c;
    free_cells_.insert(i, grid_.index(c));
  }
  void leave_cell(int i) { free_cells_.remove(i); }
  template <class Visit>
  void for_each_free_in(int cell, Visit visit) const {
    free_cells_.for_each_in(cell, visit);
  }
  /// The cells around free sphere i's, with the empty stand-in beyond the grid's sides.
  [[gnu::always_inline]] Around around(int i) const {
    Around cells;
    grid_.block(sphere_[i].cell, grid_.cell_count(), cells);
    return cells;
  }
  /// Asks for the cache lines of `cells` where the cells outgrow half the L2 cache
  /// (below that the prefetch only costs instructions). Always inlined: GCC splits the
  /// loop off into a function of its own, finds it without effect (a prefetch changes no
  /// memory) and drops the call.
  [[gnu::always_inline]] void prefetch_cells(const Around& cells) const {
    if (prefetch_cells_) free_cells_.prefetch(cells);
  }
  /// Moves free sphere i into the cell beyond `face`: returns the cells it has newly
  /// around it (its contacts with the spheres in the others were predicted with the
  /// same trajectory).
  Layer cross_face(int i, Face face);

  // Events.
  EventQueue& queue() { return queue_; }
  void push(const Event& event) { queue_.push(event); }
  /// Whether an event is still what would be predicted now (the host's events carry
  /// `host_epoch`'s value when predicted; by reference, as it is read only for those).
  [[gnu::always_inline]] bool is_current(const Event& event, const std::uint32_t& host_epoch) const;
  /// Predicts free sphere i's events without the host anew at t_s (after replacing its
  /// host-dependent event): its next face crossing, its contacts with the free spheres in
  /// `new_cells` (an Around, or the Layer a face crossing entered: its other neighbours'
  /// contacts are known), the side wall, and a `host_check` at the earliest time it
  /// could come within reach of a cap or the bed if the host moved as fast as `host`'s
  /// envelope allows (if before the crossing). True if it may be within reach now: then
  /// its host-dependent event is HostCoupling's to predict. Inline, and always: the
  /// engine's prediction of a sphere (this, then the host's part) then compiles as one
  /// function; as a call of its own it costs the gas instructions (tools/bench/HISTORY.md).
  [[gnu::always_inline]] bool predict(int i, std::span<const int> new_cells, double t_s, HostReach host);
  /// Whether the engine asks for neighbours' records and cells ahead of use: where they
  /// outgrow half the L2 cache.
  bool prefetching() const { return prefetch_records_ && prefetch_cells_; }

  /// Its state verbatim (hard_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  Eigen::Vector3d gravity_m_s2_;
  Cavity cavity_;
  PackedParticles particles_;
  std::vector<SphereState> sphere_;
  /// Bumped whenever a sphere's trajectory changes. Apart from SphereState: every contact
  /// a prediction enters reads its partner's, and every sphere–sphere event that reaches
  /// the queue's top or a re-key; 4 bytes a sphere stay in cache where a SphereState would not.
  std::vector<std::uint32_t> trajectory_counter_;
  CellGrid grid_;           ///< lab frame, for free spheres; the host frame uses the same geometry
  CellMembers free_cells_;  ///< free spheres by lab cell
  EventQueue queue_;
  std::vector<int> neighbours_;  ///< predict's scratch: the free spheres around the one predicted
  ScreenResult screen_result_;   ///< predict's scratch: the contact tests of those neighbours
  double contact_tolerance_m_;
  double max_radius_m_;
  /// Whether predict asks for all the neighbours' records at once before screening them:
  /// only where the records outgrow half the L2 cache (where they are in cache, the
  /// requests only cost instructions). After predict's members: among them it shifts
  /// their layout and slows the gas (tools/bench/HISTORY.md).
  bool prefetch_records_ = false;
  /// Whether a sphere–sphere collision asks for the cells around both spheres before it
  /// predicts them: likewise only where the cells outgrow half the L2 cache.
  bool prefetch_cells_ = false;
  /// The neighbour screen of the process's SimdPath; after predict's members, as above.
  NeighbourScreen screen_ = neighbour_screen(simd::default_simd_path());
};

inline bool FreeFlight::is_current(const Event& e, const std::uint32_t& host_epoch) const {
  if (e.kind == EventKind::bed_release) return host_epoch == e.count_j;
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

inline bool FreeFlight::predict(int i, std::span<const int> new_cells, double t, HostReach host) {
  // Whatever host-dependent event i had is replaced; before anything is entered, which
  // keeps a list refilled after a trajectory change fresh (EventQueue::host_stamp_changed).
  replace_host_events(i);
  const Ballistic f = flight(i);
  const Eigen::Vector3d x = f.position_at(t, gravity_m_s2_), v = f.velocity_at(t, gravity_m_s2_);
  const double r = particles_.radius_m[i];
  const CellCoord c = sphere_[i].cell;
  const Eigen::Vector3d& g = gravity_m_s2_;

  // The next face crossing bounds the predictions of walls and host: the sphere is
  // predicted anew there. Lanes pair the faces in x and y, and the face in z with a
  // guard on the host (see below); a cell at the grid's side has no face there.
  const double envelope = host.speed_envelope_m_s;
  const FaceTimes xy = time_to_faces(Lanes2{x.x() - grid_.x_lower_m(c.ix), x.y() - grid_.x_lower_m(c.iy)},
                                     Lanes2{grid_.x_lower_m(c.ix + 1) - x.x(), grid_.x_lower_m(c.iy + 1) - x.y()},
                                     Lanes2{v.x(), v.y()}, Lanes2{g.x(), g.y()});
  const double above_bed = x.z() - r - host.z_m - host.bed_depth_m;
  const double below_top_bed = host.z_m + cavity_.height_m() - host.bed_depth_m - x.z() - r;
  const Lanes2 to_lower_z = time_to_plane(Lanes2{x.z() - grid_.z_lower_m(c.iz), above_bed},
                                          Lanes2{v.z(), v.z() - envelope}, Lanes2{g.z(), g.z()});
  const Lanes2 to_upper_z = time_to_plane(Lanes2{grid_.z_lower_m(c.iz + 1) - x.z(), below_top_bed},
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
  screen_({x, v, r, t, i}, g, &particles_.record(0), candidates, candidate_count, screen_result_);
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

  // Caps and the resting bed: when the sphere could reach the bed's farthest extent if
  // the host moved at the envelope's speed.
  // A sphere already inside the bed's reach is within reach now, even receding from its
  // plane faster than the envelope (time_to_plane would answer when it comes back, or never).
  const double guard = t + std::min(to_lower_z[1], to_upper_z[1]);
  if (std::min(guard - t, std::min(above_bed, below_top_bed)) <= 0.0) return true;
  if (guard < horizon) push({guard, i, 0, 0, EventKind::host_check});
  return false;
}

}  // namespace pdamp::hard
