#include "pdamp/soft/neighbour_list.hpp"

#include <algorithm>
#include <array>

#include "pdamp/soft/contact_table.hpp"

namespace pdamp::soft {

void NeighbourList::rebuild(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& radii) {
  const int n = static_cast<int>(positions.size());
  // The positions seen as a 3 × n matrix, without a copy (a Vector3d is three doubles).
  cells_.build(grid_, Eigen::Map<const Eigen::Matrix3Xd>(n > 0 ? positions.front().data() : nullptr, 3, n));

  // Only the open contacts are set aside to be handed over.
  kept_first_.assign(n + 1, 0);
  kept_.clear();
  const int listed = first_.empty() ? 0 : n;  // none before the first build
  for (int i = 0; i < listed; ++i) {
    kept_first_[i] = static_cast<int>(kept_.size());
    for (int k = first_[i]; k < first_[i + 1]; ++k) {
      if (contact_[k] != ContactTable::none) kept_.push_back({partner_[k], contact_[k]});
    }
  }
  std::fill(kept_first_.begin() + listed, kept_first_.end(), static_cast<int>(kept_.size()));

  first_.assign(n + 1, 0);
  partner_.clear();
  std::array<int, 27> cells{};
  for (int i = 0; i < n; ++i) {
    first_[i] = static_cast<int>(partner_.size());
    const int count = grid_.neighbours(grid_.coord_of(positions[i]), cells);
    for (int c = 0; c < count; ++c) {
      for (const int j : cells_.particles_in(cells[c])) {
        if (j <= i) continue;
        const double reach = radii[i] + radii[j] + skin_m_;
        if ((positions[i] - positions[j]).squaredNorm() < reach * reach) partner_.push_back(j);
      }
    }
  }
  first_[n] = static_cast<int>(partner_.size());
  owner_.resize(partner_.size());
  for (int i = 0; i < n; ++i) std::fill(owner_.begin() + first_[i], owner_.begin() + first_[i + 1], i);

  // Hand over: mark i's kept partners, look up the new pairs, unmark.
  contact_.assign(partner_.size(), ContactTable::none);
  old_slot_.assign(n, -1);
  for (int i = 0; i < n; ++i) {
    if (kept_first_[i] == kept_first_[i + 1]) continue;
    for (int s = kept_first_[i]; s < kept_first_[i + 1]; ++s) old_slot_[kept_[s].partner] = s;
    for (int k = first_[i]; k < first_[i + 1]; ++k) {
      const int s = old_slot_[partner_[k]];
      if (s < 0) continue;
      contact_[k] = kept_[s].contact;
    }
    for (int s = kept_first_[i]; s < kept_first_[i + 1]; ++s) old_slot_[kept_[s].partner] = -1;
  }

  ++rebuilds_;
}

}  // namespace pdamp::soft
