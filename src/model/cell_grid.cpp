#include "pdamp/model/cell_grid.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "pdamp/errors.hpp"

namespace pdamp {

namespace {

/// Cells across the cavity in x and y, and their size (cubes tiling the cross-section).
struct Tiling {
  double across, cell_m;
  Tiling(double cavity_radius_m, double min_cell_size_m)
      : across(std::max(1.0, std::floor(2.0 * cavity_radius_m / min_cell_size_m))),
        cell_m(2.0 * cavity_radius_m / across) {}
  // Two spare cells beyond the cavity's height keep the periodic images of the cavity's
  // top and bottom layers out of each other's neighbourhood; at least 3 keeps the 27
  // neighbours distinct.
  double layers(double cavity_height_m) const { return std::max(3.0, std::ceil(cavity_height_m / cell_m) + 2.0); }
};

}  // namespace

double CellGrid::cell_count(double cavity_radius_m, double cavity_height_m, double min_cell_size_m) {
  const Tiling t(cavity_radius_m, min_cell_size_m);
  return t.across * t.across * t.layers(cavity_height_m);
}

CellGrid::CellGrid(double cavity_radius_m, double cavity_height_m, double min_cell_size_m)
    : half_width_m_(cavity_radius_m) {
  if (!(cell_count(cavity_radius_m, cavity_height_m, min_cell_size_m) <= max_cells)) {
    throw InputError("a cavity of diameter " + std::to_string(2.0 * cavity_radius_m) + " m and height " +
                     std::to_string(cavity_height_m) + " m holds more than " + std::to_string(max_cells) +
                     " cells of " + std::to_string(min_cell_size_m) + " m");
  }
  const Tiling t(cavity_radius_m, min_cell_size_m);
  n_xy_ = static_cast<int>(t.across);
  cell_m_ = t.cell_m;
  inverse_cell_1_m_ = 1.0 / cell_m_;
  n_z_ = static_cast<int>(t.layers(cavity_height_m));
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
