#include "pdamp/soft/neighbour_list.hpp"

#include <algorithm>
#include <array>

namespace pdamp::soft {

void NeighbourList::rebuild(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& radii) {
  const int n = static_cast<int>(positions.size());
  cell_positions_.resize(3, n);
  for (int i = 0; i < n; ++i) cell_positions_.col(i) = positions[i];
  cells_.build(grid_, cell_positions_);

  next_first_.assign(n + 1, 0);
  next_partner_.clear();
  next_history_.clear();
  std::array<int, 27> cells{};
  for (int i = 0; i < n; ++i) {
    next_first_[i] = static_cast<int>(next_partner_.size());
    const int count = grid_.neighbours(grid_.coord_of(positions[i]), cells);
    for (int c = 0; c < count; ++c) {
      for (const int j : cells_.particles_in(cells[c])) {
        if (j <= i) continue;
        const double reach = radii[i] + radii[j] + skin_m_;
        if ((positions[i] - positions[j]).squaredNorm() < reach * reach) next_partner_.push_back(j);
      }
    }
    const auto begin = next_partner_.begin() + next_first_[i];
    std::sort(begin, next_partner_.end());
    // Hand over the histories of pairs listed before (both lists are sorted by partner).
    int old = first_.empty() ? 0 : first_[i];
    const int old_end = first_.empty() ? 0 : first_[i + 1];
    for (auto it = begin; it != next_partner_.end(); ++it) {
      while (old < old_end && partner_[old] < *it) ++old;
      next_history_.push_back(old < old_end && partner_[old] == *it ? history_[old] : ContactHistory{});
    }
  }
  next_first_[n] = static_cast<int>(next_partner_.size());
  first_.swap(next_first_);
  partner_.swap(next_partner_);
  history_.swap(next_history_);
  ++rebuilds_;
}

}  // namespace pdamp::soft
