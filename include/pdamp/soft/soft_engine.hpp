#pragma once
/// The soft-sphere DEM engine: the paper's Hertz law with tangential history, velocity
/// Verlet for particles, their rotations and the host, contacts found exactly with a
/// Verlet neighbour list on the shared cell grid. The reference model.

#include <array>
#include <string>
#include <vector>

#include "pdamp/model/cavity.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/model/host.hpp"
#include "pdamp/soft/contact_law.hpp"
#include "pdamp/soft/contact_table.hpp"
#include "pdamp/soft/neighbour_list.hpp"

namespace pdamp::soft {

struct SoftEngineOptions {
  /// Keep the host still at its initial displacement (the settling phase).
  bool hold_host = false;
  /// Drag −γ m v on every sphere and −γ I ω on its spin (1/s); only for settling, where
  /// spheres rolling on the floor would otherwise never stop (the law has no rolling
  /// resistance). Zero in every run.
  double settling_drag_1_s = 0.0;
  /// Neighbour-list skin as a fraction of the largest diameter.
  double skin_fraction = 0.3;
};

class SoftEngine final : public Engine {
 public:
  SoftEngine(const Scenario& scenario, const Particles& initial, SoftEngineOptions options = {});

  void advance_to(double t_s) override;
  Observation observe() const override;
  State state() const override;
  double time_step_s() const override { return dt_s_; }
  EngineStatistics statistics() const override;
  std::vector<std::string> warnings() const override;

  /// Kinetic energy of the particles, translational plus rotational (J).
  double particle_kinetic_J() const;

 private:
  // The phases of a velocity-Verlet step (advance_to strings them together).
  double next_step_s(double t_s);
  void move(double kick_s, double dt_s);
  void refresh_neighbours();
  void compute_forces(double dt_s);
  void add_host_forces();
  void kick(double dt_s);
  void check_particles_inside() const;

  double host_acceleration_m_s2() const;

  /// What one chunk of spheres adds up in a force computation.
  struct ChunkTotals {
    double impact_J = 0.0, friction_J = 0.0, elastic_J = 0.0, on_host_N = 0.0, max_overlap_ratio = 0.0;
    std::int64_t contacts = 0;
    void record_contact(double overlap_m, double radius_m);
  };
  /// Spheres per chunk: fixed, so that sums are formed in the same order on any number of threads.
  static constexpr int chunk_size = 64;
  /// Below this many spheres a step is too short to share between threads.
  static constexpr int parallel_minimum = 512;
  /// Force and torque on one body.
  struct Wrench {
    Eigen::Vector3d force_N = Eigen::Vector3d::Zero(), torque_N_m = Eigen::Vector3d::Zero();
  };
  /// A listed pair whose contact is evaluated this step: its owner and its index in the list.
  struct PairToEvaluate {
    int owner, pair;
  };
  // Inlined into the force pass so that the chunk's totals stay in registers: the pass's
  // stores (histories, reactions) might otherwise alias them and force a store and reload
  // per contact.
  [[gnu::always_inline]] inline Wrench start_forces(int i) const;
  /// Lists the pairs of spheres [first, end) that touch or were touching; returns how many.
  [[gnu::always_inline]] inline int list_pairs_to_evaluate(int first, int end, PairToEvaluate* out) const;
  /// Evaluates lane_count<Real> pairs at once, adding to the wrenches `on_chunk[owner − first]`.
  template <class Real>
  [[gnu::always_inline]] inline void add_pair_contacts(const PairToEvaluate* pairs, double dt_s, int first,
                                                       ContactTable& contacts, ChunkTotals& totals, Wrench* on_chunk);
  [[gnu::always_inline]] inline void add_wall_contacts(int i, double dt_s, ContactTable& contacts, ChunkTotals& totals,
                                                       Wrench& on_i);
  void add_reactions();
  void compact_contact_tables();

  Scenario scenario_;
  SoftEngineOptions options_;
  HostModel host_model_;
  Cavity cavity_;
  double dt_s_;
  double t_s_ = 0.0;
  double end_of_advance_s_ = -1.0;  ///< set for the step that must end exactly at advance_to's target

  // Particles (SI), in the initial order. Between the kicks v_ and w_ are the half-step
  // velocities, which the contact forces (dashpots included) are computed with.
  std::vector<Eigen::Vector3d> x_, v_, w_, force_, torque_;
  std::vector<double> radius_, mass_, inv_mass_, inv_inertia_;
  NeighbourList neighbours_;
  /// The open contacts of each chunk's spheres, pairs and walls, with the reactions the
  /// pair contacts put on their partners (added to the partners after the chunks, in
  /// chunk order).
  std::vector<ContactTable> contact_tables_;
  ContactTable compacted_table_;  ///< where compact_contact_tables builds each chunk's table
  std::vector<ChunkTotals> chunk_totals_;
  /// Per thread: the pairs of its current chunk to evaluate (as long as the chunk's pairs).
  std::vector<std::vector<PairToEvaluate>> pairs_to_evaluate_;
  int most_pairs_in_a_chunk_ = 0;
  std::vector<Eigen::Vector3d> x_at_rebuild_;
  bool needs_rebuild_ = true;
  double host_z_at_rebuild_ = 0.0;
  /// Each particle's open contacts with the side wall, the bottom and the top, in its
  /// chunk's table (ContactTable::none if apart).
  std::vector<std::array<int, 3>> wall_contacts_;

  // Host.
  HostState host_;
  double host_particle_force_N_ = 0.0;  ///< vertical force of the particles on the host
  double host_other_force_N_ = 0.0;     ///< spring, damper and excitation at the current step
  /// The host's forces and positions at the last force computation, for the energy books.
  struct HostForces {
    double stretch_m = 0.0, stretch_rate_m_s = 0.0, applied_N = 0.0, particles_N = 0.0, z_m = 0.0, base_m = 0.0;
  };
  HostForces previous_host_forces_;

  EnergyLedger ledger_;
  double contact_elastic_J_ = 0.0;
  std::int64_t steps_ = 0;
  std::int64_t contacts_ = 0;
  double max_overlap_ratio_ = 0.0;
  double max_overlap_time_s_ = 0.0;
};

}  // namespace pdamp::soft
