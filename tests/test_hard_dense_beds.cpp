/// Dense beds on the hard engine: the opt-in diagnosis of where its collisions come from
/// (EventDiagnosis: its decades, a bouncing ball whose intervals are known in closed form,
/// and that asking for it changes no result), the TC model (hard.tc_window), the rest window
/// (hard.rest_tc_window) and the rest speed's floor at the elastic speed.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "hard/event_diagnosis.hpp"
#include "hard/hard_engine_class.hpp"
#include "pdamp/model/hertz_contact.hpp"
#include "pdamp/model/placement.hpp"
#include "test_support.hpp"

using namespace pdamp;
using hard::EventDiagnosis;
using hard::HardEngine;

TEST_CASE("diagnosis: intervals fall into decades of the contact time, speeds into decades of m/s") {
  // A contact time of 1 s puts each decade's lower edge at a number the ratio keeps exactly.
  const double tc = 1.0;
  CHECK(EventDiagnosis::interval_of(0.0, tc) == EventDiagnosis::same_instant);
  CHECK(EventDiagnosis::interval_of(0.005, tc) == EventDiagnosis::below_0_01);
  CHECK(EventDiagnosis::interval_of(0.01, tc) == EventDiagnosis::below_0_1);
  CHECK(EventDiagnosis::interval_of(0.9, tc) == EventDiagnosis::below_1);
  CHECK(EventDiagnosis::interval_of(1.0, tc) == EventDiagnosis::below_10);
  CHECK(EventDiagnosis::interval_of(50.0, tc) == EventDiagnosis::below_100);
  CHECK(EventDiagnosis::interval_of(100.0, tc) == EventDiagnosis::at_least_100);
  CHECK(EventDiagnosis::interval_of(2e-7, 1e-5) == EventDiagnosis::below_0_1);
  CHECK(EventDiagnosis::interval_of(std::numeric_limits<double>::infinity(), tc) == EventDiagnosis::first);
  CHECK(EventDiagnosis::speed_bin_of(0.5e-4) == 0);
  CHECK(EventDiagnosis::speed_bin_of(1e-4) == 1);
  CHECK(EventDiagnosis::speed_bin_of(1e-3) == 2);
  CHECK(EventDiagnosis::speed_bin_of(0.05) == 3);
  CHECK(EventDiagnosis::speed_bin_of(1.0) == 5);
  CHECK(EventDiagnosis::speed_bin_of(0.99) == 4);
  CHECK(EventDiagnosis::speed_bin_of(30.0) == 5);
}

TEST_CASE("diagnosis: an elastic ball bouncing on a fixed floor collides every 2v/g, about 100 contact times") {
  // Dropped from 5 mm: v = sqrt(2 g h) = 0.313 m/s, bounces every 2v/g = 63.9 ms; the soft
  // wall law's contact at that speed lasts t_c ≈ 0.6 ms.
  const Scenario s = test::fixed_walls(
      "[cavity]\ndiameter_m = 0.01\nheight_m = 0.03\n[particles]\ncount = 1\n"
      "[hard_wall]\nen = 1\n");
  const double h_m = 0.005, r_m = 0.0005;
  const Particles ball = test::spheres({{0.0, 0.0, r_m + h_m}}, {{0.0, 0.0, 0.0}}, r_m);
  const double v = std::sqrt(2 * 9.81 * h_m), period_s = 2 * v / 9.81;
  const double tc = hertz_contact_time_s(ball.mass_kg[0], s.soft_wall.kn_N_m1_5, v);
  REQUIRE(period_s / tc > 100);
  HardEngine engine(s, ball);
  engine.diagnose_events(s);
  engine.advance_to(1.0);
  const std::int64_t bounces = test::statistic(engine, "events_cap");
  CHECK(bounces == static_cast<std::int64_t>(std::floor((1.0 - period_s / 2) / period_s)) + 1);
  CHECK(test::statistic(engine, "diagnosis_cap_dt_first") == 1);
  CHECK(test::statistic(engine, "diagnosis_cap_dt_above_100tc") == bounces - 1);
  CHECK(test::statistic(engine, "diagnosis_cap_within_tc") == 0);
  CHECK(test::statistic(engine, "diagnosis_cap_v_1e-1_1") == bounces);
  CHECK(test::statistic(engine, "diagnosis_sphere_sphere_dt_first") == 0);
}

TEST_CASE("diagnosis: asking for it changes no result, and it sees every collision that has a law") {
  const Scenario s = load_scenario(test::scenario_file("small"), {"run.duration_s=0.05"});
  const Particles initial = place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m);
  HardEngine plain(s, initial), diagnosed(s, initial);
  diagnosed.diagnose_events(s);
  for (int k = 1; k <= 50; ++k) {
    plain.advance_to(0.001 * k);
    diagnosed.advance_to(0.001 * k);
    REQUIRE(plain.observe().energy.dissipated_impact_J == diagnosed.observe().energy.dissipated_impact_J);
  }
  CHECK(plain.state().particles.position_m == diagnosed.state().particles.position_m);
  EngineStatistics counts = diagnosed.statistics();
  const EngineStatistics plain_counts = plain.statistics();
  REQUIRE(counts.size() > plain_counts.size());
  CHECK(EngineStatistics(counts.begin(), counts.begin() + static_cast<std::ptrdiff_t>(plain_counts.size())) ==
        plain_counts);

  // Each collision is counted once by its approach speed, and each sphere in it once by
  // its interval. A knocked-off rider's collision is one of two free spheres.
  auto sum = [&](const std::string& kind, const std::string& measure_prefix) {
    std::int64_t total = 0;
    for (const auto& [name, value] : counts) {
      if (name.rfind("diagnosis_" + kind + "_" + measure_prefix, 0) == 0) total += value;
    }
    return total;
  };
  const auto stat = [&](const char* name) { return test::statistic(diagnosed, name); };
  REQUIRE(stat("jam_merges") == 0);
  REQUIRE(stat("bed_jammed") == 0);
  CHECK(sum("sphere_sphere", "v_") == stat("events_sphere_sphere") + stat("bed_knock_offs"));
  CHECK(sum("sphere_sphere", "dt_") == 2 * sum("sphere_sphere", "v_"));
  CHECK(sum("side_wall", "v_") == stat("events_wall"));
  CHECK(sum("side_wall", "dt_") == stat("events_wall"));
  CHECK(sum("cap", "v_") == stat("events_cap"));
  CHECK(sum("rider", "v_") == stat("events_rider") - stat("bed_knock_offs"));
  CHECK(sum("sphere_sphere", "v_") > 0);
  CHECK(sum("cap", "v_") > 0);
}

namespace {

/// A ball of 1 mm dropped from 5 mm onto the fixed floor of a wall law with e_n = 0.5 and
/// the TC window `tc_window`; its energy lost by impact after `duration_s`.
double ball_impact_loss_J(double tc_window, double duration_s) {
  Scenario s = test::fixed_walls(
      "[cavity]\ndiameter_m = 0.01\nheight_m = 0.03\n[particles]\ncount = 1\n"
      "[hard_wall]\nen = 0.5\n");
  s.hard_resting.tc_window = tc_window;
  HardEngine engine(s, test::spheres({{0.0, 0.0, 0.0055}}, {{0.0, 0.0, 0.0}}, 0.0005));
  engine.advance_to(duration_s);
  CHECK(engine.observe().energy.dissipated_friction_J == 0.0);
  return engine.observe().energy.dissipated_impact_J;
}

}  // namespace

TEST_CASE("TC model: a collision within the window of the sphere's last one is elastic, the first one is not") {
  // The first impact at v = sqrt(2 g h) loses (1 − e²) of the ball's kinetic energy.
  const double mass_kg = 9000 * 4.0 / 3.0 * std::numbers::pi * 0.0005 * 0.0005 * 0.0005;
  const double first_loss_J = 0.5 * mass_kg * 2 * 9.81 * 0.005 * (1 - 0.5 * 0.5);
  // Off: the ball bounces lower and lower; its first bounce lasts 2 e v / g = 32 ms.
  CHECK(ball_impact_loss_J(0.0, 0.1) > 1.2 * first_loss_J);
  // A window of 10^3 t_c (t_c ≈ 0.6 ms at 0.3 m/s, shorter at lower speed): every later
  // bounce falls within it and is elastic.
  CHECK(ball_impact_loss_J(1e3, 0.1) == test::relative(first_loss_J).epsilon(1e-9));
  // A window of one t_c holds no bounce of this ball: the TC model changes nothing here.
  CHECK(ball_impact_loss_J(1.0, 0.1) == ball_impact_loss_J(0.0, 0.1));
}

TEST_CASE("TC rest: the enduring speed is where a flight of 2v/a lasts the window's soft contact times") {
  for (const double mass_kg : {4.7e-6, 1.0e-5}) {
    for (const double kn : {3e5, 3.6e5}) {
      for (const double a : {9.81, 400.0, 1.2e4}) {
        for (const double window : {0.5, 1.0, 10.0}) {
          CAPTURE(mass_kg);
          CAPTURE(a);
          CAPTURE(window);
          const double v = hertz_enduring_speed_m_s(mass_kg, kn, a, window);
          CHECK(2 * v / a == test::relative(window * hertz_contact_time_s(mass_kg, kn, v)).epsilon(1e-12));
        }
      }
    }
  }
  // Nothing presses, or no window: nothing endures.
  CHECK(hertz_enduring_speed_m_s(1e-5, 3e5, 0.0, 1.0) == 0.0);
  CHECK(hertz_enduring_speed_m_s(1e-5, 3e5, -9.81, 1.0) == 0.0);
  CHECK(hertz_enduring_speed_m_s(1e-5, 3e5, 9.81, 0.0) == 0.0);
}

namespace {

/// What a ball of 1 mm dropped from 5 mm onto the fixed floor of a wall law with e_n = 0.5
/// did in 0.3 s with the rest window `rest_tc_window`.
struct DroppedBall {
  double mass_kg, kn_N_m1_5, rest_speed_m_s;
  std::int64_t impacts, rests;
  double impact_J, kinetic_J;
};

/// A 1 mm ball dropped from `drop_m` onto a fixed floor (e_n 0.5) at 1 g, for 0.3 s, with the
/// resting settings `resting` (the defaults but for what is given).
DroppedBall dropped_ball(const HardRestingSettings& resting, double drop_m = 0.005) {
  Scenario s = test::fixed_walls(
      "[cavity]\ndiameter_m = 0.01\nheight_m = 0.03\n[particles]\ncount = 1\n"
      "[hard_wall]\nen = 0.5\nbeta0 = 0\n");
  s.hard_resting = resting;
  const double r_m = 0.0005;
  const Particles ball = test::spheres({{0.0, 0.0, r_m + drop_m}}, {{0.0, 0.0, 0.0}}, r_m);
  HardEngine engine(s, ball);
  engine.advance_to(0.3);
  const auto energy = engine.observe().energy;
  return {ball.mass_kg[0],
          s.soft_wall.kn_N_m1_5,
          s.hard_resting.rest_speed_m_s,
          test::statistic(engine, "events_cap"),
          test::statistic(engine, "bed_rests"),
          energy.dissipated_impact_J,
          energy.particle_translational_J + energy.particle_rotational_J};
}

}  // namespace

TEST_CASE("TC rest: a ball rests at the first bounce that would land again within the window, and loses all") {
  // Leaving the floor at v_k = 0.5^k sqrt(2 g h): 0.157, 0.078, 0.039 … m/s, each flight
  // 2 v_k / g. The soft wall law's contact at v lasts t_c(v) ≈ 0.14 ms (v / 1 m/s)^(−1/5).
  const DroppedBall plain = dropped_ball({});
  const double v0 = std::sqrt(2 * 9.81 * 0.005);
  // Off: it bounces until it leaves slower than the rest speed (5 mm/s): v_6 = 4.9 mm/s.
  REQUIRE(plain.rest_speed_m_s == 0.005);
  CHECK(plain.impacts == 6);
  CHECK(plain.rests == 1);
  // A window of 100 t_c: the first bounce (32 ms against 100 t_c(0.157 m/s) = 20.6 ms) flies,
  // the second (16 ms against 23.6 ms) does not: it rests at its second impact.
  const double window = 100;
  const double tc_1 = hertz_contact_time_s(plain.mass_kg, plain.kn_N_m1_5, 1.0);
  REQUIRE(2 * 0.5 * v0 / 9.81 > window * tc_1 * std::pow(0.5 * v0, -0.2));
  REQUIRE(2 * 0.25 * v0 / 9.81 < window * tc_1 * std::pow(0.25 * v0, -0.2));
  const DroppedBall tc = dropped_ball({.rest_tc_window = window});
  CHECK(tc.impacts == 2);
  CHECK(tc.rests == 1);
  // Resting, it has lost all it had by impact: m g h, to the ledger's accuracy, as without.
  CHECK(tc.impact_J == test::relative(plain.mass_kg * 9.81 * 0.005).epsilon(1e-9));
  CHECK(tc.kinetic_J == 0.0);
  CHECK(plain.impact_J == test::relative(tc.impact_J).epsilon(1e-9));
  // One t_c at 1 g holds none of these bounces (below the rest speed either way): the same bits.
  CHECK(hertz_enduring_speed_m_s(plain.mass_kg, plain.kn_N_m1_5, 9.81, 1.0) < 0.005);
  const DroppedBall one = dropped_ball({.rest_tc_window = 1.0});
  CHECK(one.impact_J == plain.impact_J);
  CHECK(one.impacts == 6);
}

namespace {

/// Two 1 mm balls on a fixed floor at 1 g with the resting settings `resting`: the lower
/// one dropped from 0.1 mm comes to rest first, then the upper one lands on it at 0.31 m/s.
struct StackedBalls {
  std::int64_t rests, knock_offs;
  double dissipated_J, expected_J, kinetic_J;
};

StackedBalls stacked_balls(const HardRestingSettings& resting) {
  Scenario s = test::fixed_walls(
      "[cavity]\ndiameter_m = 0.01\nheight_m = 0.03\n[particles]\ncount = 2\n"
      "[hard_wall]\nen = 0.5\nbeta0 = 0\n[hard]\nbeta0 = 0\n");
  s.hard_resting = resting;
  const double r_m = 0.0005, low_drop_m = 1e-4, high_drop_m = 0.005;
  const Particles balls = test::spheres({{0.0, 0.0, r_m + low_drop_m}, {0.0, 0.0, 3 * r_m + high_drop_m}},
                                        {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}}, r_m);
  HardEngine engine(s, balls);
  engine.advance_to(0.3);
  const auto energy = engine.observe().energy;
  return {test::statistic(engine, "bed_rests"), test::statistic(engine, "bed_knock_offs"),
          energy.dissipated_impact_J + energy.dissipated_friction_J,
          balls.mass_kg[0] * 9.81 * (low_drop_m + high_drop_m),
          energy.particle_translational_J + energy.particle_rotational_J};
}

}  // namespace

TEST_CASE("TC rest: a rider hit slower than the speed at which it would rest stays on the bed") {
  // Without a window the upper ball, at 0.31 m/s, knocks the lower one off its floor.
  CHECK(stacked_balls({}).knock_offs > 0);
  // With 10⁴ contact times the soft law would hold both against 1 g below ~4 m/s: the lower
  // ball stays, the upper one rests on it at once, and all of their fall is dissipated.
  const StackedBalls held = stacked_balls({.rest_tc_window = 1e4});
  CHECK(held.knock_offs == 0);
  CHECK(held.rests == 2);
  CHECK(held.kinetic_J == 0.0);
  CHECK(held.dissipated_J == test::relative(held.expected_J).epsilon(1e-9));
}

TEST_CASE("resting: a sphere slower than the elastic speed rests, where it would bounce without end") {
  // Dropped from 20 µm it lands at 19.8 mm/s, between the rest speed (5 mm/s) and an elastic
  // speed of 5 cm/s: the bounce is elastic, and it would leave the floor as fast as it came,
  // every 4 ms. Leaving slower than the elastic speed, it rests at its first impact instead,
  // having lost its fall m g h by impact.
  const double drop_m = 2e-5;
  const DroppedBall slow = dropped_ball({.elastic_speed_m_s = 0.05}, drop_m);
  CHECK(slow.impacts == 1);
  CHECK(slow.rests == 1);
  CHECK(slow.kinetic_J == 0.0);
  CHECK(slow.impact_J == test::relative(slow.mass_kg * 9.81 * drop_m).epsilon(1e-9));
  // With resting off it bounces elastically throughout the 0.3 s (about 74 times), losing
  // nothing but round-off.
  const DroppedBall bouncing = dropped_ball({.rest_speed_m_s = 0.0, .elastic_speed_m_s = 0.05}, drop_m);
  CHECK(bouncing.rests == 0);
  CHECK(bouncing.impacts > 70);
  CHECK(bouncing.impact_J < 1e-9 * bouncing.mass_kg * 9.81 * drop_m);
  // The same on a rider: at an elastic speed of 0.5 m/s the upper ball, landing at 0.31 m/s,
  // does not knock the lower one off; it rests on it, and all of their fall is dissipated.
  const StackedBalls held = stacked_balls({.elastic_speed_m_s = 0.5});
  CHECK(held.knock_offs == 0);
  CHECK(held.rests == 2);
  CHECK(held.kinetic_J == 0.0);
  CHECK(held.dissipated_J == test::relative(held.expected_J).epsilon(1e-9));
}

TEST_CASE(
    "the dense-bed settings (rest window 10, elastic speed 0.1 m/s): no overlaps, the ledger kept, far fewer "
    "collisions") {
  // docs/hard-engine.md, "Settings for dense beds": on the paper's dense beds they keep the
  // particles' total within 3 % of the soft model's, 3.2-72x faster than it.
  const ScenarioOverrides dense = {"hard.rest_tc_window=10", "hard.elastic_speed_m_s=0.1"};
  struct Outcome {
    std::int64_t collisions;
    double particles_J;
  };
  const auto run = [&](ScenarioOverrides overrides, int milliseconds) {
    const Scenario s = load_scenario(test::scenario_file("small"), overrides);
    HardEngine engine(s, place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m));
    const double e0 = engine.observe().energy.stored_J();
    for (int k = 1; k <= milliseconds; ++k) {
      engine.advance_to(0.001 * k);
      REQUIRE(engine.max_overlap_m() <= engine.overlap_tolerance_m());
    }
    const auto energy = engine.observe().energy;
    CHECK(energy.balance_relative_error(e0) <= 1e-9);
    test::check_dissipation_by_sphere(engine);
    return Outcome{engine.collisions(), energy.dissipated_impact_J + energy.dissipated_friction_J};
  };
  for (const auto& mode : test::excitation_modes()) {
    CAPTURE(mode.empty() ? std::string("free") : mode[0]);
    ScenarioOverrides overrides = mode;
    overrides.insert(overrides.end(), dense.begin(), dense.end());
    CHECK(run(overrides, 100).particles_J > 0);
  }
  // The free decay of the small damper from 15.7 mm over 0.3 s: the spheres' many slow
  // collisions in lasting contact are what the settings spare (about 5× fewer). How their
  // loss compares with the soft model's: test_models_compared.cpp, "a small damper".
  const Outcome plain = run({}, 300);
  const Outcome fast = run(dense, 300);
  MESSAGE("collisions " << plain.collisions << " -> " << fast.collisions);
  CHECK(fast.collisions * 4 < plain.collisions);
}

TEST_CASE(
    "the side wall's elastic speed is its own: a ball meeting it at 5 cm/s loses by impact unless that is raised") {
  // Without gravity, a 1 mm ball moving radially at 5 cm/s meets the fixed side wall (e_n
  // 0.5, no tangential motion) once in 0.1 s. An elastic speed of 0.1 m/s for the spheres
  // and caps leaves the wall's law: it loses (1 − e_n²) of its energy, by impact.
  const auto impact_J = [](const HardRestingSettings& resting) {
    Scenario s = test::fixed_walls(
        "[cavity]\ndiameter_m = 0.01\nheight_m = 0.03\n[particles]\ncount = 1\n[gravity]\ng_m_s2 = 0\n"
        "[hard_wall]\nen = 0.5\nbeta0 = 0\n");
    s.hard_resting = resting;
    HardEngine engine(s, test::spheres({{0.0, 0.0, 0.015}}, {{0.05, 0.0, 0.0}}));
    engine.advance_to(0.1);
    CHECK(test::statistic(engine, "events_wall") == 1);
    CHECK(engine.observe().energy.dissipated_friction_J == 0.0);
    return engine.observe().energy.dissipated_impact_J;
  };
  const double mass_kg = 9000 * 4.0 / 3.0 * std::numbers::pi * 0.0005 * 0.0005 * 0.0005;
  const double expected_J = 0.5 * mass_kg * 0.05 * 0.05 * (1 - 0.5 * 0.5);
  const double kept_J = impact_J({.elastic_speed_m_s = 0.1});
  CHECK(std::abs(kept_J - expected_J) <= 1e-9 * expected_J);
  // Raised too, the bounce is elastic: nothing lost but round-off.
  CHECK(impact_J({.elastic_speed_m_s = 0.1, .side_wall_elastic_speed_m_s = 0.1}) <= 1e-12 * expected_J);
}
