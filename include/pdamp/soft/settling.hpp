#pragma once
/// The settling phase: the random placement falls under gravity into the cavity, with the
/// host held still at its initial displacement, until the bed is at rest. Both engines
/// then start from that bed.
///
/// Spheres rolling on the floor would roll for seconds (the paper's law has no rolling
/// resistance), so settling adds a drag −γ m v, −γ I ω with γ = 1/t_fall, t_fall =
/// sqrt(2H/|g|): it barely slows the fall and makes the rest come within ~0.5 s. The
/// drag only shapes how the bed comes to rest, not the runs that start from it.
///
/// "At rest": the particles' mean kinetic energy (translational + rotational) is below
/// 1e-8 m̄ |g| d̄ — the energy of lifting a mean sphere by a hundred-millionth of its
/// diameter, i.e. speeds of order 1e-5 m/s for the paper's spheres — checked every 5 ms of
/// simulated time once the spheres have had time to fall the cavity's height. Without
/// gravity there is nothing to settle and the placement is returned as it is.

#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>

#include "pdamp/model/particles.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp::soft {

constexpr double settled_energy_fraction = 1e-8;  ///< of m̄ |g| d̄ per sphere
constexpr double settling_check_interval_s = 0.005;
constexpr double settling_time_limit_s = 5.0;

/// t_fall = sqrt(2H/|g|), the drag's time constant (s); gravity must not be zero.
inline double settling_fall_time_s(const Scenario& scenario) {
  return std::sqrt(2.0 * scenario.cavity.height_m / scenario.gravity_m_s2.norm());
}

struct SettledBed {
  Particles particles;
  double settle_time_s = 0.0;  ///< simulated time it took
  double kinetic_J = 0.0;      ///< particle kinetic energy at the end
  std::int64_t steps = 0;
};

/// Settles `placement` (positions with the cavity bottom at host.z0_m). Throws
/// RuntimeFailure if the bed is not at rest after settling_time_limit_s or its state
/// stops being finite, and Interrupted (within a time step) when `stop` becomes true.
SettledBed settle_bed(const Scenario& scenario, const Particles& placement, const std::atomic<bool>* stop = nullptr,
                      const std::function<void(double t_s, double kinetic_J)>& progress = {});

}  // namespace pdamp::soft
