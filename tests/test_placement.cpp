#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "pdamp/errors.hpp"
#include "pdamp/model/cavity.hpp"
#include "pdamp/model/placement.hpp"

using namespace pdamp;

namespace {

void check_valid(const Particles& p, const CavitySettings& cavity_settings, double host_z) {
  const Cavity cavity(cavity_settings);
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    REQUIRE(cavity.clearance_m(p.position_m.col(i), p.radius_m[i], host_z) >= 0.0);
    for (Eigen::Index j = i + 1; j < p.size(); ++j) {
      REQUIRE((p.position_m.col(i) - p.position_m.col(j)).norm() >= p.radius_m[i] + p.radius_m[j]);
    }
  }
}

}  // namespace

TEST_CASE("placement: Table 1 fill, inside the cavity, no overlaps, reproducible") {
  const ParticleSettings settings{1246, 0.00088, 0.00088, 9000, 42};
  const CavitySettings cavity{0.0254, 0.00704};
  const Particles a = place_particles(settings, cavity, 0.0157);
  CHECK(a.size() == 1246);
  check_valid(a, cavity, 0.0157);
  CHECK(a.total_mass_kg() ==
        doctest::Approx(1246 * 9000 * 3.14159265358979 / 6 * 0.00088 * 0.00088 * 0.00088).scale(0.0));
  CHECK(a.velocity_m_s.isZero());
  const Particles again = place_particles(settings, cavity, 0.0157);
  CHECK(again.position_m == a.position_m);
  ParticleSettings other = settings;
  other.seed = 43;
  CHECK(place_particles(other, cavity, 0.0157).position_m != a.position_m);
}

TEST_CASE("placement: dense Table 4 fill (37 % solid) and polydisperse spheres") {
  const CavitySettings cavity{0.01, 0.012};
  const Particles dense = place_particles({386, 0.0012, 0.0012, 3840, 1}, cavity, 0.0);
  check_valid(dense, cavity, 0.0);
  const Particles mixed = place_particles({300, 0.0008, 0.0012, 3840, 5}, cavity, -0.002);
  check_valid(mixed, cavity, -0.002);
  CHECK(mixed.radius_m.minCoeff() < mixed.radius_m.maxCoeff());
}

TEST_CASE("placement: too many spheres is an input error that says how many fit") {
  const CavitySettings cavity{0.01, 0.012};
  const int capacity = max_particles_that_fit(cavity, 0.0012);
  CHECK(capacity >= 386);
  CHECK_NOTHROW(place_particles({capacity, 0.0012, 0.0012, 3840, 1}, cavity, 0.0));
  try {
    place_particles({capacity + 1, 0.0012, 0.0012, 3840, 1}, cavity, 0.0);
    FAIL("expected InputError");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("at most " + std::to_string(capacity)) != std::string::npos);
  }
  CHECK(place_particles({0, 0.0012, 0.0012, 3840, 1}, cavity, 0.0).size() == 0);
}

// A range of diameters was counted as if every sphere had the largest: 100 spheres of 1 to
// 2 mm, 17 % of this cavity's volume, were refused. Beyond the lattice for the largest they
// are stacked by their own sizes; what does not fit so is refused, naming how many do.
TEST_CASE("placement: a range of diameters beyond the lattice for the largest is stacked by size") {
  const CavitySettings cavity{0.012, 0.010};
  const ParticleSettings settings{100, 0.001, 0.002, 7800, 3};
  REQUIRE(max_particles_that_fit(cavity, 0.002) < 100);
  CHECK(particles_that_fit(settings, cavity) == 100);
  const Particles p = place_particles(settings, cavity, 0.0157);
  REQUIRE(p.size() == 100);
  check_valid(p, cavity, 0.0157);
  CHECK(p.radius_m.minCoeff() >= 0.0005);
  CHECK(p.radius_m.maxCoeff() <= 0.001);
  CHECK(solid_fraction(cavity, p) > 0.15);
  CHECK(place_particles(settings, cavity, 0.0157).position_m == p.position_m);
  // The most that stack: 210, 36 % of the volume (99 spheres of 2 mm, the lattice's, 37 %).
  const ParticleSettings dense{210, 0.001, 0.002, 7800, 3};
  REQUIRE(particles_that_fit(dense, cavity) == 210);
  const Particles q = place_particles(dense, cavity, 0.0);
  check_valid(q, cavity, 0.0);
  CHECK(solid_fraction(cavity, q) > 0.36);
  // More are refused, naming how many fit; so are more than the cavity holds at the
  // smallest diameter.
  for (const int count : {230, 3000}) {
    CAPTURE(count);
    const ParticleSettings many{count, 0.001, 0.002, 7800, 3};
    CHECK(particles_that_fit(many, cavity) == 210);
    try {
      place_particles(many, cavity, 0.0);
      FAIL("expected InputError");
    } catch (const InputError& e) {
      CHECK(std::string(e.what()).find("at most 210 spheres of diameters from 0.001 to 0.002 m can be placed") !=
            std::string::npos);
    }
  }
}

TEST_CASE("overlapping spheres are separated from each other and from the walls") {
  const CavitySettings cavity{0.008, 0.008};
  Particles p(3);
  p.radius_m.setConstant(0.0005);
  p.mass_kg.setConstant(1e-6);
  p.position_m.col(0) << 0.0, 0.0, 0.0005 - 3e-6;   // into the floor
  p.position_m.col(1) << 0.00099, 0.0, 0.0005;      // 10 um into sphere 0
  p.position_m.col(2) << 0.00099, 0.00099, 0.0005;  // and into sphere 1
  const double moved = separate_overlaps(p, cavity, 0.0);
  check_valid(p, cavity, 0.0);
  CHECK(moved > 4e-6);
  CHECK(moved < 3e-5);
}

TEST_CASE("a deep bed's overlaps, which add up along its columns, are separated") {
  // Columns of 40 spheres, each 1 % of a radius into the one below and the lowest into the
  // floor, as a settled soft bed under its own weight: the whole column must rise by 40 x
  // that overlap. Table 2's settled bed is such a case.
  const CavitySettings cavity{0.01, 0.05};
  const double r = 0.0005, overlap = 0.01 * r;
  Particles p(80);
  p.radius_m.setConstant(r);
  p.mass_kg.setConstant(1e-6);
  for (int k = 0; k < 40; ++k) {
    const double z = r - overlap + k * (2 * r - overlap);
    p.position_m.col(k) << -0.001, 0.0, z;
    p.position_m.col(40 + k) << 0.001 - overlap, 0.0, z;  // and 1 % into its neighbour column
  }
  const double moved = separate_overlaps(p, cavity, 0.0);
  check_valid(p, cavity, 0.0);
  CHECK(moved >= 40 * overlap);
  CHECK(moved < 0.05 * r * 40);
}

TEST_CASE("a bed pressed against the lid or the side wall is separated against its gravity") {
  // The columns of the deep bed above, hanging from the lid (gravity upwards) or lying
  // against the side wall (gravity along x): separated from that wall outwards.
  const CavitySettings cavity{0.01, 0.05};
  const double r = 0.0005, overlap = 0.01 * r;
  for (const Eigen::Vector3d& up : {Eigen::Vector3d(0.0, 0.0, -1.0), Eigen::Vector3d(-1.0, 0.0, 0.0)}) {
    CAPTURE(up.transpose());
    Particles p(16);
    p.radius_m.setConstant(r);
    p.mass_kg.setConstant(1e-6);
    for (int k = 0; k < 8; ++k) {
      const double h = r - overlap + k * (2 * r - overlap);  // from the wall the bed rests on
      const double across = 0.002 - overlap;                 // the neighbour column, 1 % into it
      if (up.z() < 0.0) {
        p.position_m.col(k) << -0.001, 0.0, cavity.height_m - h;
        p.position_m.col(8 + k) << -0.001 + across, 0.0, cavity.height_m - h;
      } else {
        p.position_m.col(k) << cavity.diameter_m / 2 - h, 0.0, 0.01;
        p.position_m.col(8 + k) << cavity.diameter_m / 2 - h, 0.0, 0.01 + across;
      }
    }
    const double moved = separate_overlaps(p, cavity, 0.0, up);
    check_valid(p, cavity, 0.0);
    CHECK(moved >= 8 * overlap);
    CHECK(moved < 0.05 * r * 8);
  }
}

namespace {

/// The lattice's sites as first written, visited one by one: the reference for the
/// counts max_particles_that_fit makes without listing them.
int sites_one_by_one(const CavitySettings& cavity, double diameter_m) {
  const double radius_m = diameter_m / 2.0 + 1e-12 * std::max(cavity.diameter_m, cavity.height_m);
  const double spacing_m = 2.0 * radius_m;
  const double reach = cavity.radius_m() - radius_m;
  const double layer_gap = spacing_m * std::sqrt(2.0 / 3.0);
  const double row_gap = spacing_m * std::sqrt(3.0) / 2.0;
  if (reach < 0) return 0;
  const int half_rows = static_cast<int>(std::ceil(reach / row_gap)) + 1;
  const int half_cols = static_cast<int>(std::ceil(reach / spacing_m)) + 1;
  int sites = 0, layer = 0;
  for (double z = radius_m; z <= cavity.height_m - radius_m; z = radius_m + (++layer) * layer_gap) {
    const double shift_x = (layer % 2) * spacing_m / 2.0, shift_y = (layer % 2) * row_gap / 3.0;
    for (int row = -half_rows; row <= half_rows; ++row) {
      const double y = row * row_gap + shift_y;
      const double row_shift = (std::abs(row) % 2) * spacing_m / 2.0;
      for (int col = -half_cols; col <= half_cols; ++col) {
        sites += std::hypot(col * spacing_m + row_shift + shift_x, y) <= reach;
      }
    }
  }
  return sites;
}

}  // namespace

TEST_CASE("placement: capacities are counted row by row, as many as the lattice has sites") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> across(1.05, 40.0), tall(1.05, 25.0);
  for (int k = 0; k < 300; ++k) {
    const double d = 0.001;
    const CavitySettings cavity{across(rng) * d, tall(rng) * d};
    CAPTURE(cavity.diameter_m);
    CAPTURE(cavity.height_m);
    const int capacity = max_particles_that_fit(cavity, d);
    REQUIRE(capacity == sites_one_by_one(cavity, d));
    if (k % 30 == 0 && capacity > 0) {
      check_valid(place_particles({capacity, d, d, 9000, 1}, cavity, 0.0), cavity, 0.0);
    }
  }
}

TEST_CASE("placement: a vast cavity is counted in bounded time, and a few spheres placed in it") {
  const auto start = std::chrono::steady_clock::now();
  for (const CavitySettings cavity :
       {CavitySettings{1e6, 1e6}, CavitySettings{0.002, 1e6}, CavitySettings{1e6, 0.0015}}) {
    CHECK(max_particles_that_fit(cavity, 0.001) == max_particle_count);
  }
  CHECK(max_particles_that_fit({1e300, 1e300}, 0.001) == max_particle_count);
  const CavitySettings room{10.0, 3.0};
  check_valid(place_particles({50, 0.001, 0.001, 9000, 1}, room, 0.0), room, 0.0);
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(2));
}
