#include "pdamp/soft/neighbour_list.hpp"

#include <array>

namespace pdamp::soft {

void NeighbourList::rebuild(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& radii) {
  const int n = static_cast<int>(positions.size());
  cell_positions_.resize(3, n);
  for (int i = 0; i < n; ++i) cell_positions_.col(i) = positions[i];
  cells_.build(grid_, cell_positions_);

  next_first_.assign(n + 1, 0);
  old_slot_.assign(n, -1);
  next_partner_.clear();
  next_history_.clear();
  next_touching_.clear();
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
    // Hand over the histories of pairs listed before: mark i's old partners, look up the new.
    if (!first_.empty()) {
      for (int k = first_[i]; k < first_[i + 1]; ++k) old_slot_[partner_[k]] = k;
    }
    for (int k = next_first_[i]; k < static_cast<int>(next_partner_.size()); ++k) {
      const int old = old_slot_[next_partner_[k]];
      next_history_.push_back(old >= 0 ? history_[old] : ContactHistory{});
      next_touching_.push_back(old >= 0 ? touching_[old] : 0);
    }
    if (!first_.empty()) {
      for (int k = first_[i]; k < first_[i + 1]; ++k) old_slot_[partner_[k]] = -1;
    }
  }
  next_first_[n] = static_cast<int>(next_partner_.size());
  first_.swap(next_first_);
  partner_.swap(next_partner_);
  history_.swap(next_history_);
  touching_.swap(next_touching_);

  // The slots by partner, by a counting sort on the partners (stable: pairs ascending).
  reverse_first_.assign(n + 1, 0);
  for (const int j : partner_) ++reverse_first_[j + 1];
  for (int j = 0; j < n; ++j) reverse_first_[j + 1] += reverse_first_[j];
  partner_slot_.resize(partner_.size());
  old_slot_.assign(reverse_first_.begin(), reverse_first_.end() - 1);  // reused as fill cursors
  for (int k = 0; k < static_cast<int>(partner_.size()); ++k) partner_slot_[k] = old_slot_[partner_[k]]++;
  ++rebuilds_;
}

}  // namespace pdamp::soft
