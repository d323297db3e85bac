#include "soft/neighbour_list.hpp"

#include <algorithm>
#include <numeric>

namespace pdamp::soft {

NeighbourList::NeighbourList(const CellGrid& grid, double skin_m) : grid_(grid), skin_m_(skin_m) {}

int NeighbourList::rank_of(double x, double y, double z) const {
  const CellCoord c = grid_.coord_of(Eigen::Vector3d(x, y, z));
  const int nz = grid_.nz();
  return rank(c.ix, c.iy, ((c.iz % nz) + nz) % nz);
}

const std::vector<int>& NeighbourList::sort_by_cell(const SphereBalls& balls) {
  const int n = balls.size();
  // A counting sort by cell rank.
  std::vector<int> rank_of_sphere(n);  // not kept: its memory serves the rest of the rebuild
  cell_first_.assign(grid_.cell_count() + 1, 0);
  for (int i = 0; i < n; ++i) {
    rank_of_sphere[i] = rank_of(balls[i].x, balls[i].y, balls[i].z);
    ++cell_first_[rank_of_sphere[i] + 1];
  }
  for (std::size_t r = 1; r < cell_first_.size(); ++r) cell_first_[r] += cell_first_[r - 1];
  order_.resize(n);
  for (int i = 0; i < n; ++i) order_[cell_first_[rank_of_sphere[i]]++] = i;
  // The fill cursors have moved each cell's start to the next cell's: shift them back.
  std::copy_backward(cell_first_.begin(), cell_first_.end() - 1, cell_first_.end());
  cell_first_.front() = 0;
  return order_;
}

void NeighbourList::start_build(int parts) {
  const int n = static_cast<int>(order_.size());
  first_.assign(n + 1, 0);
  // Parts of about n / parts spheres, each a run of whole cells.
  part_cell_.resize(parts + 1);
  for (int p = 0; p < parts; ++p) {
    part_cell_[p] = static_cast<int>(std::lower_bound(cell_first_.begin(), cell_first_.end() - 1, n * p / parts) -
                                     cell_first_.begin());
  }
  part_cell_[parts] = grid_.cell_count();
  part_pairs_.assign(parts, 0);
  more_partners_.resize(parts - 1);
}

void NeighbourList::finish_build() {
  const int n = static_cast<int>(order_.size()), parts = static_cast<int>(part_pairs_.size());
  int pairs = part_pairs_[0];
  pairs_.resize(std::reduce(part_pairs_.begin(), part_pairs_.end()) + padding);
  for (int p = 1; p < parts; ++p) {
    for (int i = cell_first_[part_cell_[p]]; i < cell_first_[part_cell_[p + 1]]; ++i) first_[i] += pairs;
    std::copy_n(more_partners_[p - 1].begin(), part_pairs_[p], pairs_.begin() + pairs);
    pairs += part_pairs_[p];
  }
  first_[n] = pairs;
  for (int i = 0; i < n; ++i) {
    for (int k = first_[i]; k < first_[i + 1]; ++k) pairs_[k] = pairs_[k] << group_bits | (i & (group_size - 1));
  }
  std::fill(pairs_.begin() + pairs, pairs_.end(), 0);
  contact_.assign(pairs + padding, ContactTable::none);
  ++rebuilds_;
}

}  // namespace pdamp::soft
