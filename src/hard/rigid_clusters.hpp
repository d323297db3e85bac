#pragma once
/// Lasting contacts as rigid clusters (`[hard] cluster_speed_m_s`, off by default;
/// docs/hard-engine.md, "Rigid clusters"). On a dense bed nearly every collision comes
/// within a soft contact time of an earlier one, most of them ever slower: touching spheres
/// whose relative motion dies out in endless binary collisions. In free flight every sphere
/// feels the same gravity, so spheres that move as one rigid body have no collisions among
/// them at all. A collision of two free spheres approaching slower than the cluster speed
/// therefore merges their clusters into one rigid body (JamResolver's perfectly inelastic,
/// sticking merge): the cluster takes a slow sphere's impulse with its whole mass. A sphere
/// leaves its cluster whenever anything else changes its motion: a collision faster than
/// the cluster speed, with the side wall, a cap or the riding bed, a jam; the rest of the
/// cluster flies on unchanged.
///
/// RigidClusters keeps who is in which cluster and counts the joins and departures;
/// moving the spheres, the merge and the predictions are the engine's.

#include <cstdint>
#include <span>
#include <vector>

#include "pdamp/model/checkpoint.hpp"
#include "pdamp/model/engine.hpp"

namespace pdamp::hard {

class RigidClusters {
 public:
  /// For `particle_count` spheres, each alone; `speed_m_s` is the cluster speed (0: off).
  RigidClusters(int particle_count, double speed_m_s);

  /// Whether collisions slower than the cluster speed merge (cluster_speed_m_s > 0).
  bool enabled() const { return speed_m_s_ > 0.0; }
  /// Whether a collision approaching at `approach_m_s` merges the clusters of its spheres.
  bool merges(double approach_m_s) const { return approach_m_s < speed_m_s_; }

  /// Joins the clusters of spheres i and j (either may be alone) into one; returns its
  /// members (i's cluster's, then j's; each cluster keeps its order).
  std::span<const int> join(int i, int j);
  /// Sphere i leaves its cluster, if in one (a cluster left with one sphere ends).
  void leave(int i) {
    if (cluster_[i] >= 0) remove(i);
  }
  /// The cluster of sphere i (−1 if alone) and its members.
  int cluster_of(int i) const { return cluster_[i]; }
  std::span<const int> members(int cluster) const { return members_[static_cast<std::size_t>(cluster)]; }

  /// The counts, named as in the store: merges, the spheres they moved, departures.
  EngineStatistics named() const;

  /// Its state verbatim (hard_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  void remove(int i);

  double speed_m_s_;
  std::vector<int> cluster_;               ///< per sphere: its cluster, −1 alone
  std::vector<int> place_;                 ///< per sphere in a cluster: its index among the members
  std::vector<std::vector<int>> members_;  ///< per cluster id; empty if unused
  std::vector<int> unused_;                ///< cluster ids free for reuse
  std::int64_t joins_ = 0, joined_spheres_ = 0, departures_ = 0;
};

}  // namespace pdamp::hard
