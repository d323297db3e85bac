#pragma once
/// The cubic cells of the paper's "box" algorithm, shared by both engines.
///
/// The grid lives in the lab frame. In x and y it covers the cylinder's square
/// bounding box; in z it is periodic, with a period two cells longer than the cavity, so
/// it never needs rebuilding as the host moves, and spheres inside the cavity are in
/// neighbouring cells only when they are really within one cell of each other.
/// Cells are at least as large as the largest sphere, so a sphere can only touch spheres
/// whose centres lie in its own cell or the 26 around it.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <vector>

namespace pdamp {

struct CellCoord {
  int ix, iy;
  int iz;  ///< unwrapped: floor(z / cell size), any integer
};

class CellGrid {
 public:
  /// The most cells a grid may have: the hard engine keeps some 40 bytes a cell.
  static constexpr int max_cells = 1 << 24;
  /// The cells of the grid these arguments give (as a double: it may not fit an int).
  static double cell_count(double cavity_radius_m, double cavity_height_m, double min_cell_size_m);

  /// `min_cell_size_m` must be ≥ the largest sphere diameter; the cells are stretched
  /// to tile the cavity's cross-section exactly. Throws InputError for more than max_cells
  /// (a scenario's validation refuses such a cavity first, naming its keys).
  CellGrid(double cavity_radius_m, double cavity_height_m, double min_cell_size_m);

  double cell_size_m() const { return cell_m_; }
  int nx() const { return n_xy_; }
  int ny() const { return n_xy_; }
  int nz() const { return n_z_; }
  int cell_count() const { return n_xy_ * n_xy_ * n_z_; }

  CellCoord coord_of(const Eigen::Vector3d& p) const;
  /// Cells from `low` to `high` (each coordinate) that cover the box between two corners:
  /// every point of it lies in one of them, as coord_of places it. Perhaps a cell more at
  /// an end; by multiplication, cheaper than coord_of's division.
  struct Cover {
    CellCoord low, high;
  };
  Cover cover(const Eigen::Vector3d& low_m, const Eigen::Vector3d& high_m) const;
  int index(const CellCoord& c) const;
  /// index(c) for a layer within the first period (0 ≤ iz < nz), without wrapping it.
  int index_in_period(const CellCoord& c) const { return (c.iz * n_xy_ + c.iy) * n_xy_ + c.ix; }
  int cell_of(const Eigen::Vector3d& p) const { return index(coord_of(p)); }

  /// The distinct cells within one cell of `c` (itself included); returns how many.
  int neighbours(const CellCoord& c, std::array<int, 27>& out) const;
  /// The 3 × 3 × 3 cells around `c` (itself in the middle), x fastest, then y, then z;
  /// `outside` stands for those beyond the grid's sides in x or y.
  void block(const CellCoord& c, int outside, std::array<int, 27>& out) const;

  /// Lab-frame faces of a cell: x ∈ [x_lower(ix), x_lower(ix + 1)), likewise y and z.
  /// The outermost x and y cells extend to infinity (spheres may overlap the side wall).
  double x_lower_m(int ix) const { return -half_width_m_ + ix * cell_m_; }
  double z_lower_m(int iz) const { return iz * cell_m_; }

 private:
  int clamp_xy(double coordinate) const;
  /// A cell index in x or y from its unclamped quotient (floored), as clamp_xy clamps it.
  int clamp_cell(double cell) const {
    return cell > 0.0 ? (cell < n_xy_ - 1 ? static_cast<int>(cell) : n_xy_ - 1) : 0;  // NaN: 0
  }
  /// A layer index from its unclamped quotient (floored), as coord_of bounds it.
  static int clamp_layer(double layer) {
    constexpr double farthest_layer = 1 << 30;  // any layer index wraps to one of the grid's
    return layer > -farthest_layer ? (layer < farthest_layer ? static_cast<int>(layer) : 1 << 30) : -(1 << 30);
  }

  double half_width_m_;
  double cell_m_;
  double inverse_cell_1_m_;  ///< 1 / cell_m_
  int n_xy_;
  int n_z_;
  std::array<int, 27> block_offsets_;  ///< of the 27 cells of a block from its middle, where none wraps or is outside
};

// Inline: these run for every sphere at every neighbour-list build. A position that is
// not a number, or far off, still gives a cell of the grid: the engines stop on such a
// state, and nothing may read memory before they do.
inline int CellGrid::clamp_xy(double coordinate) const {
  return clamp_cell(std::floor((coordinate + half_width_m_) / cell_m_));
}

inline CellCoord CellGrid::coord_of(const Eigen::Vector3d& p) const {
  return {clamp_xy(p.x()), clamp_xy(p.y()), clamp_layer(std::floor(p.z() / cell_m_))};
}

inline CellGrid::Cover CellGrid::cover(const Eigen::Vector3d& low_m, const Eigen::Vector3d& high_m) const {
  // A product by the inverse is within some 10⁻¹⁴ of a cell of the quotient (grids hold at
  // most 2²⁴ cells): moving each end 10⁻⁹ of a cell outwards keeps every cell coord_of
  // gives a point of the box.
  constexpr double slack = 1e-9;
  const auto across = [&](double x, double outwards) {
    return clamp_cell(std::floor((x + half_width_m_) * inverse_cell_1_m_ + outwards));
  };
  const auto layer = [&](double z, double outwards) {
    return clamp_layer(std::floor(z * inverse_cell_1_m_ + outwards));
  };
  return {{across(low_m.x(), -slack), across(low_m.y(), -slack), layer(low_m.z(), -slack)},
          {across(high_m.x(), slack), across(high_m.y(), slack), layer(high_m.z(), slack)}};
}

inline int CellGrid::index(const CellCoord& c) const {
  const int remainder = c.iz % n_z_;  // one integer division: they are slow
  return index_in_period({c.ix, c.iy, remainder < 0 ? remainder + n_z_ : remainder});
}

// Always inlined: with a sphere–sphere collision working out both spheres' blocks, GCC
// keeps it out of line otherwise, and the call slows the hard gas (tools/bench/HISTORY.md).
[[gnu::always_inline]] inline void CellGrid::block(const CellCoord& c, int outside, std::array<int, 27>& out) const {
  // Most cells are inside in x and y, and their layers do not wrap: fixed offsets.
  const int remainder = c.iz % n_z_;
  const int iz = remainder < 0 ? remainder + n_z_ : remainder;
  const auto within = [](int k, int n) { return static_cast<unsigned>(k - 1) < static_cast<unsigned>(n - 2); };
  if (within(c.ix, n_xy_) && within(c.iy, n_xy_) && within(iz, n_z_)) {
    const int middle = (iz * n_xy_ + c.iy) * n_xy_ + c.ix;
    for (int k = 0; k < 27; ++k) out[k] = middle + block_offsets_[k];
    return;
  }
  // The three layers wrapped once, not each cell: integer divisions are slow.
  const int layer = iz * n_xy_ * n_xy_;
  const int layer_size = n_xy_ * n_xy_, period = n_z_ * layer_size;
  const std::array<int, 3> layers{layer == 0 ? period - layer_size : layer - layer_size, layer,
                                  layer + layer_size == period ? 0 : layer + layer_size};
  std::array<int, 3> row_inside{}, column_inside{};  // ints: `&` of them is meant, without a branch
  for (int d = 0; d < 3; ++d) {
    row_inside[d] = c.iy - 1 + d >= 0 && c.iy - 1 + d < n_xy_;
    column_inside[d] = c.ix - 1 + d >= 0 && c.ix - 1 + d < n_xy_;
  }
  int k = 0;
  for (const int z_offset : layers) {
    for (int dy = 0; dy < 3; ++dy) {
      for (int dx = 0; dx < 3; ++dx) {
        const int cell = z_offset + (c.iy - 1 + dy) * n_xy_ + c.ix - 1 + dx;
        out[k++] = (row_inside[dy] & column_inside[dx]) != 0 ? cell : outside;
      }
    }
  }
}

inline int CellGrid::neighbours(const CellCoord& c, std::array<int, 27>& out) const {
  constexpr int outside = -1;
  block(c, outside, out);
  return static_cast<int>(std::remove(out.begin(), out.end(), outside) - out.begin());
}

/// Particles binned by cell with a counting sort: the particles of cell c are
/// `particles_in(c)`. Rebuilding reuses the arrays, so it does not allocate once warm.
class CellList {
 public:
  void build(const CellGrid& grid, const Eigen::Ref<const Eigen::Matrix3Xd>& positions);
  std::span<const int> particles_in(int cell) const {
    return {order_.data() + start_[cell], static_cast<std::size_t>(start_[cell + 1] - start_[cell])};
  }
  int cell_of_particle(int i) const { return cell_of_[i]; }

 private:
  std::vector<int> start_;    ///< size cell_count + 1
  std::vector<int> order_;    ///< particle indices grouped by cell
  std::vector<int> cell_of_;  ///< cell of each particle
  std::vector<int> scratch_;  ///< fill cursors of the counting sort
};

}  // namespace pdamp
