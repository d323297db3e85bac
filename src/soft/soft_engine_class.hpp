#pragma once
/// The soft engine's class (pdamp/soft/soft_engine.hpp is its public face): the soft-sphere
/// DEM engine, the paper's Hertz law with tangential history, velocity Verlet for
/// particles, their rotations and the host, contacts found exactly with a Verlet neighbour
/// list on the shared cell grid. The reference model.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "pdamp/model/cavity.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/model/host.hpp"
#include "pdamp/simd/simd_path.hpp"
#include "pdamp/soft/soft_engine.hpp"
#include "soft/contact_law.hpp"
#include "soft/contact_table.hpp"
#include "soft/neighbour_list.hpp"
#include "soft/sphere_arrays.hpp"

namespace pdamp::soft {

class SoftEngine final : public Engine {
 public:
  SoftEngine(const Scenario& scenario, const Particles& initial, SoftEngineOptions options = {});

  void advance_to(double t_s) override;
  Observation observe() const override;
  State state() const override;
  SphereDissipation dissipation_by_sphere() const override;
  double time_step_s() const override { return dt_s_; }
  EngineStatistics statistics() const override;
  std::vector<std::string> warnings() const override;
  /// Everything a step reads: the spheres in their current order, the neighbour list and
  /// the contact tables with their tangential histories as they stand, the host, the
  /// books and counters (soft_checkpoint.cpp). Any thread count and SIMD path may resume.
  void save(CheckpointWriter& out) const override;
  void restore(CheckpointReader& in) override;

  /// Kinetic energy of the particles, translational plus rotational (J).
  double particle_kinetic_J() const;
  SimdPath simd_path() const { return simd_path_; }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  /// The particles' energies, each summed sphere by sphere (observe, particle_kinetic_J).
  ParticleEnergySums particle_energies() const;
  // The phases of a velocity-Verlet step (advance_to strings them together).
  double next_step_s(double t_s);
  void move(double kick_s, double dt_s);
  void refresh_neighbours();
  void compute_forces(double dt_s);
  /// The host's forces at the end of a step of dt_s, and their books over it.
  void add_host_forces(double dt_s);
  void kick(double dt_s);
  /// Throws RuntimeFailure if a position (a sphere's or the host's) is no longer a finite number.
  void check_state_finite() const;
  void check_particles_inside() const;

  double host_acceleration_m_s2() const;

  // The kernels, run chunk by chunk in the instruction set of simd_path_ (soft_engine.cpp).
  // Always inlined, down to their last part, into a function compiled for that instruction
  // set: none of them exists on its own, compiled for another.
  struct DriftPass;
  struct ForcePass;
  struct BuildPass;
  /// The pass's kernel compiled for simd_path_: it runs pass.run<Real>(c) for chunk (or part) c.
  template <class Pass>
  auto kernel() const -> void (*)(Pass&, int);
  /// Runs the kernel for c = 0, ..., count − 1 on the threads.
  template <class Pass>
  void run_kernel(Pass& pass, int count);
  /// Kicks and drifts the spheres of chunk c; returns whether one has moved past half the skin.
  template <class Real>
  [[gnu::always_inline]] inline bool drift_chunk(int c, double kick_s, double dt_s);
  template <class Real>
  [[gnu::always_inline]] inline void force_chunk(int c, double dt_s);

  /// What one chunk of spheres adds up in a force computation.
  struct ChunkTotals {
    double impact_J = 0.0, friction_J = 0.0, elastic_J = 0.0, on_host_N = 0.0, max_overlap_ratio = 0.0;
    std::int64_t contacts = 0;
    void record_contact(double overlap_ratio);  ///< overlap / smaller radius
  };
  /// Spheres per chunk: fixed, so that sums are formed in the same order on any number of threads.
  static constexpr int chunk_size = NeighbourList::group_size;
  int chunk_count() const { return (sphere_count() + chunk_size - 1) / chunk_size; }
  bool runs_in_parallel() const;
  int sphere_count() const { return balls_.size(); }

  /// Force and torque on each sphere of a chunk, and its share of the step's losses, as
  /// they build up in the force pass.
  struct ChunkWrenches {
    double fx[chunk_size], fy[chunk_size], fz[chunk_size], tx[chunk_size], ty[chunk_size], tz[chunk_size];
    double impact_J[chunk_size], friction_J[chunk_size];
  };
  /// What a pair contact gives its partner, added after the force pass: its force and
  /// torque if it touches, and the partner's half of the step's losses (also of a contact
  /// that has just come apart).
  struct Reaction {
    Vec3<double> force_N, torque_N_m;
    double impact_J, friction_J;
    int partner;
    bool touching;
  };
  // The force pass's parts; inlined, the chunk's totals also stay in registers (the pass's
  // stores, histories and reactions, might otherwise alias them and force a store and
  // reload per contact).
  template <class Real>
  [[gnu::always_inline]] inline void start_forces(int first, int end, ChunkWrenches& on_chunk) const;
  /// Lists the pairs of spheres [first, end) that touch or were touching; returns how many.
  template <class Real>
  [[gnu::always_inline]] inline int list_pairs_to_evaluate(int first, int end, int* out) const;
  /// Spheres per wall, each list with a register's worth of room past its last sphere.
  using WallLists = std::array<std::array<int, chunk_size + NeighbourList::padding>, 3>;
  /// Lists, for each wall, the spheres of [first, end) that touch it or were touching;
  /// returns how many.
  template <class Real>
  [[gnu::always_inline]] inline std::array<int, 3> list_wall_contacts_to_evaluate(int first, int end,
                                                                                  WallLists& out) const;
  /// Evaluates the pairs `pairs[0, count)` of chunk c (count ≤ lanes; `pairs` holds a
  /// register's worth), adding to the chunk's wrenches and writing their reactions at
  /// `reactions[reaction_count++]`.
  template <class Real>
  [[gnu::always_inline]] inline void add_pair_contacts(const int* pairs, int count, double dt_s, int c,
                                                       ChunkTotals& totals, ChunkWrenches& on_chunk,
                                                       Reaction* reactions, int& reaction_count);
  /// Evaluates the contacts of `spheres[0, count)` of chunk c with one wall, likewise.
  template <class Real, int wall>
  [[gnu::always_inline]] inline void add_wall_contacts(const int* spheres, int count, double dt_s, int c,
                                                       ChunkTotals& totals, ChunkWrenches& on_chunk);
  /// The history of entry[l] of the table, in lane l.
  template <class Real>
  [[gnu::always_inline]] static inline ContactHistory<Real> gather_histories(const ContactTable& contacts,
                                                                             const int* entry);
  /// Adds lane l of a contact evaluated for the sphere in `slot` of its chunk: its force and
  /// torque (which acts with the opposite sign), its energy (`loss_share` of the losses to
  /// the sphere), and its history, opened, kept or closed at `open`.
  template <class Real>
  [[gnu::always_inline]] static inline void book_contact(const ContactForce<Real>& f, const Vec3<Real>& torque,
                                                         const ContactHistory<Real>& h, int l, bool touching,
                                                         double overlap_ratio, double loss_share, int& open,
                                                         ContactTable& contacts, ChunkTotals& totals,
                                                         ChunkWrenches& on_chunk, int slot);
  void add_reactions();

  // Renumbering the spheres at each neighbour-list build (refresh_neighbours).
  void set_aside_open_contacts(const std::vector<int>& order);
  void reorder_spheres(const std::vector<int>& order);
  void hand_over_contacts(const std::vector<int>& order);

  Scenario scenario_;
  SoftEngineOptions options_;
  SimdPath simd_path_;
  HostModel host_model_;
  Cavity cavity_;
  double dt_s_;
  double t_s_ = 0.0;
  double end_of_advance_s_ = -1.0;  ///< set for the step that must end exactly at advance_to's target

  // Particles (SI), in cell order: slot s holds the scenario's sphere original_index_[s].
  // Between the kicks v_ and w_ are the half-step velocities, which the contact forces
  // (dashpots included) are computed with.
  SphereBalls balls_;
  SphereMotions v_, w_;
  SphereVectors force_, torque_, x_at_rebuild_;
  SphereScalars mass_;
  /// Each sphere's losses since t = 0 (dissipation_by_sphere).
  SphereScalars impact_J_, friction_J_;
  std::vector<int> original_index_;
  std::vector<bool> visited_;  ///< scratch for renumbering
  NeighbourList neighbours_;
  /// The open contacts of each chunk's spheres, pairs and walls; and the reactions of its
  /// pair contacts on their partners at the last force computation (added to the partners
  /// after the chunks, in chunk order).
  std::vector<ContactTable> contact_tables_, next_contact_tables_;
  std::vector<std::vector<Reaction>> reactions_;
  /// During a rebuild: the open pair contacts, by their new owner
  /// ([kept_first_[i], kept_first_[i + 1]) for sphere i), and where partner j of the
  /// current owner is kept, or −1.
  struct KeptContact {
    int partner, table, entry;
    bool flipped;  ///< owner and partner swapped by the renumbering: the history changes sign
  };
  std::vector<KeptContact> kept_;
  std::vector<int> kept_first_, kept_slot_;
  /// During a rebuild: the last new chunk that reads each old table, and the old tables
  /// in the order they are freed.
  std::vector<int> last_reader_, release_order_;
  std::vector<ChunkTotals> chunk_totals_;
  /// Per thread: the contacts of its current chunk to evaluate, pairs (room for all the
  /// chunk's pairs) and spheres at each wall.
  struct PassScratch {
    std::vector<int> pairs;
    WallLists wall_spheres;
  };
  std::vector<PassScratch> scratch_;
  int most_pairs_in_a_chunk_ = 0;
  std::vector<int> farthest_partner_;  ///< of each chunk's pairs (−1 if it has none)
  bool needs_rebuild_ = true;
  double host_z_at_rebuild_ = 0.0;
  /// Each particle's open contact with the side wall, the bottom and the top (indexed by
  /// wall, then particle), in its chunk's table (ContactTable::none if apart).
  std::array<std::vector<int>, 3> wall_contacts_;

  // Host.
  HostState host_;
  double host_particle_force_N_ = 0.0;  ///< vertical force of the particles on the host
  double host_other_force_N_ = 0.0;     ///< spring, damper and excitation at the current step
  /// The host's forces and positions at the last force computation, for the energy and load books.
  struct HostForces {
    double stretch_m = 0.0, stretch_rate_m_s = 0.0, applied_N = 0.0, particles_N = 0.0, z_m = 0.0, base_m = 0.0;
    double own_N = 0.0;
    ExcitationPhase::Weights weights{0.0, 1.0};
  };
  HostForces previous_host_forces_;
  /// Books the host's load integrals over the step of dt_s from `before` to `now`.
  void book_host_load(const HostForces& before, const HostForces& now, double dt_s);
  /// The host's load integrals: the trapezoid over each step, as the kicks apply the forces.
  HostLoadBooks host_load_;

  EnergyLedger ledger_;
  double contact_elastic_J_ = 0.0;
  std::int64_t steps_ = 0;
  std::int64_t contacts_ = 0;
  double max_overlap_ratio_ = 0.0;
  double max_overlap_time_s_ = 0.0;
};

}  // namespace pdamp::soft
