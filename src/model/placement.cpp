#include "pdamp/model/placement.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <sstream>
#include <vector>

#include "pdamp/errors.hpp"
#include "pdamp/model/cavity.hpp"
#include "pdamp/model/cell_grid.hpp"

namespace pdamp {
namespace {

/// Centres of a hexagonal close-packed lattice of spacing `spacing_m` that keep a sphere
/// of radius `radius_m` inside the cavity (cavity frame: bottom centre at the origin).
std::vector<Eigen::Vector3d> lattice_sites(const CavitySettings& cavity, double radius_m, double spacing_m) {
  std::vector<Eigen::Vector3d> sites;
  const double reach = cavity.radius_m() - radius_m;  // how far from the axis a centre may be
  const double layer_gap = spacing_m * std::sqrt(2.0 / 3.0);
  const double row_gap = spacing_m * std::sqrt(3.0) / 2.0;
  if (reach < 0) return sites;
  const int half_rows = static_cast<int>(std::ceil(reach / row_gap)) + 1;
  const int half_cols = static_cast<int>(std::ceil(reach / spacing_m)) + 1;
  int layer = 0;
  for (double z = radius_m; z <= cavity.height_m - radius_m; z = radius_m + (++layer) * layer_gap) {
    // Alternate layers sit over the hollows of the one below (A, B, A, ... stacking).
    const double shift_x = (layer % 2) * spacing_m / 2.0, shift_y = (layer % 2) * row_gap / 3.0;
    for (int row = -half_rows; row <= half_rows; ++row) {
      const double y = row * row_gap + shift_y;
      const double row_shift = (std::abs(row) % 2) * spacing_m / 2.0;
      for (int col = -half_cols; col <= half_cols; ++col) {
        const double x = col * spacing_m + row_shift + shift_x;
        if (std::hypot(x, y) <= reach) sites.emplace_back(x, y, z);
      }
    }
  }
  return sites;
}

/// A point in the unit ball, uniformly.
Eigen::Vector3d random_in_ball(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (;;) {
    const Eigen::Vector3d p(unit(rng), unit(rng), unit(rng));
    if (p.squaredNorm() <= 1.0) return p;
  }
}

/// Moves a centre back inside the cavity region allowed for a sphere of this radius.
/// The region is convex and contains the lattice site, so this never moves the centre
/// further from its site.
Eigen::Vector3d project_into_cavity(Eigen::Vector3d p, const CavitySettings& cavity, double radius_m) {
  const double reach = cavity.radius_m() - radius_m;
  const double rho = std::hypot(p.x(), p.y());
  if (rho > reach) {
    p.x() *= reach / rho;
    p.y() *= reach / rho;
  }
  p.z() = std::clamp(p.z(), radius_m, cavity.height_m - radius_m);
  return p;
}

/// Spheres are placed as if a hair larger, so that rounding (and adding the host's
/// displacement) never leaves one touching a wall or a neighbour.
double padded_radius(const CavitySettings& cavity, double radius_m) {
  return radius_m + 1e-12 * std::max(cavity.diameter_m, cavity.height_m);
}

}  // namespace

int max_particles_that_fit(const CavitySettings& cavity, double diameter_m) {
  const double r = padded_radius(cavity, diameter_m / 2.0);
  return static_cast<int>(lattice_sites(cavity, r, 2.0 * r).size());
}

double solid_fraction(const CavitySettings& cavity, const Particles& particles) {
  const double spheres_m3 = 4.0 / 3.0 * std::numbers::pi * particles.radius_m.array().cube().sum();
  return spheres_m3 / (std::numbers::pi * cavity.radius_m() * cavity.radius_m() * cavity.height_m);
}

void check_particles_fit(const ParticleSettings& settings, const CavitySettings& cavity) {
  const double d_max = settings.diameter_max_m;
  if (const int capacity = max_particles_that_fit(cavity, d_max); settings.count > capacity) {
    std::ostringstream msg;
    msg << "particles.count = " << settings.count << ": at most " << capacity << " spheres of diameter " << d_max
        << " m can be placed in the cavity";
    throw InputError(msg.str());
  }
}

Particles place_particles(const ParticleSettings& settings, const CavitySettings& cavity, double host_z_m) {
  check_particles_fit(settings, cavity);
  const int n = settings.count;
  const double d_max = settings.diameter_max_m;
  Particles particles(n);
  if (n == 0) return particles;

  // The widest lattice that still has a site for every sphere leaves the most room to
  // jitter. Site counts fall as the spacing grows (not strictly), so bisect on them.
  const double r_max = padded_radius(cavity, d_max / 2.0);
  double tight = 2.0 * r_max, loose = std::max(2.0 * cavity.radius_m(), cavity.height_m);
  for (int iteration = 0; iteration < 60; ++iteration) {
    const double mid = 0.5 * (tight + loose);
    (static_cast<int>(lattice_sites(cavity, r_max, mid).size()) >= n ? tight : loose) = mid;
  }
  const double spacing = tight;
  std::vector<Eigen::Vector3d> sites = lattice_sites(cavity, r_max, spacing);

  std::mt19937_64 rng(settings.seed);
  std::shuffle(sites.begin(), sites.end(), rng);
  sites.resize(n);
  // Keep neighbours adjacent in memory: sort the chosen sites bottom-up, then by y and x.
  std::sort(sites.begin(), sites.end(), [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::tie(a.z(), a.y(), a.x()) < std::tie(b.z(), b.y(), b.x());
  });

  // Every centre stays within (spacing − 2 r_max)/2 of its site, so spheres never overlap.
  const double jitter = 0.5 * spacing - r_max;
  std::uniform_real_distribution<double> diameter(settings.diameter_min_m, settings.diameter_max_m);
  for (int i = 0; i < n; ++i) {
    const double d = settings.diameter_min_m == d_max ? d_max : diameter(rng);
    const double r = d / 2.0;
    const Eigen::Vector3d centre =
        project_into_cavity(sites[i] + jitter * random_in_ball(rng), cavity, padded_radius(cavity, r));
    particles.position_m.col(i) = centre + Eigen::Vector3d(0.0, 0.0, host_z_m);
    particles.radius_m[i] = r;
    particles.mass_kg[i] = settings.density_kg_m3 * std::numbers::pi / 6.0 * d * d * d;
  }
  return particles;
}

double separate_overlaps(Particles& particles, const CavitySettings& settings, double host_z_m) {
  const auto n = static_cast<int>(particles.size());
  if (n == 0) return 0.0;
  const Cavity cavity(settings);
  const Particles original = particles;
  // Push a hair beyond touching, so that rounding cannot leave a contact behind.
  const double margin = 1e-9 * particles.max_radius_m();
  const CellGrid grid(settings.radius_m(), settings.height_m, 2.0 * particles.max_radius_m() + 2.0 * margin);
  CellList cells;
  std::array<int, 27> neighbours{};
  std::vector<int> order(static_cast<std::size_t>(n)), rank(static_cast<std::size_t>(n));
  for (int sweep = 0; sweep < 1000; ++sweep) {
    bool moved = false;
    cells.build(grid, particles.position_m);
    // Bottom up, each sphere moves out of those it rests on (and out of the walls): a bed's
    // overlaps add up along its columns, and this lifts a whole column in one sweep, where
    // pushing pairs apart symmetrically passes them up one layer a sweep. Side by side
    // contacts are pushed apart half each, so that a sphere against the side wall can
    // move its neighbour rather than be pushed back into it.
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      const double za = particles.position_m(2, a), zb = particles.position_m(2, b);
      return za < zb || (za == zb && a < b);
    });
    for (int k = 0; k < n; ++k) rank[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] = k;
    for (const int i : order) {
      auto xi = particles.position_m.col(i);
      const int count = grid.neighbours(grid.coord_of(xi), neighbours);
      for (int c = 0; c < count; ++c) {
        for (const int j : cells.particles_in(neighbours[c])) {
          if (rank[static_cast<std::size_t>(j)] >= rank[static_cast<std::size_t>(i)]) continue;
          auto xj = particles.position_m.col(j);
          const Eigen::Vector3d d = xi - xj;
          const double distance = d.norm(), overlap = particles.radius_m[i] + particles.radius_m[j] - distance;
          if (overlap <= 0.0) continue;
          const Eigen::Vector3d push = (overlap + margin) / distance * d;
          const bool resting_on_j = d.z() > 0.5 * distance;
          if (resting_on_j) {
            xi += push;
          } else {
            xi += 0.5 * push;
            xj -= 0.5 * push;
          }
          moved = true;
        }
      }
      for (const Wall wall : {Wall::side, Wall::bottom, Wall::top}) {
        const WallGap gap = cavity.gap(wall, xi, particles.radius_m[i], host_z_m);
        if (gap.gap_m < 0.0) {
          xi += (margin - gap.gap_m) * gap.normal;
          moved = true;
        }
      }
    }
    if (!moved) return (particles.position_m - original.position_m).colwise().norm().maxCoeff();
  }
  throw RuntimeFailure("the spheres could not be separated: the bed's overlaps are far beyond a resting bed's");
}

}  // namespace pdamp
