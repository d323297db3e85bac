#pragma once
/// Verlet neighbour list with a skin, built on the shared cell grid. Every pair closer
/// than r_i + r_j + skin is listed (half list: i < j), so no contact
/// can be missed until some sphere has moved more than skin/2 relative to the host since
/// the build — the engine rebuilds before that. Each listed pair carries the index of its
/// open contact in the owner's ContactTable (ContactTable::none if it has none), which a
/// rebuild hands over to the new list.

#include <Eigen/Core>
#include <vector>

#include "pdamp/model/cell_grid.hpp"

namespace pdamp::soft {

class NeighbourList {
 public:
  NeighbourList(const CellGrid& grid, double skin_m) : grid_(grid), skin_m_(skin_m) {}

  /// Lists the pairs within reach of `positions`, keeping the contacts of pairs that
  /// stay listed.
  void rebuild(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& radii);

  double skin_m() const { return skin_m_; }
  int size() const { return static_cast<int>(partner_.size()); }
  /// Pairs of particle i are [first(i), first(i + 1)).
  int first(int i) const { return first_[i]; }
  int owner(int k) const { return owner_[k]; }
  int partner(int k) const { return partner_[k]; }
  /// The open contact of pair k, or ContactTable::none.
  int& contact(int k) { return contact_[k]; }
  int contact(int k) const { return contact_[k]; }
  long long rebuilds() const { return rebuilds_; }

 private:
  CellGrid grid_;
  double skin_m_;
  CellList cells_;
  std::vector<int> first_, owner_, partner_, contact_;
  /// During a rebuild: the open contacts, by owner ([kept_first_[i], kept_first_[i + 1])
  /// for particle i), and where partner j of the current i is kept, or −1.
  struct KeptContact {
    int partner, contact;
  };
  std::vector<KeptContact> kept_;
  std::vector<int> kept_first_;
  std::vector<int> old_slot_;
  long long rebuilds_ = 0;
};

}  // namespace pdamp::soft
