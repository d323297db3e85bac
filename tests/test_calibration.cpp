#include <doctest/doctest.h>

#include <cmath>

#include "pdamp/errors.hpp"
#include "pdamp/sim/calibration.hpp"
#include "test_support.hpp"

using namespace pdamp;

namespace {

/// The 1D Hertz-dashpot impact, m* δ'' = −max(0, k δ^{3/2} + c δ'), integrated with RK4 at
/// a far finer step: the rebound speed ratio.
double reference_restitution(double effective_mass, double kn, double cn, double speed) {
  const double dt = 2e-9;
  double delta = 0.0, rate = speed;
  auto accel = [&](double d, double r) { return -std::max(0.0, kn * std::pow(std::max(d, 0.0), 1.5) + cn * r) / effective_mass; };
  do {
    const double k1d = rate, k1r = accel(delta, rate);
    const double k2d = rate + 0.5 * dt * k1r, k2r = accel(delta + 0.5 * dt * k1d, k2d);
    const double k3d = rate + 0.5 * dt * k2r, k3r = accel(delta + 0.5 * dt * k2d, k3d);
    const double k4d = rate + dt * k3r, k4r = accel(delta + dt * k3d, k4d);
    delta += dt / 6 * (k1d + 2 * k2d + 2 * k3d + k4d);
    rate += dt / 6 * (k1r + 2 * k2r + 2 * k3r + k4r);
  } while (delta > 0.0);
  return -rate / speed;
}

}  // namespace

TEST_CASE("calibration: e_n(v) of the soft law, sphere-sphere and sphere-wall, against the exact impact") {
  const Scenario s = load_scenario(test::scenario_file("table1"));
  const RestitutionTable table = calibrate_restitution(s, 7);
  const double m = 9000 * 3.14159265358979 / 6 * std::pow(0.00088, 3);
  REQUIRE(table.sphere_sphere.impact_speed_m_s.size() == 7);
  CHECK(table.sphere_sphere.impact_speed_m_s.front() == doctest::Approx(1e-3));
  for (std::size_t k = 0; k < 7; ++k) {
    const double v = table.sphere_sphere.impact_speed_m_s[k];
    CAPTURE(v);
    CHECK(table.sphere_sphere.en[k] == doctest::Approx(reference_restitution(m / 2, 3.6e5, 0.01, v)).epsilon(2e-3));
    CHECK(table.sphere_wall.en[k] == doctest::Approx(reference_restitution(m, 3.6e5, 0.01, v)).epsilon(2e-3));
    // The paper's stiff tangential spring rings many times in a contact and its dashpot
    // damps it: sticking impacts leave almost no tangential rebound.
    CHECK(std::abs(table.sphere_sphere.beta0[k]) < 0.25);
    CHECK(std::abs(table.sphere_wall.beta0[k]) < 0.25);
  }
  // Restitution grows with the impact speed for a constant dashpot.
  CHECK(table.sphere_sphere.en.front() < table.sphere_sphere.en.back());
  // Interpolation in log(speed) and clamping at the ends.
  const RestitutionCurve& c = table.sphere_wall;
  CHECK(c.en_at(1e-6) == c.en.front());
  CHECK(c.en_at(1e3) == c.en.back());
  const double between = std::sqrt(c.impact_speed_m_s[2] * c.impact_speed_m_s[3]);
  CHECK(c.en_at(between) == doctest::Approx(0.5 * (c.en[2] + c.en[3])));
}

TEST_CASE("calibration: a frictionless, undamped law restitutes fully") {
  const Scenario s = load_scenario(test::scenario_file("small"), {"soft.cn_N_s_m=0", "soft.mu=0", "soft.cs_N_s_m=0"});
  const RestitutionTable table = calibrate_restitution(s, 3);
  for (std::size_t k = 0; k < 3; ++k) {
    CHECK(table.sphere_sphere.en[k] == doctest::Approx(1.0).epsilon(1e-3));
    CHECK(table.sphere_sphere.beta0[k] == doctest::Approx(-1.0).epsilon(1e-3));  // no tangential force at all
  }
}

TEST_CASE("calibration: a law that cannot stop the scenario's fastest impact says so and what to use instead") {
  // Table 4 at 500 Hz from 10 mm: impacts up to ~63 m/s, which the paper's k_n lets through.
  const Scenario s = load_scenario(test::scenario_file("table4_f500"));
  CHECK_THROWS_WITH_AS(calibrate_restitution(s, 3), doctest::Contains("use [hard] restitution = constant"), RuntimeFailure);
}
