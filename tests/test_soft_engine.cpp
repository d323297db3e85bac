/// The soft-sphere engine against exact and independent results.
#include <doctest/doctest.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/model/placement.hpp"
#include "pdamp/soft/settling.hpp"
#include "pdamp/soft/time_step.hpp"
#include "soft/soft_engine_class.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::soft;
using pdamp::test::scenario_from;
using pdamp::test::spheres;

namespace {

/// A wide cavity and lead spheres of 1 mm with the Table 1 law; no gravity unless asked.
const std::string wide_cavity =
    "[cavity]\ndiameter_m = 0.02\nheight_m = 0.02\n[particles]\ndiameter_m = 0.001\ncount = 2\n"
    "[gravity]\ng_m_s2 = 0\n[host]\nz0_m = 0\n";

SoftEngineOptions held() {
  SoftEngineOptions o;
  o.hold_host = true;
  return o;
}

/// The reference impacts' step, far below the engine's.
constexpr double reference_dt_s = 1e-10;

struct Impact {
  double restitution, contact_time_s;
};

/// Drops one sphere at `speed` onto the held floor (no gravity) and measures the bounce.
Impact drop_on_floor(const Scenario& s, double speed) {
  const double r = 0.0005;
  SoftEngine engine(s, spheres({{0.001, 0.0, r + 1e-6}}, {{0.0, 0.0, -speed}}, r), held());
  const double dt = engine.time_step_s();
  double t = 0.0, contact_start = -1.0, contact_end = -1.0;
  while (contact_end < 0.0) {
    t += dt;
    engine.advance_to(t);
    const bool touching = engine.observe().counters.contacts > 0;
    if (touching && contact_start < 0.0) contact_start = t;
    if (!touching && contact_start >= 0.0) contact_end = t;
    REQUIRE(t < 0.01);
  }
  return {engine.state().particles.velocity_m_s(2, 0) / speed, contact_end - contact_start};
}

}  // namespace

TEST_CASE("a sphere dropped on a fixed floor rebounds as the Hertz-dashpot solution says") {
  for (const double speed : {0.05, 0.5, 2.0}) {
    CAPTURE(speed);
    const Scenario s = scenario_from(wide_cavity, {"particles.count=1"});
    const double m = 9000 * 4.0 / 3.0 * std::numbers::pi * 1.25e-10;
    const auto [e_exact, tc_exact] = test::reference_hertz_impact(m, 3.6e5, 0.01, speed, reference_dt_s);
    const Impact impact = drop_on_floor(s, speed);
    CHECK(impact.restitution == doctest::Approx(e_exact).scale(1.0).epsilon(2e-3));
    // The engine sees the contact at whole steps: its duration is within a step of the exact one.
    SoftEngine probe(s, spheres({{0, 0, 0.001}}, {{0, 0, 0}}), held());
    CHECK(std::abs(impact.contact_time_s - tc_exact) <= 1.01 * probe.time_step_s());
  }
}

TEST_CASE("an elastic Hertz impact lasts 2.9432 delta_max / v and returns all its energy") {
  const Scenario s = scenario_from(wide_cavity + "[soft_wall]\ncn_N_s_m = 0\n", {"particles.count=1"});
  const double m = 9000 * 4.0 / 3.0 * std::numbers::pi * 1.25e-10;
  const double speed = 1.0;
  const Impact impact = drop_on_floor(s, speed);
  CHECK(impact.restitution == doctest::Approx(1.0).scale(1.0).epsilon(1e-4));
  CHECK(impact.contact_time_s == test::relative(hertz_contact_time_s(m, 3.6e5, speed)).epsilon(0.03));
  const double exact_s = test::reference_hertz_impact(m, 3.6e5, 0.0, speed, reference_dt_s).contact_time_s;
  CHECK(hertz_contact_time_s(m, 3.6e5, speed) == test::relative(exact_s).epsilon(1e-4));
}

namespace {

struct Totals {
  Eigen::Vector3d momentum, angular_momentum;
  double energy;  ///< kinetic + contact elastic + dissipated
};

Totals totals(const SoftEngine& engine) {
  const State s = engine.state();
  const Particles& p = s.particles;
  Totals t{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0};
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    const Eigen::Vector3d x = p.position_m.col(i), v = p.velocity_m_s.col(i), w = p.angular_velocity_rad_s.col(i);
    t.momentum += p.mass_kg[i] * v;
    t.angular_momentum += p.mass_kg[i] * x.cross(v) + p.moment_of_inertia(i) * w;
  }
  const EnergyLedger& e = s.observation.energy;
  t.energy = e.particle_translational_J + e.particle_rotational_J + e.contact_elastic_J + e.dissipated_J();
  return t;
}

}  // namespace

TEST_CASE("binary collisions conserve momentum and angular momentum, and the energy lost is what the books say") {
  struct Case {
    const char* name;
    Eigen::Vector3d offset, spin;
  };
  const Case cases[] = {
      {"head-on", {0, 0, 0}, {0, 0, 0}},
      {"oblique", {0, 0.0006, 0.0002}, {0, 0, 0}},
      {"oblique with spin", {0, 0.0004, 0}, {300, -200, 500}},
  };
  for (const auto& c : cases) {
    CAPTURE(c.name);
    const Scenario s = scenario_from(wide_cavity);
    Particles p = spheres({Eigen::Vector3d(-0.0008, 0, 0.01), Eigen::Vector3d(0.0008, 0, 0.01) + c.offset},
                          {{0.7, 0, 0}, {-0.7, 0, 0}});
    p.angular_velocity_rad_s.col(0) = c.spin;
    SoftEngine engine(s, p, held());
    const Totals before = totals(engine);
    engine.advance_to(0.003);
    const Totals after = totals(engine);
    CHECK(engine.observe().counters.contacts == 0);  // the collision is over
    const double p_scale = 2 * p.mass_kg[0] * 0.7;
    CHECK((after.momentum - before.momentum).norm() <= 1e-13 * p_scale);
    // Round-off of ~2,000 steps: 1e-12 of |x| |p| (lever 0.01 m).
    CHECK((after.angular_momentum - before.angular_momentum).norm() <= 1e-12 * p_scale * 0.01);
    const EnergyLedger e = engine.observe().energy;
    CHECK(e.dissipated_impact_J > 0.0);
    if (c.offset.norm() > 0) CHECK(e.dissipated_friction_J > 0.0);
    // Kinetic energy lost = dissipated, to the integrator's O(dt^2) (a few 1e-5 here).
    CHECK(std::abs(after.energy - before.energy) <= 1e-4 * before.energy);
  }
}

TEST_CASE("head-on: the impact loss equals the dashpot work integrated step by step") {
  const Scenario s = scenario_from(wide_cavity);
  SoftEngine engine(s, spheres({{-0.0008, 0, 0.01}, {0.0008, 0, 0.01}}, {{0.5, 0, 0}, {-0.5, 0, 0}}), held());
  const double dt = engine.time_step_s();
  double dashpot_work = 0.0;
  for (double t = dt; t < 0.003; t += dt) {
    engine.advance_to(t);
    const Particles p = engine.state().particles;
    const double overlap = 0.001 - (p.position_m.col(1) - p.position_m.col(0)).norm();
    if (overlap <= 0) continue;
    const double rate = (p.velocity_m_s.col(0) - p.velocity_m_s.col(1)).x();  // δ' for a head-on pair
    const double elastic = 3.6e5 * std::pow(overlap, 1.5);
    // The force never pulls: where the dashpot would, the clamp takes the elastic force away.
    dashpot_work += (elastic + 0.01 * rate > 0 ? 0.01 * rate * rate : -elastic * rate) * dt;
  }
  CHECK(engine.observe().energy.dissipated_impact_J == test::relative(dashpot_work).epsilon(2e-2));
  CHECK(engine.observe().energy.dissipated_friction_J == doctest::Approx(0.0).scale(1e-12));
}

TEST_CASE("a sphere sliding on the floor rolls at 5/7 of its initial speed") {
  const Scenario s = scenario_from(wide_cavity, {"particles.count=1", "gravity.g_m_s2=9.81"});
  const double r = 0.0005;
  // Start resting on the floor with its static overlap, sliding without spin.
  const double m = 9000 * 4.0 / 3.0 * std::numbers::pi * r * r * r;
  const double static_overlap = std::pow(m * 9.81 / 3.6e5, 2.0 / 3.0);
  SoftEngine engine(s, spheres({{-0.005, 0, r - static_overlap}}, {{0.2, 0, 0}}, r), held());
  engine.advance_to(0.05);
  const Particles p = engine.state().particles;
  CHECK(p.velocity_m_s(0, 0) == test::relative(0.2 * 5.0 / 7.0).epsilon(2e-3));
  CHECK(p.angular_velocity_rad_s(1, 0) * r == test::relative(0.2 * 5.0 / 7.0).epsilon(2e-3));  // rolling: v = omega r
  // What sliding took away is friction.
  const EnergyLedger e = engine.observe().energy;
  CHECK(e.dissipated_friction_J == test::relative(0.5 * m * 0.04 * 2.0 / 7.0).epsilon(5e-3));
}

TEST_CASE("no contact is ever missed: the engine's contacts equal a brute-force search every step") {
  // A dense, agitated gas of 400 spheres (32 % solid) in a shaking host.
  const Scenario s = test::scenario_from("[particles]\ncount = 400\n[cavity]\ndiameter_m = 0.012\nheight_m = 0.004\n");
  Particles placed = place_particles(s.particles, s.cavity, s.host.z0_m);
  placed.velocity_m_s = Eigen::Matrix3Xd::Random(3, placed.size());  // up to 1 m/s each way
  SoftEngine engine(s, placed);
  const double dt = engine.time_step_s();
  const Cavity cavity(s.cavity);
  int busy_steps = 0;
  for (int k = 1; k <= 3000; ++k) {
    engine.advance_to(k * dt);
    if (k % 10) continue;
    const State st = engine.state();
    const Particles& p = st.particles;
    std::int64_t brute = 0;
    for (Eigen::Index i = 0; i < p.size(); ++i) {
      for (Eigen::Index j = i + 1; j < p.size(); ++j) {
        brute += (p.position_m.col(i) - p.position_m.col(j)).norm() < p.radius_m[i] + p.radius_m[j];
      }
      for (const Wall w : {Wall::side, Wall::bottom, Wall::top}) {
        brute += cavity.gap(w, p.position_m.col(i), p.radius_m[i], st.observation.host.z_m).gap_m < 0;
      }
    }
    REQUIRE(st.observation.counters.contacts == brute);
    busy_steps += brute > 20;
  }
  CHECK(busy_steps > 50);
}

TEST_CASE("the time step resolves the Hertz contact and the tangential spring, and refuses what cannot") {
  const Scenario s = scenario_from("");
  // Table 1: fastest impact 2 x 1.755 m/s + sqrt(2 g H) = 3.88 m/s; t_c of a sphere pair ~ 71 us.
  CHECK(max_impact_speed_m_s(s) ==
        doctest::Approx(2 * 0.0157 * std::sqrt(470 / 0.0376) + std::sqrt(2 * 9.81 * 0.00704)).scale(1.0).epsilon(1e-3));
  const double tc = shortest_contact_time_s(s);
  CHECK(tc == test::relative(7.1e-5).epsilon(0.03));
  // A sticking pair of 0.88 mm lead spheres: T_s = 2 pi sqrt(m / 7 k_s) = 7.4 us.
  const double m = 9000 * std::numbers::pi / 6 * std::pow(0.00088, 3);
  const double ts = shortest_tangential_period_s(s);
  CHECK(ts == test::relative(2 * std::numbers::pi * std::sqrt(m / 7 / 3.3e5)));
  CHECK(choose_time_step_s(s) == test::relative(std::min(tc / 50, ts / 8)));
  CHECK(shortest_tangential_period_s(scenario_from("[soft]\nks_N_m = 0\n")) == std::numeric_limits<double>::infinity());
  // The paper's 2.5 us is past the limit T_s/4; 1.5 us is not.
  CHECK_THROWS_WITH_AS(choose_time_step_s(scenario_from("[run]\ndt_s = 2.5e-6\n")),
                       doctest::Contains("run.dt_s = 2.5e-06"), InputError);
  CHECK_NOTHROW(choose_time_step_s(scenario_from("[run]\ndt_s = 1.5e-6\n")));
  CHECK_THROWS_WITH_AS(choose_time_step_s(scenario_from("[run]\ndt_s = 2e-5\n[soft]\nks_N_m = 0\n")),
                       doctest::Contains("t_c/10"), InputError);
}

namespace {

/// Largest energy-balance error over a run of `engine` observed every `interval`.
double worst_balance_error(SoftEngine& engine, double duration, double interval) {
  const double e0 = engine.observe().energy.stored_J();
  double worst = 0.0;
  for (int k = 1; k * interval <= duration * (1 + 1e-12); ++k) {
    engine.advance_to(k * interval);
    worst = std::max(worst, engine.observe().energy.balance_relative_error(e0));
  }
  return worst;
}

Scenario with_time_step(const Scenario& s, double dt) {
  std::ostringstream step;
  step.precision(17);
  step << "run.dt_s=" << dt;
  return test::scenario_from(s.canonical_text, {step.str()});
}

}  // namespace

TEST_CASE("the energy balance error converges at second order in the time step") {
  // Two spinning spheres hit the floor of the free Table 1 host and each other, sliding
  // and sticking: every term of the books is exercised, and nothing is chaotic in 10 ms.
  const Scenario s0 =
      scenario_from("[particles]\ncount = 2\ndiameter_m = 0.001\n[cavity]\ndiameter_m = 0.012\nheight_m = 0.01\n");
  Particles p = spheres({{0.001, 0, 0.002 + s0.host.z0_m}, {0.003, 0.0005, 0.0045 + s0.host.z0_m}},
                        {{0.3, 0.1, -0.5}, {-0.2, 0, -1.0}});
  p.angular_velocity_rad_s.col(0) << 100, -300, 50;
  const double dt = choose_time_step_s(s0);
  std::vector<double> errors;
  for (const double factor : {1.0, 0.5, 0.25}) {
    SoftEngine engine(with_time_step(s0, dt * factor), p);
    errors.push_back(worst_balance_error(engine, 0.01, 0.0005));
    CHECK(engine.observe().energy.dissipated_friction_J > 0);
  }
  CAPTURE(errors[0]);
  CAPTURE(errors[1]);
  CAPTURE(errors[2]);
  CHECK(errors[0] < 1e-8);
  CHECK(std::log2(errors[0] / errors[1]) > 1.8);
  CHECK(std::log2(errors[1] / errors[2]) > 1.8);
}

TEST_CASE("a small damper (100 spheres, 0.3 s) keeps its energy books") {
  const Scenario small = load_scenario(test::scenario_file("small"));
  const SettledBed bed = settle_bed(small, place_particles(small.particles, small.cavity, small.host.z0_m));
  SoftEngine engine(small, bed.particles);
  CHECK(worst_balance_error(engine, 0.3, 0.001) < 1e-4);
  const EnergyLedger e = engine.observe().energy;
  CHECK(e.dissipated_impact_J > 0);
  CHECK(e.dissipated_friction_J > 0);
  // The particles take far more energy out than the host's damper does by itself.
  CHECK(e.dissipated_impact_J + e.dissipated_friction_J > 0.3 * e.dissipated_viscous_J);
}

TEST_CASE("settling: the placement comes to rest on the floor and stays inside the cavity") {
  const Scenario s = scenario_from("[particles]\ncount = 150\n[cavity]\ndiameter_m = 0.008\nheight_m = 0.008\n");
  const Particles placed = place_particles(s.particles, s.cavity, s.host.z0_m);
  const SettledBed bed = settle_bed(s, placed);
  CHECK(bed.settle_time_s >= std::sqrt(2 * 0.008 / 9.81));
  CHECK(bed.settle_time_s < 1.0);
  const Cavity cavity(s.cavity);
  double top = 0.0;
  for (Eigen::Index i = 0; i < bed.particles.size(); ++i) {
    CHECK(cavity.clearance_m(bed.particles.position_m.col(i), bed.particles.radius_m[i], s.host.z0_m) > -2e-6);
    top = std::max(top, bed.particles.position_m(2, i) - s.host.z0_m);
  }
  // 150 spheres of 0.88 mm fill well under half of the 8 mm hole once settled.
  CHECK(top < 0.004);
  // The bed rests on overlaps of a tiny fraction of a radius; separating them for a hard-
  // sphere start moves no sphere by as much as 1 % of a radius (the overlaps of ~5 layers add up).
  Particles hard_start = bed.particles;
  const double moved = separate_overlaps(hard_start, s.cavity, s.host.z0_m);
  CHECK(moved > 0.0);
  CHECK(moved < 0.01 * 0.00044);
  // Without gravity there is nothing to settle.
  const Scenario weightless = scenario_from(s.canonical_text, {"gravity.g_m_s2=0"});
  CHECK(settle_bed(weightless, placed).settle_time_s == 0.0);
}

TEST_CASE("threads: one or two, the results are the same bits") {
  const Scenario s = load_scenario(test::scenario_file("small"),
                                   {"particles.count=600", "particles.diameter_m=0.001", "cavity.diameter_m=0.016"});
  Particles bed = place_particles(s.particles, s.cavity, s.host.z0_m);
  bed.velocity_m_s = Eigen::Matrix3Xd::Random(3, bed.size());  // collisions from the first step
  auto run_on = [&](int threads) {
    omp_set_num_threads(threads);
    SoftEngineOptions shared;
    shared.parallel_minimum_spheres = 500;  // a bed this small would run on one thread by default
    SoftEngine engine(s, bed, shared);
    engine.advance_to(1000 * engine.time_step_s());
    CHECK(engine.observe().counters.contacts > 50);
    CHECK(test::statistic(engine, "threads_used") == threads);
    return engine.state();
  };
  const int before = omp_get_max_threads();
  const State one = run_on(1), two = run_on(2);
  omp_set_num_threads(before);
  CHECK(one.particles.position_m == two.particles.position_m);
  CHECK(one.particles.angular_velocity_rad_s == two.particles.angular_velocity_rad_s);
  CHECK(one.observation.host.z_m == two.observation.host.z_m);
  CHECK(one.observation.energy.dissipated_friction_J == two.observation.energy.dissipated_friction_J);
  CHECK(one.observation.energy.contact_elastic_J == two.observation.energy.contact_elastic_J);
}

TEST_CASE("an impact the contact law cannot stop fails the run and says why") {
  // At 60 m/s the paper's k_n stops a 1 mm lead sphere only 1.3 mm deep, its centre
  // beyond the floor (Table 4 at 500 Hz from 10 mm is like this). The run observes every
  // microsecond here; the engine checks at every observation.
  const Scenario s = scenario_from(wide_cavity, {"particles.count=1"});
  SoftEngine engine(s, spheres({{0.001, 0.0, 0.0006}}, {{0.0, 0.0, -60.0}}), held());
  auto observe_each_microsecond = [&] {
    for (int k = 1; k <= 100; ++k) engine.advance_to(1e-6 * k);
  };
  CHECK_THROWS_WITH_AS(observe_each_microsecond(), doctest::Contains("the contact law is too soft"), RuntimeFailure);
}

TEST_CASE("SIMD paths: one this build or CPU cannot run is refused, saying which are valid") {
  // An unoptimised build runs sse2 only (the wide kernels need inlining); sse2 always runs.
  CHECK(is_available(SimdPath::sse2));
  for (const SimdPath path : {SimdPath::sse2, SimdPath::avx2, SimdPath::avx512}) {
    CAPTURE(to_string(path));
    if (is_available(path)) {
      CHECK_NOTHROW(require_available(path, "--simd"));
    } else {
      CHECK_THROWS_WITH_AS(require_available(path, "--simd"), doctest::Contains("(valid here: sse2"), InputError);
    }
  }
}

TEST_CASE("SIMD paths: every instruction set the CPU runs gives the same bits") {
  // An agitated bed of three full chunks and a partial one, against the walls and each other.
  const Scenario s = load_scenario(test::scenario_file("small"),
                                   {"particles.count=230", "particles.diameter_m=0.001", "cavity.diameter_m=0.008"});
  Particles bed = place_particles(s.particles, s.cavity, s.host.z0_m);
  bed.velocity_m_s = Eigen::Matrix3Xd::Random(3, bed.size());
  bed.angular_velocity_rad_s = 300.0 * Eigen::Matrix3Xd::Random(3, bed.size());
  auto run_on = [&](SimdPath path) {
    SoftEngineOptions options;
    options.simd_path = path;
    SoftEngine engine(s, bed, options);
    engine.advance_to(2000 * engine.time_step_s());
    CHECK(engine.observe().counters.contacts > 20);
    return engine.state();
  };
  const State reference = run_on(SimdPath::sse2);
  int compared = 0;
  for (const SimdPath path : {SimdPath::avx2, SimdPath::avx512}) {
    if (!is_available(path)) continue;
    ++compared;
    CAPTURE(to_string(path));
    const State other = run_on(path);
    test::check_same_state(other, reference);
  }
  // CTest reports a test whose output says [skipped] as skipped (tests/CMakeLists.txt).
  if (compared == 0) MESSAGE("[skipped] this build or CPU runs sse2 only: no other path to compare with");
}

namespace {

/// Overlap of the Hertz-dashpot contact at `t_s` after it begins at `speed_m_s`, by RK4 far
/// finer than any engine step.
double reference_overlap_m(double effective_mass_kg, double kn, double cn, double speed_m_s, double t_s) {
  test::HertzDashpotContact contact{effective_mass_kg, kn, cn, 0.0, speed_m_s};
  for (long k = std::lround(t_s / reference_dt_s); k > 0; --k) contact.step(reference_dt_s);
  return contact.delta;
}

}  // namespace

TEST_CASE(
    "a stiff dashpot sets the automatic step, which follows the Hertz-dashpot contact, and a step past its limit is "
    "refused") {
  // Such dashpots overdamp the paper's soft Hertz spring: the sphere stops within m/c and
  // then creeps out of the floor for far longer than the 0.1 ms compared here.
  const double m = 9000 * 4.0 / 3.0 * std::numbers::pi * 1.25e-10;  // 1 mm lead
  const double r = 0.0005, speed = 0.5, gap = 1e-6, compared_s = 1e-4;
  for (const double cn : {1.0, 10.0}) {
    CAPTURE(cn);
    const Scenario s = scenario_from(wide_cavity, {"particles.count=1", "soft.cn_N_s_m=" + std::to_string(cn)});
    // The sphere-sphere pair (m* = m/2) relaxes fastest: tau = m / 2 c_n, and auto takes tau/10.
    const Relaxation tau = shortest_relaxation(s);
    CHECK(tau.time_s == test::relative(0.5 * m / cn));
    CHECK(tau.what.find("soft.cn_N_s_m") != std::string::npos);
    CHECK(choose_time_step_s(s) == tau.time_s / 10);
    // Without the dashpot's limit the step was T_s/8: at c_n = 10, c_n dt / m* = 2.4 > 2,
    // where each step reverses the approach speed and amplifies it.
    if (cn == 10.0) CHECK(shortest_tangential_period_s(s) / 8 / tau.time_s > 2);
    // The contact begins on a step: touching at t = 0.
    SoftEngine engine(s, spheres({{0.001, 0.0, r}}, {{0.0, 0.0, -speed}}, r), held());
    const double e0 = engine.observe().energy.stored_J();
    engine.advance_to(compared_s);
    const double overlap = r - engine.state().particles.position_m(2, 0);
    CHECK(overlap == test::relative(reference_overlap_m(m, 3.6e5, cn, speed, compared_s)).epsilon(0.01));
    CHECK(engine.observe().energy.balance_relative_error(e0) < 1e-3);
    // One that begins within a step stops short by the part of that step before the touch
    // (the dashpot acts over the whole step): up to v dt, 5 % of the depth m v / c_n here.
    SoftEngine late(s, spheres({{0.001, 0.0, r + gap}}, {{0.0, 0.0, -speed}}, r), held());
    late.advance_to(gap / speed + compared_s);
    const double late_overlap = r - late.state().particles.position_m(2, 0);
    CHECK(late_overlap <= overlap);
    CHECK(late_overlap >= overlap - speed * late.time_step_s());
    std::ostringstream step;
    step << "run.dt_s=" << 0.51 * tau.time_s;
    CHECK_THROWS_WITH_AS(choose_time_step_s(scenario_from(s.canonical_text, {step.str()})),
                         doctest::Contains("soft.cn_N_s_m relaxes in tau = m/c"), InputError);
  }
  // The tangential dashpot on m_t = m/7, and the host's damper on M, likewise.
  CHECK(shortest_relaxation(scenario_from(wide_cavity, {"soft.cs_N_s_m=10"})).what.find("soft.cs_N_s_m") !=
        std::string::npos);
  CHECK(shortest_relaxation(scenario_from(wide_cavity, {"host.damping_N_s_m=1e6"})).time_s == 0.0376 / 1e6);
  // A prescribed host has no damper to resolve.
  const Scenario prescribed = scenario_from(
      "[host]\ndamping_N_s_m = 0.1\n[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = 50\n");
  CHECK(shortest_relaxation(prescribed).what.find("host") == std::string::npos);
}

TEST_CASE("at the refusal limit a sticking contact's spring and dashpot together stay stable") {
  // c_s chosen so that T_s/4 = tau_t/2: the step at the limit has Omega = pi/2 and
  // gamma = 1/2, Omega^2 + 2 gamma = 3.47 < 4 (time_step.hpp).
  const double m = 9000 * 4.0 / 3.0 * std::numbers::pi * 1.25e-10;
  const Scenario base = scenario_from(wide_cavity, {"particles.count=1"});
  const double ts = shortest_tangential_period_s(base);  // the pair's, on m/7
  std::ostringstream cs;
  cs.precision(17);
  cs << "soft.cs_N_s_m=" << 2.0 * (m / 7.0) / ts;
  const Scenario probe = scenario_from(wide_cavity, {"particles.count=1", cs.str()});
  CHECK(shortest_relaxation(probe).time_s == test::relative(ts / 2));
  std::ostringstream dt;
  dt.precision(17);
  dt << "run.dt_s=" << ts / 4 * (1 - 1e-12);
  const Scenario s = scenario_from(probe.canonical_text, {dt.str()});
  // A sliding drop that sticks as it rolls: the tangential spring and dashpot work together.
  SoftEngine engine(s, spheres({{0.001, 0.0, 0.0005 + 1e-6}}, {{0.3, 0.0, -0.5}}), held());
  const double e0 = engine.observe().energy.stored_J();
  for (int k = 1; k <= 200; ++k) engine.advance_to(k * 1e-5);
  const EnergyLedger e = engine.observe().energy;
  CHECK(std::isfinite(e.stored_J()));
  CHECK(e.stored_J() + e.dissipated_J() <= e0 * (1 + 1e-2));
  CHECK(e.stored_J() < e0);
}

TEST_CASE("a state that stops being finite fails the engine with the reason, wherever it shows") {
  const Scenario s = scenario_from(wide_cavity);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  SoftEngine engine(s, spheres({{0.002, 0.0, 0.005}, {-0.004, 0.0, 0.005}}, {{0.0, 0.0, nan}, {0.0, 0.0, 0.0}}),
                    held());
  CHECK_THROWS_WITH_AS(engine.advance_to(1e-4), doctest::Contains("state stopped being finite"), RuntimeFailure);
  // Far off but finite: the neighbour list still finds a cell for it.
  SoftEngine far(s, spheres({{0.002, 0.0, 0.005}}, {{0.0, 0.0, 1e300}}), held());
  CHECK_THROWS_AS(far.advance_to(1e-4), RuntimeFailure);
}

TEST_CASE("a stop request ends advance_to within a step, and settling with it") {
  const Scenario s = load_scenario(test::scenario_file("small"));
  const Particles placement = place_particles(s.particles, s.cavity, s.host.z0_m);
  std::atomic<bool> stop{true};
  SoftEngine engine(s, placement);
  engine.set_stop_request(&stop);
  CHECK_THROWS_AS(engine.advance_to(10.0), Interrupted);
  CHECK(engine.observe().counters.time_steps == 0);
  CHECK_THROWS_WITH_AS(settle_bed(s, placement, &stop), doctest::Contains("settling"), Interrupted);
}
