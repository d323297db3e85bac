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
}

int CellGrid::clamp_xy(double coordinate) const {
  const double cell = std::floor((coordinate + half_width_m_) / cell_m_);
  return static_cast<int>(std::clamp(cell, 0.0, static_cast<double>(n_xy_ - 1)));
}

CellCoord CellGrid::coord_of(const Eigen::Vector3d& p) const {
  return {clamp_xy(p.x()), clamp_xy(p.y()), static_cast<int>(std::floor(p.z() / cell_m_))};
}

int CellGrid::index(const CellCoord& c) const {
  const int iz = ((c.iz % n_z_) + n_z_) % n_z_;
  return (iz * n_xy_ + c.iy) * n_xy_ + c.ix;
}

int CellGrid::neighbours(const CellCoord& c, std::array<int, 27>& out) const {
  int count = 0;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int iy = std::max(0, c.iy - 1); iy <= std::min(n_xy_ - 1, c.iy + 1); ++iy) {
      for (int ix = std::max(0, c.ix - 1); ix <= std::min(n_xy_ - 1, c.ix + 1); ++ix) {
        out[count++] = index({ix, iy, c.iz + dz});
      }
    }
  }
  return count;
}

void CellList::build(const CellGrid& grid, const Eigen::Matrix3Xd& positions) {
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
