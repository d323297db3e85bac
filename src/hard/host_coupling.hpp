#pragma once
/// Host coupling: the host's motion, and all of the spheres that depends on it — the free
/// spheres' predictions of their contacts with the caps and the riding spheres, the
/// riding spheres themselves (the resting bed), and when the bed is released.
///
/// The host follows its closed-form HostTrajectory, restarted after every impulse it
/// takes (`restart`); the books get the damper's and the excitation's share of each
/// stretch (HardLedger::book_host).
///
/// Host-dependent predictions go out of date whenever the host's motion changes; tiers
/// keep that from costing O(N) per host impulse:
/// - far: a `host_check` at the earliest time the sphere could reach a cap or the bed
///   if the host moved as fast as the speed envelope allows (FreeFlight::predict enters
///   it); valid across impulses.
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
///   at every impulse unless the impulse only moves the walls and the bed away from them
///   (TouchingBound).
///
/// Resting: a sphere that leaves the floor, the top cap or a riding sphere slower than
/// the rest speed (hard.rest_speed_m_s, at least hard.elastic_speed_m_s; with
/// hard.rest_tc_window, also slower than it would have to be to land again within that
/// many soft contact times) while the host's acceleration presses it there stops and
/// rides with the host as added mass (no events at all; `attach`) until the host's
/// acceleration stops pressing (the whole bed is released: a `bed_release` event) or a
/// sphere hits it faster than that speed (`detach`).

#include <array>
#include <cstdint>
#include <vector>

#include "hard/cell_members.hpp"
#include "hard/event_prediction.hpp"
#include "hard/free_flight.hpp"
#include "hard/hard_ledger.hpp"
#include "hard/particle_set.hpp"
#include "pdamp/model/cavity.hpp"
#include "pdamp/model/host.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp::hard {

class HostCoupling {
 public:
  /// The host at rest in its initial state, `initial`'s spheres all free; predictions
  /// are entered in `flight`'s queue, the host's work and damping booked in `ledger`.
  HostCoupling(const Scenario& scenario, const Particles& initial, FreeFlight& flight, HardLedger& ledger);
  // Its trajectory refers to its own model.
  HostCoupling(const HostCoupling&) = delete;
  HostCoupling& operator=(const HostCoupling&) = delete;

  // The host's motion.
  const HostModel& model() const { return model_; }
  bool prescribed() const { return model_.has_infinite_mass(); }
  const HostTrajectory& trajectory() const { return trajectory_; }
  /// Bumped whenever the trajectory is replaced or every prediction forgotten.
  const std::uint32_t& epoch() const { return epoch_; }
  /// trajectory().at(t_s), which every prediction needs: the two of a collision share it.
  HostState now(double t_s) const {
    // A host that cannot move (speed bound 0: fixed walls) is where it was: its trig need
    // not be evaluated at every instant.
    const bool moved = now_.t_s != t_s && (trajectory_.speed_bound_m_s() > 0.0 || now_.t_s == -never);
    const bool stale = now_.epoch != epoch_ || moved;
    if (stale) now_ = {t_s, epoch_, trajectory_.at(t_s)};
    return now_.state;
  }
  /// How near the host can come, for FreeFlight::predict's host_check.
  HostReach reach(double t_s) const { return {now(t_s).z_m, speed_envelope_m_s_, bed_depth_bound_m_}; }
  /// The mass the host's velocity stands for besides a sphere's: its own and the riders'.
  double carried_mass_kg() const { return model_.mass_kg() + riding_mass_kg_; }
  double inverse_mass_1_kg() const { return prescribed() ? 0.0 : 1.0 / carried_mass_kg(); }
  /// The host and its riders take a vertical impulse from a sphere or a cluster at t_s
  /// (N·s): the host's own share, the rest moving the riders with it (all of it for a
  /// prescribed host, which carries the riders whatever they weigh), into the load books.
  /// Call it before the host restarts and before the riding mass changes.
  void take_impulse(double on_carried_N_s, double t_s) {
    if (on_carried_N_s == 0.0) return;
    ledger_.load.add_impulse(prescribed() ? on_carried_N_s : on_carried_N_s * model_.mass_kg() / carried_mass_kg(),
                             t_s);
  }
  /// Books the trajectory from the last booking to t_s (with the riding mass it had).
  void book(double t_s) { ledger_.book_host(trajectory_, t_s, riders()); }
  Riders riders() const { return {riding_mass_kg_, gravity_m_s2_.z(), prescribed()}; }
  /// The host moves on from `start` at t_s (after an impulse, or with another riding
  /// mass): the trajectory that ends is booked, and the host-dependent predictions that
  /// the change made out of date are made anew. False if the new trajectory may move
  /// faster than the speed envelope the far spheres' guards assumed: then the envelope
  /// is widened, and every prediction must be redone (forget_predictions).
  [[nodiscard]] bool restart(HostState start, double t_s);

  // The resting bed.
  int riding_count() const { return riding_count_; }
  /// +1 riders rest on the bottom cap, −1 on the top cap.
  int bed_side() const { return bed_side_; }
  /// Whether free sphere i leaving its support (rider `support`, −1 a cap; the support's
  /// normal's z component `normal_z_from_support`) at `leaving_m_s` comes to rest there
  /// at t_s, the host then in state `host` (after the collision's impulse, before it
  /// restarts): slower than the rest speed, pressed there by the host's acceleration, and
  /// on the side of the bed if there is one.
  bool rests(int i, int support, double leaving_m_s, double normal_z_from_support, const HostState& host,
             double t_s) const;
  /// The rest speed of sphere i on rider `support` (−1 a cap) along a normal with z component
  /// `normal_z_from_support` at t_s: hard.rest_speed_m_s (at least the elastic speed, below
  /// which it would bounce as fast as it came, without end), or with hard.rest_tc_window the
  /// speed below which the host's pressing acceleration brings it back within that many soft
  /// contact times, if that is faster (hertz_enduring_speed_m_s).
  double rest_speed_m_s(int i, int support, double normal_z_from_support, const HostState& host, double t_s) const;
  /// Whether spheres rest at all (hard.rest_speed_m_s or hard.rest_tc_window above 0).
  bool resting_on() const { return rest_speed_m_s_ > 0.0 || rest_tc_window_ > 0.0; }
  /// What attach did.
  struct Attached {
    HostState host_after;            ///< the host's state after the sticking collision
    bool bed_deeper;                 ///< beyond the depth the guards assumed: predict all anew
    Eigen::Vector3d lab_position_m;  ///< where the sphere came to rest
  };
  /// Free sphere i (its record at t_s) comes to rest on the bed on `side`, on rider
  /// `support` (−1: on its cap), at contact with it: a perfectly inelastic, sticking
  /// collision with the host in state `host` (the normal loss booked as impact, the
  /// sliding and spinning that stop as friction), after which it rides as added mass. The
  /// host must then restart from `host_after`: once for a collision and the sticking that
  /// ends it, so that the two move the host one way (restart).
  Attached attach(int i, int side, int support, const HostState& host, double t_s);
  /// Riding sphere i leaves the bed at t_s with the host's velocity (`host`, now; no
  /// momentum changes hands) and becomes free, without predictions yet; the host must
  /// then restart with the riding mass that is left (before the next event).
  void detach(int i, const HostState& host, double t_s);

  // Host-dependent predictions.
  /// Free sphere i may be within reach of the host at t_s: it becomes near, and gets its
  /// host-relative prediction.
  void enter_near(int i, double t_s) {
    tiers_[0].members.insert(i);
    predict_relative(i, 0, t_s);
  }
  /// Predicts free sphere i's host-dependent event at t_s, starting the descent through
  /// the tiers at `first_level` (a tier it is in: the levels above it are known to hold it).
  void predict_relative(int i, std::size_t first_level, double t_s);
  /// The bed's release (the host's acceleration stops pressing it), if there is a bed.
  void predict_bed_release(double t_s);
  /// Sphere i is far from the host, or riding: in no tier.
  void leave_sets(int i) {
    // The sets nest (touching within the close tier, within the imminent, within the
    // near), and most spheres are in none: one look at the outermost settles it.
    if (!tiers_[0].members.contains(i)) return;
    for (MarginTier& tier : tiers_) tier.members.erase(i);
    touching_.erase(i);
  }
  /// A sphere came to rest at `lab_position_m`: near spheres that could reach it are
  /// predicted anew.
  void repredict_near_around(const Eigen::Vector3d& lab_position_m, double t_s);
  /// Every host-dependent prediction is about to be made anew (after the queue was cleared).
  void forget_predictions();

  // For tests of the tiers.
  /// The margin of tier `level` (m) and its horizon τ (s).
  double margin_m(std::size_t level) const { return tiers_[level].margin_m; }
  double horizon_s(std::size_t level) const { return tiers_[level].horizon_s; }
  /// The innermost tier free sphere i is in (0 near, 1 imminent, 2 close, 3 touching), −1 if far.
  int tier_of(int i) const;

  /// Its state verbatim (hard_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  /// Spheres whose host-dependent events are lower bounds, valid while the host strays
  /// less than `margin_m` from the trajectory they were computed with.
  struct MarginTier {
    ParticleSet members;
    double margin_m;
    double horizon_s;       ///< τ: how far ahead its predictions look
    double budget_m = 0.0;  ///< how far the host may have strayed since the last sweep
    double t_last_sweep_s = 0.0;
  };
  /// Tier `level` for `initial`'s spheres (needs fastest_rate_1_s_).
  MarginTier tier(std::size_t level, const Particles& initial) const;
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
  /// The host-frame box host_contact searched for riders: a rider whose centre lies outside
  /// it cannot be reached before the event it predicted.
  struct SearchBox {
    /// Its corners; by default everywhere (no riders were searched).
    std::array<double, 3> low_m{-never, -never, -never}, high_m{never, never, never};
    SearchBox() = default;
    SearchBox(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& half_m);
    bool holds(const Eigen::Vector3d& p_m, double slack_m) const;
  };
  struct HostContact {
    Approach when;
    EventKind kind;
    int partner;
    SearchBox searched;
  };

  /// How a restart's trajectory departs from the one it replaces: by d(s) after s, with
  /// |d(s)| ≤ velocity·s + ½ acceleration·s², all in `direction` (+1 up, −1 down; 0: not
  /// surely one way) until `until_s`.
  struct Departure {
    int direction;
    double velocity_m_s, acceleration_m_s2;
    double until_s;
  };
  /// The departure of a restart from `start` at t_s, the old trajectory (still
  /// trajectory_) then at `old`, and the riding mass changed from the one it was built with.
  Departure departure(const HostState& old, const HostState& start, double t_s) const;
  void sweep_tier(std::size_t level, double t_s);
  /// After a restart at t_s that departs from the old trajectory as `departure` says:
  /// whether touching sphere i's prediction still stands (see TouchingBound).
  bool defer_touching(int i, const Departure& departure, double t_s);
  /// Whether a rider left since the last restart from the box touching sphere i's last
  /// prediction searched (its event may be a collision with it).
  bool departed_from_box(int i, double t_s) const;
  /// The bound of touching sphere i's exact prediction at t_s, which ends at `until_s`.
  TouchingBound touching_bound(int i, double until_s, double t_s) const;
  /// Calls visit(j) for each rider j in the cells that cover the host-frame box centre ± half.
  template <class Visit>
  void for_each_rider_in(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& half_m, Visit visit) const;
  /// Whether free sphere i, grown by `margin_m`, touches a cap or rider at t_s: what
  /// host_contact(i, end_s, margin_m, t_s) answers at its first step, without its root finders.
  bool within_host_margin(int i, double end_s, double margin_m, double t_s) const;
  /// The first contact of free sphere i, grown by `margin_m`, with a cap or rider, from
  /// t_s until `end_s` (or the end of the riders' window). `riders_searched`, if given,
  /// receives the riders it looked at: all those in a host-frame box around the path
  /// (with margin 0 it reaches touching_slack_m_ farther in z than the path needs).
  HostContact host_contact(int i, double end_s, double margin_m, double t_s,
                           std::vector<int>* riders_searched = nullptr) const;
  bool presses(double normal_z_from_support, const HostState& host, double t_s) const;

  FreeFlight& flight_;
  HardLedger& ledger_;
  // Settings.
  Eigen::Vector3d gravity_m_s2_;
  Cavity cavity_;
  HostModel model_;
  double fastest_rate_1_s_;
  double rest_speed_m_s_;  ///< hard.rest_speed_m_s, at least the elastic speed if resting is on
  double rest_tc_window_;
  double sphere_kn_N_m1_5_, wall_kn_N_m1_5_;  ///< the soft law's, for its contact times

  // The host.
  HostTrajectory trajectory_;
  std::uint32_t epoch_ = 0;
  struct Now {
    double t_s;
    std::uint32_t epoch;
    HostState state;
  };
  mutable Now now_{-never, 0, {}};          ///< now()'s last answer
  double speed_envelope_m_s_;               ///< ≥ the speed bound of every trajectory since the last rebuild
  double trajectory_riding_mass_kg_ = 0.0;  ///< the riding mass trajectory_ was built with

  // The bed.
  double riding_mass_kg_ = 0.0;
  int riding_count_ = 0;
  int bed_side_ = 0;
  double bed_depth_bound_m_ = 0;  ///< riders never reach farther from their cap than this
  CellMembers rider_cells_;       ///< riding spheres by host-frame cell (the free cells' geometry)
  /// Where the riders detached since the last restart were (lab frame): a restart predicts
  /// anew the spheres whose predictions may meet them. Empty between events.
  std::vector<Eigen::Vector3d> departed_m_;

  // The tiers.
  /// Near spheres (host_check fired; margin 0.1 r), within those the imminent ones (within
  /// 0.1 r; margin 0.002 r), within those the close ones (within 0.002 r; margin 4e-5 r).
  std::array<MarginTier, 3> tiers_;
  ParticleSet touching_;  ///< within the inner margin: exact predictions, redone at every impulse (or deferred)
  std::vector<TouchingBound> touching_bound_;
  /// How much farther in z than its path needs a touching sphere's riders are searched:
  /// riders beyond the box stay out of reach of a host that strays less than this.
  double touching_slack_m_;
  std::vector<int> riders_searched_;  ///< predict_relative's scratch: the riders its exact search saw
  /// Each near sphere's box of its last prediction: a rider that comes or goes outside it
  /// leaves the prediction standing (repredict_near_around).
  std::vector<SearchBox> searched_;
  int top_rider_layer_;  ///< the highest layer a rider's host-frame centre can be in
};

}  // namespace pdamp::hard
