/// Frequency-response points (analysis/frf_response.hpp, sim/frf_point.hpp): the host
/// alone against its closed-form steady state, and a resting bed's apparent mass, each
/// run on both engines with one test body.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "pdamp/model/placement.hpp"
#include "pdamp/sim/engine_factory.hpp"
#include "pdamp/sim/frf_point.hpp"
#include "pdamp/soft/settling.hpp"
#include "test_support.hpp"

using namespace pdamp;

TEST_CASE_TEMPLATE("the host alone: steady amplitude, phase and loss factor as in closed form, on both engines", M,
                   test::SoftModel, test::HardModel) {
  // Each engine's own host integration, with one sphere floating at rest in weightlessness
  // in a cavity far taller than the host's motion: it never touches a wall, so the particles'
  // load is zero and the host is alone. (A scenario without spheres would run the host-only
  // engine whatever the model.) The soft step is set so that velocity Verlet's error,
  // (ω dt)² / 12 relative, stays below 1e-7; the sphere's contact laws are made soft enough
  // for that step (they never act).
  const std::string base =
      "[host]\nz0_m = 0\ndamping_N_s_m = 1\n[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = 0.02\nheight_m = 0.05\n"
      "[particles]\ncount = 1\ndiameter_m = 0.001\n[soft]\nkn_N_m1_5 = 1000\nks_N_m = 100\n[soft_wall]\nkn_N_m1_5 = "
      "1000\nks_N_m = 100\n[run]\ndt_s = 5e-6\n";
  const Particles floating = test::spheres({{0.0, 0.0, 0.025}}, {{0.0, 0.0, 0.0}});
  SteadyStateCriterion criterion;
  criterion.amplitude_tolerance = 1e-10;
  criterion.phase_tolerance_rad = 1e-10;
  criterion.measured_cycles = 5;
  for (const std::string drive : {"mode = force\nforce_N = 0.2\n", "mode = base\namplitude_m = 0.001\n"}) {
    for (const double f_hz : {12.0, 17.8, 30.0}) {
      CAPTURE(drive);
      CAPTURE(f_hz);
      const Scenario s =
          test::scenario_from(base + "[excitation]\n" + drive + "frequency_hz = " + std::to_string(f_hz) + "\n");
      auto engine = make_engine({M::model}, s, floating);
      const FrfPointOutcome point = run_frf_point(*engine, s, criterion);
      const test::ClosedForm exact = test::host_alone(s);
      const ResponseMetrics& m = point.metrics;
      REQUIRE(m.settled);
      CHECK(engine->observe().host_load.particles_N_s == 0.0);
      // Both engines to 1e-6: the soft engine's damper acts on the step-end velocity (its
      // scheme's own error, (ω dt)² / 12 relative, is below 1e-7 at this step).
      const double w = s.excitation.angular_frequency_rad_s(), k = s.host.stiffness_N_m, c = s.host.damping_N_s_m;
      const double tolerance = 1e-6;
      CHECK(m.amplitude_m == test::relative(exact.amplitude_m).epsilon(tolerance));
      CHECK(std::abs(m.phase_rad - exact.phase_rad) <= tolerance);
      CHECK(m.loss_factor == test::relative(c * w / k).epsilon(tolerance));
      const double level =
          s.excitation.mode == ExcitationMode::force ? s.excitation.force_N / k : s.excitation.amplitude_m;
      CHECK(m.normalised_amplitude == doctest::Approx(exact.amplitude_m / level).scale(1.0).epsilon(tolerance));
      CHECK(m.amplitude_spread_m <= 1e-6 * m.amplitude_m);
    }
  }
}

TEST_CASE_TEMPLATE("a bed resting on the floor under Gamma < 1: apparent mass the bed's, no equivalent damping", M,
                   test::SoftModel, test::HardModel) {
  // 40 spheres (0.64 g) settled on the Table 1 host (its damping raised so that the start
  // dies out within a second), forced at 12 Hz to Γ ≈ 0.46: the bed moves with the floor,
  // F_p = m_p (g_z − z''), whose first harmonic is −m_p z₁''.
  const Scenario s = test::scenario_from(
      "[host]\nz0_m = 0\ndamping_N_s_m = 1\n[cavity]\ndiameter_m = 0.012\nheight_m = 0.01\n[particles]\ncount = "
      "40\ndiameter_m = "
      "0.0015\n[excitation]\nmode = force\nforce_N = 0.2\nfrequency_hz = 12\n");
  const Particles bed = soft::settle_bed(s, place_particles(s.particles, s.cavity, s.host.z0_m)).particles;
  auto engine = make_engine({M::model}, s, bed);
  SteadyStateCriterion criterion;
  criterion.amplitude_tolerance = 1e-4;
  criterion.phase_tolerance_rad = 1e-4;
  const FrfPointOutcome point = run_frf_point(*engine, s, criterion);
  const ResponseMetrics& m = point.metrics;
  const double m_p = bed.total_mass_kg(), w = s.excitation.angular_frequency_rad_s();
  REQUIRE(m.gamma.has_value());
  CAPTURE(*m.gamma);
  CAPTURE(m.equivalent_damping_N_s_m);
  CHECK(m.settled);
  CHECK(*m.gamma < 1.0);
  CHECK(m.apparent_mass_kg == test::relative(m_p).epsilon(0.01));
  // Its force along the host's velocity is under 1 % of its inertial force.
  CHECK(std::abs(m.equivalent_damping_N_s_m) * w <= 0.01 * m_p * w * w);
}
