#pragma once
/// The hard engine's class (pdamp/hard/hard_engine.hpp is its public face): the
/// event-driven hard-sphere engine (docs/hard-engine.md).
///
/// Spheres fly on exact parabolas and are advanced lazily: each keeps the time its
/// position and velocity refer to, and only the spheres an event involves are moved.
/// One step of `advance_to` pops the earliest event, drops it if stale, and handles it;
/// handling a collision applies Walton's impulse, books the losses and predicts the
/// involved spheres' next events.
///
/// The engine keeps the event loop and the handling of each kind of event; the rest is
/// in four parts with one job each, plain members that hold their own state:
/// - FreeFlight: the spheres, their cells, the event queue, and the predictions that
///   need no host (other spheres, cell faces, the side wall);
/// - HostCoupling: the host's trajectory and speed envelope, the tiers and touching
///   bounds of the host-dependent predictions, the riding spheres and the resting bed;
/// - JamResolver: the collisions of each instant, and the rigid merge (and sticking to
///   the host) of a cluster that keeps colliding at one instant;
/// - HardLedger: the energy books and the counts of events;
/// - RigidClusters (off by default): who moves as one rigid body since a slow collision.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "hard/collision_rules.hpp"
#include "hard/event_diagnosis.hpp"
#include "hard/free_flight.hpp"
#include "hard/hard_ledger.hpp"
#include "hard/host_coupling.hpp"
#include "hard/jam_resolution.hpp"
#include "hard/rigid_clusters.hpp"
#include "pdamp/hard/hard_engine.hpp"
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
  SphereDissipation dissipation_by_sphere() const override { return books_.by_sphere; }
  double time_step_s() const override { return 0.0; }
  EngineStatistics statistics() const override;
  std::vector<std::string> warnings() const override;
  /// Everything the event loop reads: the spheres with their own clocks, the event queue's
  /// content and calendar as they stand (the order of ties is the queue's), the host's
  /// trajectory, tiers, riders and bed, the jams, the books and counters
  /// (hard_checkpoint.cpp).
  void save(CheckpointWriter& out) const override;
  void restore(CheckpointReader& in) override;

  /// The deepest overlap now between two spheres or a sphere and a wall (m, 0 if none).
  double max_overlap_m() const { return deepest_overlap().depth_m; }
  /// Overlaps never exceed this (m): the contact tolerance of the root finders plus round-off.
  double overlap_tolerance_m() const { return 10.0 * flight_.contact_tolerance_m(); }
  /// Where the deepest overlap is: spheres i and j (j −1: i and `wall`), how deep (m).
  struct Overlap {
    double depth_m = 0.0;
    int i = -1, j = -1;
    Wall wall = Wall::side;
  };
  Overlap deepest_overlap() const;
  /// "sphere 3 (riding) and the side wall", for messages.
  std::string describe(const Overlap& overlap) const;
  /// What a failure at `overlap` adds to its message: a known limitation and what to run
  /// instead, or that it is a defect to report.
  std::string known_cause(const Overlap& overlap) const;
  int riding_count() const { return host_.riding_count(); }
  /// Whether the engine asks for neighbours' records and cells ahead of use: where they
  /// outgrow half the L2 cache (FreeFlight).
  bool prefetching() const { return flight_.prefetching(); }
  /// Collisions processed so far (all kinds).
  std::int64_t collisions() const { return books_.counts.collisions(); }
  /// From now on, counts where the collisions come from (EventDiagnosis) and adds the
  /// counts to statistics().
  void diagnose_events(const Scenario& scenario) { diagnosis_ = std::make_unique<EventDiagnosis>(scenario); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  /// Lab-frame position of any sphere now (free or riding).
  Eigen::Vector3d position_now(int i, const HostState& host) const;
  /// The law of a collision of i with `partner`: j (−1 for a wall or rider; `rider`, the
  /// rider) at this approach speed (ContactLaws); records the collision's time.
  /// Always inlined into the collisions, as before the TC window (as a call it cost the gas
  /// 0.9 % more instructions per collision: tools/bench/HISTORY.md).
  [[gnu::always_inline]] HardContactLaw law_for(double approach_speed_m_s, Partner partner, int i, int j,
                                                int rider = -1);
  /// Whether the collision of i with j (or `rider`, or a wall) falls within the TC window
  /// of an earlier collision of i or j (before law_for records this one).
  [[gnu::noinline]] bool within_tc_window(double approach_speed_m_s, bool wall, int i, int j, int rider) const;

  /// Tells the diagnosis of a collision of `kind` of sphere i with sphere `partner` (a
  /// free one for sphere_sphere, a rider for rider; −1 a wall), before law_for records it.
  [[gnu::cold, gnu::noinline]] void diagnose(EventDiagnosis::Kind kind, int i, int partner, double approach_m_s);
  /// Throws Interrupted on a stop request and RuntimeFailure past run.max_events.
  [[gnu::cold, gnu::noinline]] void poll();

  // Prediction.
  /// Predicts every event of free sphere i anew (its trajectory changed).
  void predict(int i) {
    const FreeFlight::Around around = flight_.around(i);
    predict(i, around);
  }
  /// Predicts sphere i's events anew, but its contacts only with the spheres in
  /// `new_cells` (it has just crossed into a cell whose other neighbours it already had):
  /// an Around or a Layer.
  void predict(int i, std::span<const int> new_cells);
  /// Forgets every prediction and predicts every free sphere anew.
  void rebuild_predictions();

  /// Throws if spheres overlap beyond the tolerance at the end of advance_to: every time
  /// in Debug builds, in release builds once check_events() events or check_calls calls
  /// have passed since the last check.
  void check_overlaps(double t_s);

  // Events.
  void handle(const Event& event);
  void collide_spheres(int i, int j);
  void collide_wall(int i, EventKind wall);
  void collide_rider(int i, int j);
  /// The jammed cluster of i stops all relative motion at once (JamResolver), and sticks
  /// to the host if a wall or the bed holds any of its spheres.
  void merge_jam(int i);
  /// A collision of free spheres i and j (brought to now) approaching at `approach_m_s`:
  /// if slower than the cluster speed, their clusters merge into one rigid body, and
  /// true; else they leave their clusters, and false (the collision is a binary one).
  bool join_clusters(int i, int j, double approach_m_s);
  void release_bed();

  // The host.
  /// A sphere-host collision outcome applied to sphere i (arm r n) and the host in state
  /// `host`; its loss is shared with `rider` if a riding sphere took the impulse for the
  /// host. Returns the host's state after it; the caller restarts the host.
  HostState apply_host_impulse(int i, const Eigen::Vector3d& normal, const CollisionOutcome& outcome,
                               const HostState& host, int rider = -1);
  /// The host moves on from `start` (HostCoupling::restart), and every prediction is
  /// made anew if it may now move faster than the far spheres' checks assumed.
  void restart_host(HostState start);
  /// After a collision with its support (rider `support`, or −1 for a cap; normal from it)
  /// that took the host from `before` to `after`, sphere i comes to rest, or is predicted
  /// anew; either way the host restarts once.
  void rest_if_slow(int i, const Eigen::Vector3d& normal_from_support, int support, const HostState& before,
                    const HostState& after);
  /// Sphere i comes to rest on the bed on `side` (+1 the floor, −1 the top cap), on rider
  /// `support` (−1: its cap), the host in state `host`: the host restarts with it, and the
  /// near spheres that could reach it are predicted anew.
  void attach(int i, int side, int support, const HostState& host);

  FreeFlight flight_;
  HardLedger books_;
  HostCoupling host_;
  JamResolver jams_;
  RigidClusters clusters_;
  ContactLaws laws_;
  double t_s_ = 0.0;
  double separation_m_ = 0.0;  ///< how far the initial spheres were moved apart
  std::int64_t events_at_this_instant_ = 0;
  std::int64_t stall_limit_;
  /// Events popped so far, all kinds; every poll_interval of them poll() looks at the
  /// stop request and run.max_events.
  static constexpr std::int64_t poll_interval = 4096;
  std::int64_t events_ = 0;
  std::int64_t max_events_;
  std::int64_t next_poll_;
  /// Some 1024 events per sphere between two overlap checks keep them a small fraction of a
  /// run (docs/hard-engine.md, "Overlaps"); the calls catch a run whose events stopped. Not
  /// state: a resumed run checks anew.
  std::int64_t check_events() const { return 1024 * (static_cast<std::int64_t>(flight_.size()) + 16); }
  static constexpr int check_calls = 1024;
  std::int64_t next_check_event_;
  int calls_since_check_ = 0;
  std::unique_ptr<EventDiagnosis> diagnosis_;  ///< null unless diagnose_events()
};

}  // namespace pdamp::hard
