/// The particles' load on the host, which both engines integrate exactly as they apply it
/// (Observation::host_load): checked against the host's and the particles' momentum, and
/// against a bed's weight. Each test runs one body on both engines.
#include <doctest/doctest.h>

#include <cfloat>
#include <cmath>
#include <string>

#include "pdamp/model/placement.hpp"
#include "pdamp/sim/engine_factory.hpp"
#include "pdamp/soft/settling.hpp"
#include "test_support.hpp"

using namespace pdamp;

namespace {

/// 40 lead spheres of 1.5 mm (0.64 g) in a small cavity on the Table 1 host.
const std::string small_damper =
    "[cavity]\ndiameter_m = 0.012\nheight_m = 0.01\n[particles]\ncount = 40\ndiameter_m = 0.0015\n";

/// The particles' vertical momentum (riders move with the host).
double particle_momentum_N_s(const State& s) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < s.particles.size(); ++i) sum += s.particles.mass_kg[i] * s.particles.velocity_m_s(2, i);
  return sum;
}

}  // namespace

TEST_CASE_TEMPLATE("the particles' load on the host balances its momentum and theirs to round-off", M, test::SoftModel,
                   test::HardModel) {
  // Dropped into a driven host, the spheres strike the floor and the lid, ride and leave.
  //   host:      M (v(t) − v(0)) = ∫ (spring + damper + excitation) dt + ∫ F_p dt
  //   particles: P_p(t) − P_p(0) = m_p g_z t − ∫ F_p dt
  for (const std::string excitation :
       {"[host]\nz0_m = 0\n[excitation]\nmode = force\nforce_N = 0.8\nfrequency_hz = 18\n",
        "[host]\nz0_m = 0\n[excitation]\nmode = base\namplitude_m = 0.003\nfrequency_hz = 20\n",
        "[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = 25\n"}) {
    CAPTURE(excitation);
    const Scenario s = test::scenario_from(small_damper + excitation);
    const Particles bed = place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m);
    auto engine = make_engine({M::model}, s, bed);
    const State start = engine->state();
    double fastest_host_m_s = 0.0;
    for (int k = 1; k <= 150; ++k) {
      engine->advance_to(0.001 * k);
      fastest_host_m_s = std::max(fastest_host_m_s, std::abs(engine->observe().host.v_m_s));
    }
    const State end = engine->state();
    const HostLoadIntegrals load = end.observation.host_load;
    const double m_p = bed.total_mass_kg(), g_z = s.gravity_m_s2.z(), t = end.observation.t_s;
    const double particles_change = particle_momentum_N_s(end) - particle_momentum_N_s(start);
    // Round-off relative to the momenta that went round, and a time-stepping engine's
    // rounding of each step's velocity updates (a rounding of the speed each, two kicks).
    const double steps = static_cast<double>(end.observation.counters.time_steps.value_or(0));
    const double momenta = (s.host.mass_kg + m_p) * fastest_host_m_s;
    const double scale = m_p * std::abs(g_z) * t + momenta * (1.0 + 2e12 * steps * DBL_EPSILON);
    CAPTURE(load.particles_N_s);
    CAPTURE(particles_change);
    CHECK(end.observation.energy.dissipated_impact_J > 0.0);  // the spheres did strike the host and each other
    CHECK(std::abs(particles_change - (m_p * g_z * t - load.particles_N_s)) <= 1e-12 * scale);
    if (s.host_has_infinite_mass()) continue;
    const double host_change = s.host.mass_kg * (end.observation.host.v_m_s - start.observation.host.v_m_s);
    CAPTURE(load.own_N_s);
    CHECK(std::abs(host_change - (load.own_N_s + load.particles_N_s)) <= 1e-12 * scale);
  }
}

TEST_CASE_TEMPLATE("a bed resting on the floor of a host at rest loads it with its weight", M, test::SoftModel,
                   test::HardModel) {
  // The host free, at its static equilibrium with the settled bed in it: ∫ F_p dt = m_p g_z t.
  Scenario s = test::scenario_from("[host]\nz0_m = 0\n" + small_damper);
  Particles bed = soft::settle_bed(s, place_particles(s.particles, s.cavity, s.host.z0_m)).particles;
  const double m_p = bed.total_mass_kg(), g_z = s.gravity_m_s2.z();
  s.host.z0_m = m_p * g_z / s.host.stiffness_N_m;
  bed.position_m.row(2).array() += s.host.z0_m;
  auto engine = make_engine({M::model}, s, bed);
  engine->advance_to(0.5);
  const Observation o = engine->observe();
  CAPTURE(o.host.z_m - s.host.z0_m);
  CHECK(o.host_load.particles_N_s == test::relative(m_p * g_z * 0.5).epsilon(1e-4));
}
