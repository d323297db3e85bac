#pragma once
/// Initial placement: n non-overlapping spheres at random in the cavity, reproducible
/// from the seed. Spheres go to a random subset of the sites of a hexagonal close-packed
/// lattice whose spacing is as wide as the count allows, each jittered at random within
/// its share of the slack, so even dense fills (up to ≈ 0.55 solid fraction) place
/// without the jamming of random sequential addition. A range of diameters that this
/// lattice, spaced for the largest, cannot hold is stacked from the floor in flat layers by
/// size, largest first, each sphere by its own size, the sizes spread evenly over the range
/// (particles_that_fit). The settling phase that follows (soft engine) erases both.

#include <cstdint>
#include <string>

#include "pdamp/model/particles.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

/// The most spheres a scenario may have.
constexpr int max_particle_count = 10'000'000;

/// The most spheres of diameter `diameter_m` that the generator can place in the cavity,
/// or max_particle_count if more fit. Counted without listing the lattice's sites: time
/// and memory do not grow with the cavity.
int max_particles_that_fit(const CavitySettings& cavity, double diameter_m);

/// The spheres' volume over the cavity's (the fill of a damper).
double solid_fraction(const CavitySettings& cavity, const Particles& particles);

/// The most spheres of `settings` the generator can place, up to `settings.count`: of one
/// diameter, max_particles_that_fit; of a range, also as many as stack by size (spread
/// evenly over the range, so it depends on the count, the range and the cavity, not the
/// seed), which their volumes decide, not the largest's.
int particles_that_fit(const ParticleSettings& settings, const CavitySettings& cavity);

/// "spheres of diameter D m", or "of diameters from A to B m", for messages.
std::string describe_spheres(const ParticleSettings& settings);

/// Throws InputError if `settings.count` spheres do not fit (particles_that_fit).
void check_particles_fit(const ParticleSettings& settings, const CavitySettings& cavity);

/// Places `settings.count` spheres with the cavity bottom at z = host_z_m, at rest.
/// Diameters are uniform in [diameter_min_m, diameter_max_m]. Throws InputError if
/// they do not fit. Lists the lattice only at the spacing it places at, where it has
/// about as many sites as spheres (at most about twice as many, when a layer appears).
Particles place_particles(const ParticleSettings& settings, const CavitySettings& cavity, double host_z_m);

/// Moves overlapping spheres apart — bottom up along `up` (a unit vector against gravity),
/// each out of the spheres it rests on along the line of centres, side-by-side pairs half
/// each, and out of the walls — until no two touch, so a bed settled with soft contacts
/// (whose overlaps are a tiny fraction of a radius at rest) can start a hard-sphere run.
/// Returns the largest distance a sphere was moved (m). Throws RuntimeFailure if 1000
/// sweeps do not separate them (overlaps far beyond a resting bed's).
double separate_overlaps(Particles& particles, const CavitySettings& cavity, double host_z_m,
                         const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

}  // namespace pdamp
