#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <random>
#include <set>
#include <utility>

#include "pdamp/model/cavity.hpp"
#include "pdamp/model/cell_grid.hpp"

using namespace pdamp;

TEST_CASE("cavity gaps and normals") {
  const Cavity cavity(CavitySettings{0.01, 0.02});
  const double host_z = 0.003;
  const Eigen::Vector3d p(0.003, 0.004, host_z + 0.0015);  // 5 mm from the axis
  const double r = 0.001;
  const WallGap side = cavity.side(p, r);
  CHECK(side.gap_m == doctest::Approx(0.005 - 0.005 - 0.001).scale(0.0));
  CHECK(side.normal.isApprox(Eigen::Vector3d(-0.6, -0.8, 0.0)));
  CHECK(cavity.bottom(p, r, host_z).gap_m == doctest::Approx(0.0005).scale(0.0));
  CHECK(cavity.bottom(p, r, host_z).normal == Eigen::Vector3d::UnitZ());
  CHECK(cavity.top(p, r, host_z).gap_m == doctest::Approx(0.02 - 0.0015 - 0.001).scale(0.0));
  CHECK(cavity.top(p, r, host_z).normal == -Eigen::Vector3d::UnitZ());
  CHECK(cavity.clearance_m(p, r, host_z) == doctest::Approx(-0.001).scale(0.0));
  CHECK(cavity.gap(Wall::bottom, p, r, host_z).gap_m == cavity.bottom(p, r, host_z).gap_m);
  // On the axis the side normal is still a unit vector.
  CHECK(cavity.side(Eigen::Vector3d(0, 0, 0.01), r).normal.norm() == doctest::Approx(1.0).scale(1.0));
}

TEST_CASE("cells are at least as large as asked and tile the cross-section") {
  const CellGrid grid(0.005, 0.02464, 0.00088);
  CHECK(grid.cell_size_m() >= 0.00088);
  CHECK(grid.nx() * grid.cell_size_m() == doctest::Approx(0.01).scale(0.0));
  CHECK(grid.nz() * grid.cell_size_m() >= 0.02464 + 2 * grid.cell_size_m());
  std::array<int, 27> cells{};
  const int n = grid.neighbours(grid.coord_of({0.0, 0.0, 0.01}), cells);
  CHECK(n == 27);
  CHECK(std::set<int>(cells.begin(), cells.begin() + n).size() == 27);
  // At a corner of the cross-section only 2 x 2 x 3 cells exist.
  CHECK(grid.neighbours(grid.coord_of({-0.0049, -0.0049, 0.01}), cells) == 12);
}

TEST_CASE("a box's cells cover every point of it as coord_of places it, and at most a cell more at an end") {
  // Cells of 1/300 m, where some heights an ulp from a face are in one layer by
  // division and in the next by the inverse.
  const CellGrid grid(0.005, 0.012, 0.003);
  const auto within = [](const CellCoord& c, const CellGrid::Cover& cover) {
    return cover.low.ix <= c.ix && c.ix <= cover.high.ix && cover.low.iy <= c.iy && c.iy <= cover.high.iy &&
           cover.low.iz <= c.iz && c.iz <= cover.high.iz;
  };
  const auto tight = [&](const Eigen::Vector3d& low, const Eigen::Vector3d& high, const CellGrid::Cover& cover) {
    const CellCoord a = grid.coord_of(low), b = grid.coord_of(high);
    return cover.low.ix >= a.ix - 1 && cover.low.iy >= a.iy - 1 && cover.low.iz >= a.iz - 1 &&
           cover.high.ix <= b.ix + 1 && cover.high.iy <= b.iy + 1 && cover.high.iz <= b.iz + 1;
  };
  // Corners on the cells' faces and a few ulps either side, where a product by the
  // inverse and a quotient can round to different sides of a whole number.
  int checked = 0, failed = 0, rounded_apart = 0;
  for (int k = 0; k <= 40; ++k) {
    for (int step = -3; step <= 3; ++step) {
      double x = grid.x_lower_m(k % (grid.nx() + 1)), z = grid.z_lower_m(k);
      for (int n = 0; n < std::abs(step); ++n) {
        x = std::nextafter(x, step > 0 ? 1.0 : -1.0);
        z = std::nextafter(z, step > 0 ? 1.0 : -1.0);
      }
      const Eigen::Vector3d corner(x, x, z);
      rounded_apart += std::floor(z / grid.cell_size_m()) != std::floor(z * (1.0 / grid.cell_size_m()));
      const Eigen::Vector3d reach = Eigen::Vector3d::Constant(3e-4);
      using Box = std::pair<Eigen::Vector3d, Eigen::Vector3d>;
      for (const auto& [low, high] : {Box{corner, corner}, Box{corner - reach, corner}, Box{corner, corner + reach}}) {
        const CellGrid::Cover cover = grid.cover(low, high);
        failed += !within(grid.coord_of(low), cover) || !within(grid.coord_of(high), cover) || !tight(low, high, cover);
        ++checked;
      }
    }
  }
  CHECK(rounded_apart > 0);
  CHECK(failed == 0);
  // Random boxes and points in them.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> across(-0.006, 0.006), up(-0.002, 0.014), size(0.0, 0.003);
  for (int k = 0; k < 2000; ++k) {
    const Eigen::Vector3d low(across(rng), across(rng), up(rng));
    const Eigen::Vector3d high = low + Eigen::Vector3d(size(rng), size(rng), size(rng));
    const CellGrid::Cover cover = grid.cover(low, high);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int j = 0; j < 4; ++j) {
      const Eigen::Vector3d p = low + (high - low).cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
      failed += !within(grid.coord_of(p), cover);
    }
    failed += !within(grid.coord_of(low), cover) || !within(grid.coord_of(high), cover) || !tight(low, high, cover);
    ++checked;
  }
  CHECK(failed == 0);
  CHECK(checked > 2000);
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
