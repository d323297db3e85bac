#pragma once
/// The event-driven hard-sphere engine (docs/hard-engine.md).
///
/// Spheres fly on exact parabolas and are advanced lazily: each keeps the time its
/// position and velocity refer to, and only the spheres an event involves are moved.
/// The host follows its closed-form HostTrajectory, restarted after every impulse it
/// takes. One step of `advance_to` pops the earliest event, drops it if stale, and
/// handles it; handling a collision applies Walton's impulse, books the losses and
/// predicts the involved spheres' next events.
///
/// Host-dependent predictions (caps, riding spheres) go out of date whenever the host's
/// motion changes; tiers keep that from costing O(N) per host impulse:
/// - far: a `host_check` at the earliest time the sphere could reach a cap or the bed
///   if the host moved as fast as `host_speed_envelope_` allows; valid across impulses.
/// - near (its check has fired) and, within it, imminent and close: a `host_margin` event when
///   the sphere comes within the tier's margin of a cap or rider on the current host
///   trajectory, or at the end of the tier's horizon τ. That is a lower bound on the
///   contact time as long as the host deviates from the trajectory it was computed with
///   by less than the margin, and only for a sphere outside the margin: one within it,
///   closing or receding, belongs to the next tier. Each impulse adds |Δv| τ + ½ Δa τ² to
///   the tier's deviation budget, and only when the budget reaches the margin are the
///   tier's spheres predicted anew (a sweep). τ adapts so that sweeps come about once
///   per τ, which minimises the sum of the two costs.
/// - touching (within the inner margin, closing or not): exact contact predictions, redone
///   at every impulse.
///
/// Resting: a sphere that leaves the floor, the top cap or a riding sphere slower than
/// hard.rest_speed_m_s while the host's acceleration presses it there stops and rides
/// with the host as added mass (no events at all) until the host's acceleration stops
/// pressing (the whole bed is released) or a sphere hits it faster than that speed.
///
/// Jams: spheres that keep colliding at one instant (inelastic collapse, or friction in a
/// wedge) merge into a rigid body, which also sticks to the host if a wall or the bed
/// holds it (merge_jam).

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "pdamp/hard/cell_members.hpp"
#include "pdamp/hard/collision_rules.hpp"
#include "pdamp/hard/event_prediction.hpp"
#include "pdamp/hard/event_queue.hpp"
#include "pdamp/hard/neighbour_screen.hpp"
#include "pdamp/hard/packed_particles.hpp"
#include "pdamp/hard/particle_set.hpp"
#include "pdamp/model/cavity.hpp"
#include "pdamp/model/cell_grid.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/model/restitution.hpp"

namespace pdamp::hard {

class HardEngine final : public Engine {
 public:
  /// Overlapping initial spheres (a bed settled with soft contacts) are pushed just apart
  /// first (separate_overlaps); a separation above 5 % of a radius is reported in warnings(). With a
  /// `calibration`, e_n and β0 follow the soft law's e_n(v), β0(v) at each impact speed
  /// (hard.restitution = calibrated); otherwise they are the scenario's constants.
  HardEngine(const Scenario& scenario, const Particles& initial, const RestitutionTable* calibration = nullptr);

  void advance_to(double t_s) override;
  Observation observe() const override;
  State state() const override;
  SphereDissipation dissipation_by_sphere() const override { return by_sphere_; }
  double time_step_s() const override { return 0.0; }
  EngineStatistics statistics() const override;
  std::vector<std::string> warnings() const override;

  /// The deepest overlap now between two spheres or a sphere and a wall (m, 0 if none).
  double max_overlap_m() const;
  /// Overlaps never exceed this (m): the contact tolerance of the root finders plus round-off.
  double overlap_tolerance_m() const { return 10.0 * contact_tolerance_m_; }
  int riding_count() const { return riding_count_; }
  /// Whether the engine asks for neighbours' records and cells ahead of use: where they
  /// outgrow half the L2 cache (see prefetch_records_ and prefetch_cells_).
  bool prefetching() const { return prefetch_records_ && prefetch_cells_; }
  /// Collisions processed so far (all kinds).
  std::int64_t collisions() const;

 private:
  enum Face : int { x_lower, x_upper, y_lower, y_upper, z_lower, z_upper };

  Ballistic flight(int i) const {
    return {particles_.position_m.col(i), particles_.velocity_m_s.col(i), particles_.t_ref_s[i]};
  }
  /// Lab-frame position of any sphere now (free or riding).
  Eigen::Vector3d position_now(int i, const HostState& host) const;
  void bring_to_now(int i);
  /// host_.at(t_s_), which every prediction needs: the two of a collision share it.
  HostState host_now() const;
  /// Sphere i's trajectory changed: every event predicted for it is out of date.
  void new_trajectory(int i) {
    ++trajectory_counter_[i];
    queue_.forget(i);
  }
  double host_inverse_mass_1_kg() const;
  /// The law of a collision of i with j (−1 for a wall or rider) at this approach speed:
  /// calibrated e_n and β0 if any, and e_n = 1 for slow first collisions (see
  /// HardRestingSettings). Records the collision's time.
  HardContactLaw law_for(double approach_speed_m_s, bool wall, int i, int j);

  /// Throws Interrupted on a stop request and RuntimeFailure past run.max_events.
  [[gnu::cold, gnu::noinline]] void poll();

  // Prediction.
  void push(const Event& event) { queue_.push(event); }
  /// Whatever host-dependent event sphere i had is replaced: returns its new host stamp.
  std::uint32_t replace_host_events(int i) {
    queue_.host_stamp_changed(i);
    return ++sphere_[i].host_stamp;
  }
  /// Predicts every event of free sphere i anew (its trajectory changed).
  void predict(int i) {
    Around around;
    grid_.block(sphere_[i].cell, grid_.cell_count(), around);  // the empty stand-in beyond the sides
    predict(i, around);
  }
  /// Predicts sphere i's events anew, but its contacts only with the spheres in
  /// `new_cells` (it has just crossed into a cell whose other neighbours it already had):
  /// an Around or a Layer.
  void predict(int i, std::span<const int> new_cells);
  /// Predicts free sphere i's host-dependent event, starting the descent through the
  /// tiers at `first_level` (a tier it is in: the levels above it are known to hold it).
  void predict_host_relative(int i, std::size_t first_level = 0);
  void predict_bed_release();
  void sweep_tier(std::size_t level);
  void repredict_near_around(const Eigen::Vector3d& lab_position);
  void leave_host_sets(int i);
  void rebuild_predictions();
  struct HostContact {
    Approach when;
    EventKind kind;
    int partner;
  };
  /// Calls visit(j) for each rider j in the cells that cover the host-frame box centre ± half.
  template <class Visit>
  void for_each_rider_in(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& half_m, Visit visit) const;
  /// Whether free sphere i, grown by `margin_m`, touches a cap or rider now: what
  /// host_contact(i, end_s, margin_m) answers at its first step, without its root finders.
  bool within_host_margin(int i, double end_s, double margin_m) const;
  /// The first contact of free sphere i, grown by `margin_m`, with a cap or rider, from
  /// now until `end_s` (or the end of the riders' window). `riders_searched`, if given,
  /// receives the riders it looked at: all those in a host-frame box around the path
  /// (with margin 0 it reaches touching_slack_m_ farther in z than the path needs).
  HostContact host_contact(int i, double end_s, double margin_m, std::vector<int>* riders_searched = nullptr) const;
  [[gnu::always_inline]] bool is_current(const Event& event) const;  // in every re-key and pop

  // Events.
  void handle(const Event& event);
  void collide_spheres(int i, int j);
  /// What a sphere collided with at this instant, besides free spheres.
  enum Hold : std::uint8_t { held_by_side_wall = 1, held_by_cap_or_bed = 2 };
  /// Records a collision of free sphere i at this instant with free sphere j, or with the
  /// host (j < 0; `hold` says which part); true once i or j has collided more than
  /// jam_repeats times at it (wedged in a jammed cluster).
  bool note_collision(int i, int j, std::uint8_t hold = 0);
  /// note_collision's record of one collision in the spheres' counts, partners and holds.
  bool record_collision(int i, int j, std::uint8_t hold);
  /// The jammed cluster of i (free spheres linked by collisions at this instant) stops
  /// all relative motion: a perfectly inelastic, sticking merge into a rigid body, which
  /// also sticks to the host if a wall or the bed holds any of its spheres.
  void merge_jam(int i);
  /// merge_jam's rigid merge of `members` (flagged in in_jam_).
  void merge_rigidly(const std::vector<int>& members);
  /// merge_jam's perfectly inelastic, sticking collision of the rigid `members` with the host.
  void stick_to_host(const std::vector<int>& members, std::uint8_t hold);
  void collide_wall(int i, EventKind wall);
  void collide_rider(int i, int j);
  void turn_along_side_wall(int i, const Eigen::Vector3d& outward);
  void cross_face(int i, Face face);
  /// Puts free sphere i into cell c (it must be in none).
  void enter_cell(int i, const CellCoord& c);
  void release_bed();

  // The host and the bed.
  /// A sphere-host collision outcome applied to sphere i (arm r n) and the host; its loss
  /// is shared with `rider` if a riding sphere took the impulse for the host.
  void apply_host_impulse(int i, const Eigen::Vector3d& normal, const CollisionOutcome& outcome, const HostState& host,
                          int rider = -1);
  void restart_host(HostState start);
  void book_host(double t_s);
  double rider_energy_J(const HostState& host) const;
  bool presses(double normal_z_from_support) const;
  void rest_if_slow(int i, const Eigen::Vector3d& normal_from_support, const HostState& host);
  void attach(int i);
  void detach(int i, const HostState& host);

  // Settings.
  Eigen::Vector3d gravity_m_s2_;
  HardContactLaw sphere_law_, wall_law_;
  HardRestingSettings resting_;
  std::optional<RestitutionTable> calibration_;
  Cavity cavity_;
  HostModel host_model_;
  double fastest_host_rate_1_s_;

  // Spheres: free ones hold lab position and velocity at t_ref; riding ones hold their
  // host-frame position (lab position minus z_host e_z).
  PackedParticles particles_;
  /// What the events touch of each sphere besides its flight, kept together: one cache
  /// line a sphere, not one per array.
  struct SphereState {
    CellCoord cell{};                  ///< lab cell of a free sphere (unwrapped z)
    std::uint32_t host_stamp = 0;      ///< bumped whenever its host-dependent event is replaced
    double t_cross_s = never;          ///< when a free sphere next crosses a cell face
    double last_collision_s = -never;  ///< when it last collided
    std::uint8_t riding = 0;           ///< it rides with the host
  };
  std::vector<SphereState> sphere_;
  /// Bumped whenever a sphere's trajectory changes. Apart from SphereState: every contact
  /// a prediction enters reads its partner's, and every sphere–sphere event that reaches
  /// the queue's top or a re-key; 4 bytes a sphere stay in cache where a SphereState would not.
  std::vector<std::uint32_t> trajectory_counter_;
  /// The 3 × 3 × 3 cells around a free sphere's cell (CellGrid::block), worked out at
  /// each prediction. Beyond the grid's sides an empty cell stands in, so that gathering
  /// the neighbours is a loop of fixed length and the layer entered at a face crossing is
  /// at fixed places.
  using Around = std::array<int, 27>;
  /// The 3 × 3 cells of Around beyond one face: those a face crossing brings in.
  using Layer = std::array<int, 9>;
  /// The collisions of free spheres at the instant t_s: per sphere how many, with which
  /// free spheres, and which parts of the host (Hold bits).
  struct Jam {
    double t_s = -1.0;
    std::vector<int> count;
    std::vector<std::vector<int>> partners;
    std::vector<std::uint8_t> hold;
    std::vector<int> involved;  ///< spheres with a count, to reset them when time moves on
    /// The instant's first collision, until a second one enters it in the records.
    struct {
      int i = 0, j = 0;
      std::uint8_t hold = 0;
      bool pending = false;
    } first;
  } jam_;
  std::vector<std::uint8_t> in_jam_;  ///< scratch for merge_jam
  /// Spheres whose host-dependent events are lower bounds, valid while the host strays
  /// less than `margin_m` from the trajectory they were computed with.
  struct MarginTier {
    ParticleSet members;
    double margin_m;
    double horizon_s;       ///< τ: how far ahead its predictions look
    double budget_m = 0.0;  ///< how far the host may have strayed since the last sweep
    double t_last_sweep_s = 0.0;
    std::int64_t sweeps = 0, repredictions = 0;
  };
  /// Near spheres (host_check fired; margin 0.1 r), within those the imminent ones (within
  /// 0.1 r; margin 0.002 r), within those the close ones (within 0.002 r; margin 4e-5 r).
  std::array<MarginTier, 3> tiers_;
  /// Tier `level` for `initial`'s spheres (needs fastest_host_rate_1_s_).
  MarginTier tier(std::size_t level, const Particles& initial) const;
  ParticleSet touching_;  ///< within the inner margin: exact predictions, redone at every impulse (or deferred)
  /// What a touching sphere's exact host prediction assumed, so that a host impulse that
  /// only moves the host's walls and bed away from it can leave the prediction standing
  /// as a lower bound (defer_touching) instead of redoing it.
  struct TouchingBound {
    double event_s = never;  ///< its host-dependent event (or its next face crossing)
    /// Its centre's host-frame heights until then, on the trajectory it was predicted with.
    double lowest_m = 0.0, highest_m = 0.0;
    /// Lower bounds until then on its gaps to the riders searched whose centres lie above
    /// its lowest height, and to those below its highest.
    double gap_above_m = never, gap_below_m = never;
    double deviation_m = 0.0;  ///< how far the host may have strayed since, all one way
    int direction = 0;         ///< that way: +1 up, −1 down, 0 not at all
  };
  std::vector<TouchingBound> touching_bound_;
  /// How much farther in z than its path needs a touching sphere's riders are searched:
  /// riders beyond the box stay out of reach of a host that strays less than this.
  double touching_slack_m_;
  /// After a host impulse that changed the host's velocity by `velocity_change_m_s` and not
  /// its riding mass: whether touching sphere i's prediction still stands (see TouchingBound).
  bool defer_touching(int i, double velocity_change_m_s);

  CellGrid grid_;            ///< lab frame, for free spheres; the host frame uses the same geometry
  CellMembers free_cells_;   ///< free spheres by lab cell
  CellMembers rider_cells_;  ///< riding spheres by host-frame cell
  EventQueue queue_;
  std::vector<int> neighbours_;       ///< predict's scratch: the free spheres around the one predicted
  ScreenResult screen_result_;        ///< predict's scratch: the contact tests of those neighbours
  std::vector<int> riders_searched_;  ///< predict_host_relative's scratch: the riders its exact search saw
  double contact_tolerance_m_;
  double max_radius_m_;
  double separation_m_ = 0.0;  ///< how far the initial spheres were moved apart
  std::int64_t events_at_this_instant_ = 0;
  std::int64_t stall_limit_;

  // Host.
  HostTrajectory host_;
  std::uint32_t host_epoch_ = 0;  ///< bumped whenever host_ is replaced
  struct HostNow {
    double t_s;
    std::uint32_t epoch;
    HostState state;
  };
  mutable HostNow host_now_{-never, 0, {}};  ///< host_now()'s last answer
  double host_speed_envelope_m_s_ = 0.0;     ///< ≥ the speed bound of every trajectory since the last rebuild
  double trajectory_riding_mass_kg_ = 0.0;   ///< the riding mass host_ was built with
  double t_s_ = 0.0;
  double t_host_booked_s_ = 0.0;
  double riding_mass_kg_ = 0.0;
  int riding_count_ = 0;
  int bed_side_ = 0;              ///< +1 riders rest on the bottom cap, −1 on the top cap
  double bed_depth_bound_m_ = 0;  ///< riders never reach farther from their cap than this

  // Ledger (J).
  double impact_J_ = 0.0, friction_J_ = 0.0, viscous_J_ = 0.0, excitation_J_ = 0.0;
  /// The impact and friction losses by sphere (dissipation_by_sphere).
  SphereDissipation by_sphere_;
  /// Adds a loss (J) to sphere i's share (the ledger's totals are booked apart).
  void book_sphere_loss(int i, double impact_J, double friction_J) {
    by_sphere_.impact_J[i] += impact_J;
    by_sphere_.friction_J[i] += friction_J;
  }

  struct Statistics {
    std::int64_t sphere_sphere = 0, side_wall = 0, cap = 0, rider = 0, cell_crossing = 0, host_check = 0,
                 host_margin = 0, stale = 0, rests = 0, knocked_off = 0, bed_releases = 0, jammed = 0,
                 host_impulses = 0, jam_merges = 0, jam_merged_spheres = 0, jam_stuck_to_host = 0,
                 touching_repredictions = 0, touching_deferrals = 0, rebuilds = 0;
  } stats_;
  /// Whether predict asks for all the neighbours' records at once before screening them:
  /// only where the records outgrow the L2 cache (below that the prefetches only cost
  /// instructions). After predict's members: among them it shifts their layout and slows
  /// the gas (tools/bench/HISTORY.md).
  bool prefetch_records_ = false;
  /// Whether a sphere–sphere collision asks for the cells around both spheres before
  /// it predicts them: only where the cells outgrow the L2 cache, as for the records.
  bool prefetch_cells_ = false;
  // Likewise after predict's members (see prefetch_records_).
  /// Events popped so far, all kinds; every poll_interval of them poll() looks at the
  /// stop request and run.max_events.
  static constexpr std::int64_t poll_interval = 4096;
  std::int64_t events_ = 0;
  std::int64_t max_events_;
  std::int64_t next_poll_;
};

}  // namespace pdamp::hard
