#include <doctest/doctest.h>

#include <array>
#include <random>
#include <set>

#include "pdamp/model/cavity.hpp"
#include "pdamp/model/cell_grid.hpp"

using namespace pdamp;

TEST_CASE("cavity gaps and normals") {
  const Cavity cavity(CavitySettings{0.01, 0.02});
  const double host_z = 0.003;
  const Eigen::Vector3d p(0.003, 0.004, host_z + 0.0015);  // 5 mm from the axis
  const double r = 0.001;
  const WallGap side = cavity.side(p, r);
  CHECK(side.gap_m == doctest::Approx(0.005 - 0.005 - 0.001));
  CHECK(side.normal.isApprox(Eigen::Vector3d(-0.6, -0.8, 0.0)));
  CHECK(cavity.bottom(p, r, host_z).gap_m == doctest::Approx(0.0005));
  CHECK(cavity.bottom(p, r, host_z).normal == Eigen::Vector3d::UnitZ());
  CHECK(cavity.top(p, r, host_z).gap_m == doctest::Approx(0.02 - 0.0015 - 0.001));
  CHECK(cavity.top(p, r, host_z).normal == -Eigen::Vector3d::UnitZ());
  CHECK(cavity.clearance_m(p, r, host_z) == doctest::Approx(-0.001));
  CHECK(cavity.gap(Wall::bottom, p, r, host_z).gap_m == cavity.bottom(p, r, host_z).gap_m);
  // On the axis the side normal is still a unit vector.
  CHECK(cavity.side(Eigen::Vector3d(0, 0, 0.01), r).normal.norm() == doctest::Approx(1.0));
}

TEST_CASE("cells are at least as large as asked and tile the cross-section") {
  const CellGrid grid(0.005, 0.02464, 0.00088);
  CHECK(grid.cell_size_m() >= 0.00088);
  CHECK(grid.nx() * grid.cell_size_m() == doctest::Approx(0.01));
  CHECK(grid.nz() * grid.cell_size_m() >= 0.02464 + 2 * grid.cell_size_m());
  std::array<int, 27> cells{};
  const int n = grid.neighbours(grid.coord_of({0.0, 0.0, 0.01}), cells);
  CHECK(n == 27);
  CHECK(std::set<int>(cells.begin(), cells.begin() + n).size() == 27);
  // At a corner of the cross-section only 2 x 2 x 3 cells exist.
  CHECK(grid.neighbours(grid.coord_of({-0.0049, -0.0049, 0.01}), cells) == 12);
}

TEST_CASE("a cell's block is its 27 neighbours, wrapped in z, with a stand-in beyond the sides") {
  const CellGrid grid(0.005, 0.012, 0.0011);  // 9 x 9 cells across, 13 layers
  constexpr int outside = -7;
  for (int iz = -30; iz <= 30; ++iz) {
    for (int iy = 0; iy < grid.ny(); ++iy) {
      for (int ix = 0; ix < grid.nx(); ++ix) {
        std::array<int, 27> block{};
        grid.block({ix, iy, iz}, outside, block);
        int k = 0;
        for (int dz = -1; dz <= 1; ++dz) {
          for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx, ++k) {
              const bool inside = ix + dx >= 0 && ix + dx < grid.nx() && iy + dy >= 0 && iy + dy < grid.ny();
              CHECK(block[k] == (inside ? grid.index({ix + dx, iy + dy, iz + dz}) : outside));
            }
          }
        }
      }
    }
  }
}

TEST_CASE("the cell list finds every pair within one cell size, wherever the host is") {
  const double radius = 0.004, height = 0.006, cell = 0.0009;
  const CellGrid grid(radius, height, cell);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (double host_z : {0.0, -0.0137, 0.0213}) {
    Eigen::Matrix3Xd positions(3, 400);
    for (int i = 0; i < positions.cols(); ++i) {
      double x, y;
      do {
        x = radius * u(rng);
        y = radius * u(rng);
      } while (x * x + y * y > radius * radius);
      positions.col(i) << x, y, host_z + 0.5 * height * (1 + u(rng));
    }
    CellList list;
    list.build(grid, positions);
    std::set<std::pair<int, int>> found;
    std::array<int, 27> cells{};
    for (int i = 0; i < positions.cols(); ++i) {
      const int n = grid.neighbours(grid.coord_of(positions.col(i)), cells);
      for (int k = 0; k < n; ++k) {
        for (int j : list.particles_in(cells[k])) {
          if (j > i) found.insert({i, j});
        }
      }
    }
    std::size_t close_pairs = 0;
    for (int i = 0; i < positions.cols(); ++i) {
      for (int j = i + 1; j < positions.cols(); ++j) {
        if ((positions.col(i) - positions.col(j)).norm() <= grid.cell_size_m()) {
          ++close_pairs;
          CHECK(found.count({i, j}) == 1);
        }
      }
    }
    CHECK(close_pairs > 100);
    // Periodic z never pairs the bottom of the cavity with its top.
    for (const auto& [i, j] : found) CHECK(std::abs(positions(2, i) - positions(2, j)) < 2.01 * grid.cell_size_m());
  }
}
