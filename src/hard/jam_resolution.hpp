#pragma once
/// Jams: free spheres that keep colliding at one instant. Touching spheres driven into
/// each other collide without end at one instant, the hard-sphere limit of a jam:
/// inelastic collapse drives their approach speeds to zero in infinitely many
/// collisions, and friction in a wedge can turn slip at one contact into approach at the
/// next for ever. The limit is taken at once: the cluster (free spheres linked by
/// collisions at this instant, all touching since time has not moved) moves on as one
/// rigid body. A cluster that a wall or the bed holds as well would be driven back into
/// it by that rigid motion, so it also sticks to the host.
///
/// JamResolver records the collisions of each instant and, once a sphere has collided
/// more than `repeats` times, finds its cluster and resolves it: the rigid merge and the
/// sticking, with their losses booked. Moving the spheres to the instant and predicting
/// them afterwards is the engine's.

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "hard/hard_ledger.hpp"
#include "hard/packed_particles.hpp"
#include "pdamp/model/host.hpp"

namespace pdamp::hard {

/// The relative motion at contacts, to split a rigid merge's loss: normal and total, each
/// contact's relative velocity squared weighted by the pair's reduced mass.
class ContactMotion {
 public:
  /// The contact of spheres k and j as their records stand.
  void add(int k, int j, const PackedParticles& particles);
  /// The normal part's share of the total (1 without relative motion).
  double impact_share() const { return total_ > 0.0 ? normal_ / total_ : 1.0; }

 private:
  double normal_ = 0.0, total_ = 0.0;
};

/// Stops all relative motion of `members` (their records at one instant): a perfectly
/// inelastic, sticking merge into a rigid body with their momentum and angular momentum.
/// The energy removed (that of the relative motion, ≥ 0) is booked as impact and friction
/// in the proportion `impact_share` : 1 − `impact_share` (ContactMotion), each sphere's
/// part being the energy of its own motion removed.
void merge_into_rigid_body(std::span<const int> members, double impact_share, PackedParticles& particles,
                           HardLedger& ledger);

class JamResolver {
 public:
  /// What a sphere collided with at this instant, besides free spheres.
  enum Hold : std::uint8_t { held_by_side_wall = 1, held_by_cap_or_bed = 2 };
  /// A sphere that collides this many times at one instant and again is jammed.
  static constexpr int repeats = 64;

  explicit JamResolver(int particle_count);

  /// Records a collision at t_s of free sphere i with free sphere j, or with the host
  /// (j < 0; `hold` says which part); true once i or j has collided more than `repeats`
  /// times at t_s (wedged in a jammed cluster).
  bool note_collision(int i, int j, double t_s, std::uint8_t hold = 0);

  /// Free spheres linked by collisions at this instant, in ascending order, and the
  /// parts of the host any of them collided with (Hold bits).
  struct Cluster {
    std::vector<int> members;
    std::uint8_t hold = 0;
  };
  /// The jammed cluster of sphere i: the free spheres linked to it by this instant's
  /// collisions (`riding(j)` says which have come to rest since).
  template <class Riding>
  Cluster cluster_of(int i, Riding riding);

  /// Stops all relative motion of the cluster (its spheres' records at this instant):
  /// merge_into_rigid_body, its loss split by the relative motion at the contacts of this
  /// instant's collisions.
  void merge_rigidly(const Cluster& cluster, PackedParticles& particles, HardLedger& ledger) const;
  /// A perfectly inelastic, sticking collision of the merged cluster with the host at
  /// `host` (a prescribed one, or a free one carrying `carried_mass_kg` in all): the host
  /// takes the body's vertical momentum, the walls (fixed horizontally) its horizontal
  /// momentum and its spin, and every sphere leaves with the host's velocity after. Returns
  /// the vertical collision (the host's velocity after, the body's impulse). The loss is impact where it is normal to a
  /// holding wall (the horizontal part at the side wall, the vertical part at a cap or the bed) and friction otherwise,
  /// the spin included.
  VerticalSticking stick_to_host(const Cluster& cluster, const HostState& host, bool prescribed, double carried_mass_kg,
                                 PackedParticles& particles, HardLedger& ledger) const;

  /// Its state verbatim (hard_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  /// note_collision's record of one collision in the spheres' counts, partners and holds.
  bool record_collision(int i, int j, std::uint8_t hold);

  /// The collisions of free spheres at the instant t_s: per sphere how many, with which
  /// free spheres, and which parts of the host (Hold bits).
  double t_s_ = -1.0;
  std::vector<int> count_;
  std::vector<std::vector<int>> partners_;
  std::vector<std::uint8_t> hold_;
  std::vector<int> involved_;  ///< spheres with a count, to reset them when time moves on
  /// The instant's first collision, until a second one enters it in the records: most
  /// instants see one collision, which cannot be a jam.
  struct {
    int i = 0, j = 0;
    std::uint8_t hold = 0;
    bool pending = false;
  } first_;
  std::vector<std::uint8_t> in_cluster_;  ///< cluster_of's scratch
};

template <class Riding>
JamResolver::Cluster JamResolver::cluster_of(int i, Riding riding) {
  Cluster cluster{{i}, 0};
  std::vector<int>& members = cluster.members;
  in_cluster_[i] = 1;
  for (std::size_t k = 0; k < members.size(); ++k) {
    cluster.hold |= hold_[members[k]];
    for (const int j : partners_[members[k]]) {
      if (in_cluster_[j] || riding(j)) continue;
      in_cluster_[j] = 1;
      members.push_back(j);
    }
  }
  for (const int k : members) in_cluster_[k] = 0;
  std::sort(members.begin(), members.end());
  return cluster;
}

}  // namespace pdamp::hard
