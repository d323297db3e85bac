#include "pdamp/model/placement.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "pdamp/errors.hpp"
#include "pdamp/model/cavity.hpp"
#include "pdamp/model/cell_grid.hpp"

namespace pdamp {
namespace {

/// The hexagonal close-packed lattice of spacing `spacing_m` whose sites keep a sphere of
/// radius `radius_m` inside the cavity (cavity frame: bottom centre at the origin): layers
/// from z = radius_m up, each a triangular lattice of rows along x, alternate layers over
/// the hollows of the one below (A, B, A, ... stacking). A row's sites inside the cavity are
/// a run of consecutive columns, found without visiting the others, and layers of one
/// parity have the same sites: the lattice is counted in time and memory that do not grow
/// with the cavity, and listed in time proportional to its sites.
class HcpLattice {
 public:
  HcpLattice(const CavitySettings& cavity, double radius_m, double spacing_m)
      : radius_m_(radius_m),
        spacing_m_(spacing_m),
        reach_m_(cavity.radius_m() - radius_m),
        top_m_(cavity.height_m - radius_m),
        layer_gap_m_(spacing_m * std::sqrt(2.0 / 3.0)),
        row_gap_m_(spacing_m * std::sqrt(3.0) / 2.0),
        half_rows_(std::ceil(reach_m_ / row_gap_m_) + 1.0),
        half_cols_(std::ceil(reach_m_ / spacing_m) + 1.0),
        layers_(reach_m_ < 0.0 ? 0.0 : layer_count()) {}

  /// The number of sites, or `cap` if there are more.
  std::int64_t count(std::int64_t cap) const {
    const double by_parity[2] = {std::ceil(0.5 * layers_), std::floor(0.5 * layers_)};
    double total = 0.0;
    for (const int parity : {0, 1}) {
      if (by_parity[parity] == 0.0) continue;
      total += by_parity[parity] * static_cast<double>(count_layer(parity, cap));
      if (total >= static_cast<double>(cap)) return cap;
    }
    return static_cast<std::int64_t>(total);
  }

  std::vector<Eigen::Vector3d> sites() const {
    std::vector<Eigen::Vector3d> sites;
    for (double layer = 0.0; layer < layers_; ++layer) add_layer(layer, sites);
    return sites;
  }

  /// The lowest layer's sites (at z = radius_m), or how many, up to `cap`.
  std::int64_t count_lowest_layer(std::int64_t cap) const { return layers_ > 0.0 ? count_layer(0, cap) : 0; }
  std::vector<Eigen::Vector3d> lowest_layer_sites() const {
    std::vector<Eigen::Vector3d> sites;
    if (layers_ > 0.0) add_layer(0.0, sites);
    return sites;
  }

 private:
  /// A row of a layer: its y, its shift and its layer's in x, and its sites' columns [first, last].
  struct Row {
    double y_m, row_shift_m, layer_shift_m, first, last;
  };

  void add_layer(double layer, std::vector<Eigen::Vector3d>& sites) const {
    const int parity = static_cast<int>(std::fmod(layer, 2.0));
    const double z = layer_z_m(layer);
    for (double row = -half_rows_; row <= half_rows_; ++row) {
      const Row r = row_sites(row, parity);
      for (double col = r.first; col <= r.last; ++col) sites.emplace_back(x_m(col, r), r.y_m, z);
    }
  }

  double layer_z_m(double layer) const { return radius_m_ + layer * layer_gap_m_; }
  double x_m(double col, const Row& r) const { return col * spacing_m_ + r.row_shift_m + r.layer_shift_m; }
  bool inside(double col, const Row& r) const { return std::hypot(x_m(col, r), r.y_m) <= reach_m_; }

  double layer_count() const {
    double layers = std::floor((top_m_ - radius_m_) / layer_gap_m_) + 1.0;
    if (!(layers < 0x1p52)) return layers;  // beyond where doubles count in ones, exact is moot
    layers = std::max(layers, 0.0);
    while (layer_z_m(layers) <= top_m_) ++layers;
    while (layers > 0.0 && !(layer_z_m(layers - 1.0) <= top_m_)) --layers;
    return layers;
  }

  Row row_sites(double row, int parity) const {
    Row r;
    // Shifts as the lattice was first written: alternate layers by half a spacing in x and
    // a third of a row gap in y, odd rows by half a spacing.
    r.y_m = row * row_gap_m_ + parity * row_gap_m_ / 3.0;
    r.row_shift_m = std::fmod(std::abs(row), 2.0) * spacing_m_ / 2.0;
    r.layer_shift_m = parity * spacing_m_ / 2.0;
    const double chord = std::sqrt(std::max(0.0, reach_m_ * reach_m_ - r.y_m * r.y_m));
    const double shift = r.row_shift_m + r.layer_shift_m;
    r.first = std::max(-half_cols_, std::ceil((-chord - shift) / spacing_m_));
    r.last = std::min(half_cols_, std::floor((chord - shift) / spacing_m_));
    // The estimate is within a column or two of the sites the exact test admits.
    if (r.last - r.first < 0x1p52) {
      while (r.first > -half_cols_ && inside(r.first - 1.0, r)) --r.first;
      while (r.first <= r.last && !inside(r.first, r)) ++r.first;
      while (r.last < half_cols_ && inside(r.last + 1.0, r)) ++r.last;
      while (r.last >= r.first && !inside(r.last, r)) --r.last;
    }
    return r;
  }

  /// The sites of one layer of this parity, or `cap` if there are more; rows from the
  /// middle out, so that a wide cavity reaches the cap in its first rows.
  std::int64_t count_layer(int parity, std::int64_t cap) const {
    double total = 0.0;
    for (double k = 0.0; k <= 2.0 * half_rows_ && total < static_cast<double>(cap); ++k) {
      const double row = std::fmod(k, 2.0) == 0.0 ? -0.5 * k : 0.5 * (k + 1.0);  // 0, 1, -1, 2, -2, ...
      const Row r = row_sites(row, parity);
      total += std::max(0.0, r.last - r.first + 1.0);
    }
    return total >= static_cast<double>(cap) ? cap : static_cast<std::int64_t>(total);
  }

  double radius_m_, spacing_m_, reach_m_, top_m_, layer_gap_m_, row_gap_m_;
  double half_rows_, half_cols_, layers_;
};

/// A point in the unit ball, uniformly.
Eigen::Vector3d random_in_ball(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (;;) {
    Eigen::Vector3d p(unit(rng), unit(rng), unit(rng));
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

/// The widest spacing from 2 radius_m up to loose_m at which `sites(spacing)` still counts n
/// sites: counts fall as the spacing grows (not strictly), so bisect on them.
template <class Sites>
double widest_spacing(double radius_m, double loose_m, std::int64_t n, Sites sites) {
  double tight = 2.0 * radius_m, loose = loose_m;
  for (int iteration = 0; iteration < 60; ++iteration) {
    const double mid = 0.5 * (tight + loose);
    (sites(mid) >= n ? tight : loose) = mid;
  }
  return tight;
}

/// The k-th largest (from 0) of n diameters spread evenly over the settings' range: the
/// stacked spheres' sizes, the range's uniform distribution without a draw's scatter, so
/// that whether they fit depends on n, the range and the cavity alone.
double spread_diameter(const ParticleSettings& settings, std::int64_t k, std::int64_t n) {
  const double step = (settings.diameter_max_m - settings.diameter_min_m) / static_cast<double>(n);
  return settings.diameter_max_m - (static_cast<double>(k) + 0.5) * step;
}

/// A flat layer of a stack: its floor (cavity frame), the padded radius its lattice is
/// spaced for, and the spheres [first, first + count) it holds, largest first.
struct Layer {
  double floor_m, radius_m;
  std::int64_t first, count;
};

/// n spheres of the range (spread_diameter), largest first, stacked from the floor in flat
/// layers: each the lowest layer of the lattice for its first (largest) sphere, filled in
/// order, the next one's floor at its top. A sphere stays within its layer's slab and its
/// share of its lattice, so none touch. Calls `visit` with each layer (none kept: a narrow
/// cavity may stack millions), until the spheres or the cavity's height run out; returns how
/// many spheres the layers hold.
template <class Visit>
std::int64_t stack_layers(const ParticleSettings& settings, std::int64_t n, const CavitySettings& cavity, Visit visit) {
  double floor_m = 0.0;
  std::int64_t first = 0;
  while (first < n) {
    const double r = padded_radius(cavity, spread_diameter(settings, first, n) / 2.0);
    const std::int64_t sites =
        HcpLattice({cavity.diameter_m, cavity.height_m - floor_m}, r, 2.0 * r).count_lowest_layer(n - first);
    if (sites == 0) break;
    visit(Layer{floor_m, r, first, sites});
    first += sites;
    floor_m += 2.0 * r;
  }
  return first;
}

bool stacks(const ParticleSettings& settings, std::int64_t n, const CavitySettings& cavity) {
  return stack_layers(settings, n, cavity, [](const Layer&) {}) == n;
}

/// The spheres stacked (stack_layers), each layer's on random sites of its lattice in a
/// random order of their sizes, each jittered within the slack its own size leaves there.
Particles place_stacked(const ParticleSettings& settings, const CavitySettings& cavity, double host_z_m) {
  std::mt19937_64 rng(settings.seed);
  Particles particles(settings.count);
  stack_layers(settings, settings.count, cavity, [&](const Layer& layer) {
    const CavitySettings above{cavity.diameter_m, cavity.height_m - layer.floor_m};
    const auto sites_at = [&](double spacing) {
      return HcpLattice(above, layer.radius_m, spacing).count_lowest_layer(layer.count + 1);
    };
    // The last layer may have far more sites than spheres: listed at the widest spacing
    // that holds them, as many as about the spheres.
    const double spacing = sites_at(2.0 * layer.radius_m) > layer.count
                               ? widest_spacing(layer.radius_m, 2.0 * cavity.radius_m(), layer.count, sites_at)
                               : 2.0 * layer.radius_m;
    std::vector<Eigen::Vector3d> sites = HcpLattice(above, layer.radius_m, spacing).lowest_layer_sites();
    std::shuffle(sites.begin(), sites.end(), rng);
    sites.resize(static_cast<std::size_t>(layer.count));
    std::sort(sites.begin(), sites.end(), [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      return std::tie(a.y(), a.x()) < std::tie(b.y(), b.x());
    });
    std::vector<Eigen::Index> order(sites.size());
    std::iota(order.begin(), order.end(), layer.first);
    std::shuffle(order.begin(), order.end(), rng);
    for (std::size_t k = 0; k < sites.size(); ++k) {
      const Eigen::Index i = layer.first + static_cast<Eigen::Index>(k);
      const double d = spread_diameter(settings, order[k], settings.count);
      const double r = padded_radius(cavity, d / 2.0);
      const Eigen::Vector3d site = sites[k] + Eigen::Vector3d(0.0, 0.0, layer.floor_m);
      const Eigen::Vector3d centre = project_into_cavity(site + (layer.radius_m - r) * random_in_ball(rng), cavity, r);
      particles.position_m.col(i) = centre + Eigen::Vector3d(0.0, 0.0, host_z_m);
      particles.radius_m[i] = d / 2.0;
      particles.mass_kg[i] = settings.density_kg_m3 * std::numbers::pi / 6.0 * d * d * d;
    }
  });
  return particles;
}

}  // namespace

int max_particles_that_fit(const CavitySettings& cavity, double diameter_m) {
  const double r = padded_radius(cavity, diameter_m / 2.0);
  return static_cast<int>(HcpLattice(cavity, r, 2.0 * r).count(max_particle_count));
}

double solid_fraction(const CavitySettings& cavity, const Particles& particles) {
  const double spheres_m3 = 4.0 / 3.0 * std::numbers::pi * particles.radius_m.array().cube().sum();
  return spheres_m3 / (std::numbers::pi * cavity.radius_m() * cavity.radius_m() * cavity.height_m);
}

int particles_that_fit(const ParticleSettings& settings, const CavitySettings& cavity) {
  const int on_lattice = max_particles_that_fit(cavity, settings.diameter_max_m);
  if (settings.count <= on_lattice || settings.diameter_min_m == settings.diameter_max_m) {
    return std::min(settings.count, on_lattice);
  }
  // None takes less room than the smallest: more than the cavity's volume holds of those
  // cannot fit, found before any is stacked. The most that stack below that, by bisection:
  // fewer spheres of a range are as large or smaller ones, never harder to stack.
  const double smallest_m3 = std::numbers::pi / 6.0 * std::pow(settings.diameter_min_m, 3);
  const double cavity_m3 = std::numbers::pi * cavity.radius_m() * cavity.radius_m() * cavity.height_m;
  auto not_fits = static_cast<std::int64_t>(std::min(settings.count + 0.0, std::floor(cavity_m3 / smallest_m3) + 1.0));
  if (not_fits == settings.count && stacks(settings, settings.count, cavity)) return settings.count;
  std::int64_t fits = on_lattice;
  while (not_fits - fits > 1) {
    const std::int64_t mid = fits + (not_fits - fits) / 2;
    (stacks(settings, mid, cavity) ? fits : not_fits) = mid;
  }
  return static_cast<int>(fits);
}

std::string describe_spheres(const ParticleSettings& settings) {
  std::ostringstream text;
  if (settings.diameter_min_m == settings.diameter_max_m) {
    text << "spheres of diameter " << settings.diameter_max_m << " m";
  } else {
    text << "spheres of diameters from " << settings.diameter_min_m << " to " << settings.diameter_max_m << " m";
  }
  return text.str();
}

void check_particles_fit(const ParticleSettings& settings, const CavitySettings& cavity) {
  if (const int capacity = particles_that_fit(settings, cavity); settings.count > capacity) {
    throw InputError("particles.count = " + std::to_string(settings.count) + ": at most " + std::to_string(capacity) +
                     " " + describe_spheres(settings) + " can be placed in the cavity");
  }
}

Particles place_particles(const ParticleSettings& settings, const CavitySettings& cavity, double host_z_m) {
  check_particles_fit(settings, cavity);
  const int n = settings.count;
  const double d_max = settings.diameter_max_m;
  Particles particles(n);
  if (n == 0) return particles;
  if (n > max_particles_that_fit(cavity, d_max)) return place_stacked(settings, cavity, host_z_m);

  // The widest lattice that still has a site for every sphere leaves the most room to jitter.
  const double r_max = padded_radius(cavity, d_max / 2.0);
  const double spacing = widest_spacing(r_max, std::max(2.0 * cavity.radius_m(), cavity.height_m), n,
                                        [&](double s) { return HcpLattice(cavity, r_max, s).count(n); });
  std::vector<Eigen::Vector3d> sites = HcpLattice(cavity, r_max, spacing).sites();

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

double separate_overlaps(Particles& particles, const CavitySettings& settings, double host_z_m,
                         const Eigen::Vector3d& up) {
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
    // Bottom up (against gravity, whichever wall the bed rests on), each sphere moves out
    // of those it rests on (and out of the walls): a bed's overlaps add up along its
    // columns, and this lifts a whole column in one sweep, where pushing pairs apart
    // symmetrically passes them up one layer a sweep. Side by side contacts are pushed
    // apart half each, so that a sphere against the side wall can move its neighbour
    // rather than be pushed back into it.
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      const double ha = particles.position_m.col(a).dot(up), hb = particles.position_m.col(b).dot(up);
      return ha < hb || (ha == hb && a < b);
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
          const bool resting_on_j = d.dot(up) > 0.5 * distance;
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
