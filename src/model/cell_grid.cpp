#include "pdamp/model/cell_grid.hpp"

#include <algorithm>
#include <cmath>

namespace pdamp {

CellGrid::CellGrid(double cavity_radius_m, double cavity_height_m, double min_cell_size_m)
    : half_width_m_(cavity_radius_m) {
  n_xy_ = std::max(1, static_cast<int>(std::floor(2.0 * cavity_radius_m / min_cell_size_m)));
  cell_m_ = 2.0 * cavity_radius_m / n_xy_;
  // Two spare cells beyond the cavity's height keep the periodic images of the cavity's
  // top and bottom layers out of each other's neighbourhood; at least 3 keeps the 27
  // neighbours distinct.
  n_z_ = std::max(3, static_cast<int>(std::ceil(cavity_height_m / cell_m_)) + 2);
  int k = 0;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) block_offsets_[k++] = (dz * n_xy_ + dy) * n_xy_ + dx;
    }
  }
}

void CellList::build(const CellGrid& grid, const Eigen::Ref<const Eigen::Matrix3Xd>& positions) {
  const auto n = static_cast<int>(positions.cols());
  start_.assign(grid.cell_count() + 1, 0);
  cell_of_.resize(n);
  order_.resize(n);
  for (int i = 0; i < n; ++i) {
    cell_of_[i] = grid.cell_of(positions.col(i));
    ++start_[cell_of_[i] + 1];
  }
  for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  scratch_.assign(start_.begin(), start_.end() - 1);
  for (int i = 0; i < n; ++i) order_[scratch_[cell_of_[i]]++] = i;
}

}  // namespace pdamp
