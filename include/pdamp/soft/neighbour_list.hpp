#pragma once
/// Verlet neighbour list with a skin, built on the shared cell grid. Every pair closer
/// than r_i + r_j + skin is listed (half list: i < j), so no contact
/// can be missed until some sphere has moved more than skin/2 relative to the host since
/// the build — the engine rebuilds before that. Each listed pair carries its contact
/// history, which a rebuild hands over to the new list.

#include <Eigen/Core>
#include <vector>

#include "pdamp/model/cell_grid.hpp"
#include "pdamp/soft/contact_law.hpp"

namespace pdamp::soft {

class NeighbourList {
 public:
  NeighbourList(const CellGrid& grid, double skin_m) : grid_(grid), skin_m_(skin_m) {}

  /// Lists the pairs within reach of `positions`, keeping the histories of pairs that
  /// stay listed.
  void rebuild(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& radii);

  double skin_m() const { return skin_m_; }
  int size() const { return static_cast<int>(partner_.size()); }
  /// Pairs of particle i are [first(i), first(i + 1)).
  int first(int i) const { return first_[i]; }
  int partner(int k) const { return partner_[k]; }
  /// The pairs grouped by partner: those in which particle j is the partner take the
  /// slots [partner_first(j), partner_first(j + 1)), in ascending pair order; pair k takes
  /// slot partner_slot(k). (A per-pair quantity stored by slot is gathered per partner
  /// from contiguous memory.)
  int partner_first(int j) const { return reverse_first_[j]; }
  int partner_slot(int k) const { return partner_slot_[k]; }
  ContactHistory<>& history(int k) { return history_[k]; }
  /// Whether pair k was touching after the last force computation.
  bool touching(int k) const { return touching_[k] != 0; }
  void set_touching(int k, bool touching) { touching_[k] = touching; }
  long long rebuilds() const { return rebuilds_; }

 private:
  CellGrid grid_;
  double skin_m_;
  CellList cells_;
  Eigen::Matrix3Xd cell_positions_;
  std::vector<int> first_, partner_;
  std::vector<ContactHistory<>> history_;
  std::vector<unsigned char> touching_;
  /// During a rebuild: the touching pairs' histories, by owner ([kept_first_[i],
  /// kept_first_[i + 1]) for particle i), and where partner j of the current i is kept, or −1.
  struct KeptHistory {
    int partner;
    ContactHistory<> history;
  };
  std::vector<KeptHistory> kept_;
  std::vector<int> kept_first_;
  std::vector<int> old_slot_;
  std::vector<int> reverse_first_, partner_slot_;
  long long rebuilds_ = 0;
};

}  // namespace pdamp::soft
