#include <doctest/doctest.h>

#include <cmath>

#include "pdamp/errors.hpp"
#include "pdamp/sim/calibration.hpp"
#include "test_support.hpp"

using namespace pdamp;

TEST_CASE("calibration: e_n(v) of the soft law, sphere-sphere and sphere-wall, against the exact impact") {
  const Scenario s = load_scenario(test::scenario_file("table1"));
  const RestitutionTable table = calibrate_restitution(s, 7);
  const double m = 9000 * 3.14159265358979 / 6 * std::pow(0.00088, 3);
  REQUIRE(table.sphere_sphere.impact_speed_m_s.size() == 7);
  CHECK(table.sphere_sphere.impact_speed_m_s.front() == test::relative(1e-3));
  for (std::size_t k = 0; k < 7; ++k) {
    const double v = table.sphere_sphere.impact_speed_m_s[k];
    CAPTURE(v);
    const double reference_dt_s = 2e-9;
    const double pair = test::reference_hertz_impact(m / 2, 3.6e5, 0.01, v, reference_dt_s).restitution;
    const double wall = test::reference_hertz_impact(m, 3.6e5, 0.01, v, reference_dt_s).restitution;
    CHECK(table.sphere_sphere.en[k] == doctest::Approx(pair).scale(1.0).epsilon(2e-3));
    CHECK(table.sphere_wall.en[k] == doctest::Approx(wall).scale(1.0).epsilon(2e-3));
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
  CHECK(c.en_at(between) == doctest::Approx(0.5 * (c.en[2] + c.en[3])).scale(1.0));
}

TEST_CASE("calibration: a frictionless, undamped law restitutes fully") {
  const Scenario s = load_scenario(test::scenario_file("small"), {"soft.cn_N_s_m=0", "soft.mu=0", "soft.cs_N_s_m=0"});
  const RestitutionTable table = calibrate_restitution(s, 3);
  for (std::size_t k = 0; k < 3; ++k) {
    CHECK(table.sphere_sphere.en[k] == doctest::Approx(1.0).scale(1.0).epsilon(1e-3));
    CHECK(table.sphere_sphere.beta0[k] ==
          doctest::Approx(-1.0).scale(1.0).epsilon(1e-3));  // no tangential force at all
  }
}

TEST_CASE("calibration: a law that cannot stop the scenario's fastest impact says so and what to use instead") {
  // Table 4 at 500 Hz from 10 mm: impacts up to ~63 m/s, which the paper's k_n lets through.
  const Scenario s = load_scenario(test::scenario_file("table4_f500"));
  CHECK_THROWS_WITH_AS(calibrate_restitution(s, 3), doctest::Contains("use [hard] restitution = constant"),
                       RuntimeFailure);
}
