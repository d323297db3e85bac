#pragma once
/// The hard engine's books: the energy dissipated, by mechanism and by sphere, and the
/// excitation's work (J), and its counts of what happened (run_statistics).
///
/// Collisions book their losses as they happen. The host's damper and its excitation act
/// all the time: they are booked in closed form over each stretch of one host trajectory,
/// whenever the trajectory ends (an impulse, a change of riding mass) and at the end of
/// every advance; an observation adds what the current trajectory did since. The host's
/// load integrals likewise: the riding bed's load m_r (g_z − z'') and z(t) over each
/// stretch, and the impulses the host takes as they happen (HostCoupling::take_impulse).

#include <array>
#include <cstdint>

#include "hard/collision_rules.hpp"
#include "pdamp/model/energy_ledger.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/model/host.hpp"

namespace pdamp::hard {

/// What the hard engine counts: events by kind, what the resting bed and the jams did,
/// the host's impulses and the host-dependent predictions they cost.
struct HardStatistics {
  std::int64_t sphere_sphere = 0, side_wall = 0, cap = 0, rider = 0, cell_crossing = 0, host_check = 0, host_margin = 0,
               stale = 0, rests = 0, knocked_off = 0, bed_releases = 0, jammed = 0, host_impulses = 0, jam_merges = 0,
               jam_merged_spheres = 0, jam_stuck_to_host = 0, touching_repredictions = 0, touching_deferrals = 0,
               rebuilds = 0;
  /// Of each tier (near, imminent, close): its sweeps and the predictions they redid.
  std::array<std::int64_t, 3> tier_sweeps{}, tier_repredictions{};

  /// Collisions of all kinds.
  std::int64_t collisions() const { return sphere_sphere + side_wall + cap + rider; }
  /// Each count under its name in run_statistics.
  EngineStatistics named() const;
};

/// The spheres riding on the host, as far as the books need them: a prescribed host
/// carries them, so the change of their energy that moves with it is the host's work.
struct Riders {
  double mass_kg;
  double gravity_z_m_s2;
  bool carried_by_prescribed_host;
  /// Their kinetic and potential energy that moves with the host.
  double energy_J(const HostState& host) const {
    return mass_kg * (0.5 * host.v_m_s * host.v_m_s - gravity_z_m_s2 * host.z_m);
  }
};

class HardLedger {
 public:
  /// Books for `particle_count` spheres, the harmonic integrals weighted at `phase`.
  explicit HardLedger(int particle_count, ExcitationPhase phase = {})
      : by_sphere{Eigen::VectorXd::Zero(particle_count), Eigen::VectorXd::Zero(particle_count)}, load(phase) {}

  /// Booked so far (J).
  double impact_J = 0.0, friction_J = 0.0, viscous_J = 0.0, excitation_J = 0.0;
  /// The impact and friction losses by sphere (Engine::dissipation_by_sphere).
  SphereDissipation by_sphere;
  /// The host's load integrals booked so far.
  HostLoadBooks load;
  HardStatistics counts;

  /// A collision's loss: all of it sphere i's (against a wall), or half each i's and j's
  /// (a sphere, or a riding sphere that took the impulse for the host).
  void book(const CollisionOutcome& outcome, int i, int j = -1) {
    impact_J += outcome.impact_J;
    friction_J += outcome.friction_J;
    if (j < 0) {
      book_sphere(i, outcome.impact_J, outcome.friction_J);
    } else {
      book_sphere(i, 0.5 * outcome.impact_J, 0.5 * outcome.friction_J);
      book_sphere(j, 0.5 * outcome.impact_J, 0.5 * outcome.friction_J);
    }
  }
  /// Sphere i's share of a loss whose totals are booked apart.
  void book_sphere(int i, double impact_share_J, double friction_share_J) {
    by_sphere.impact_J[i] += impact_share_J;
    by_sphere.friction_J[i] += friction_share_J;
  }
  /// The host's damper and excitation on `trajectory` from the last booking to t_s, with
  /// `riders` on it.
  void book_host(const HostTrajectory& trajectory, double t_s, const Riders& riders);
  /// The dissipation and the excitation's work into `o.energy`, the load integrals into
  /// `o.host_load`, as at t_s on `trajectory` (what was booked, and the trajectory since
  /// the last booking).
  void write_to(Observation& o, const HostTrajectory& trajectory, double t_s, const Riders& riders) const;

  /// Its state verbatim (hard_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  /// Adds what the host did on `trajectory` from the last booking to t_s.
  void add_host_since_booked(double& viscous_sum_J, double& excitation_sum_J, HostLoadBooks& load_sums,
                             const HostTrajectory& trajectory, double t_s, const Riders& riders) const;

  double t_host_booked_s_ = 0.0;
};

}  // namespace pdamp::hard
