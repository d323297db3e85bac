/// The event-driven hard-sphere engine: conservation laws, the energy ledger, resting
/// beds, determinism and the overlap invariant.
#include <doctest/doctest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <fstream>
#include <numbers>
#include <random>

#include "benchmark_gas.hpp"
#include "hard/hard_engine_class.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/model/placement.hpp"
#include "pdamp/sim/run.hpp"
#include "pdamp/simd/simd_path.hpp"
#include "test_support.hpp"

using namespace pdamp;
using hard::HardEngine;

namespace {

/// Spheres placed by the shared placement, with random velocities of one speed and random spins.
/// The shared placement, with the cavity where the host starts.
Particles placed(const Scenario& s) { return place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m); }

Particles moving_spheres(const Scenario& s, double speed_m_s, double spin_rad_s, std::uint64_t seed) {
  Particles p = placed(s);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    const Eigen::Vector3d direction = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
    p.velocity_m_s.col(i) = speed_m_s * direction;
    p.angular_velocity_rad_s.col(i) = spin_rad_s * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  }
  return p;
}

constexpr double jam_radius_m = 0.0006;

/// The `count` sites of a face-centred cubic packing of touching spheres of radius r
/// nearest the origin, nearest first.
std::vector<Eigen::Vector3d> fcc_sites_nearest_origin(int count, double r) {
  std::vector<Eigen::Vector3d> sites;
  const double edge = 2 * r * std::sqrt(2.0);
  for (int x = -3; x <= 3; ++x) {
    for (int y = -3; y <= 3; ++y) {
      for (int z = -3; z <= 3; ++z) {
        for (const Eigen::Vector3d& o : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.5, 0.5, 0),
                                         Eigen::Vector3d(0.5, 0, 0.5), Eigen::Vector3d(0, 0.5, 0.5)}) {
          sites.emplace_back(edge * (Eigen::Vector3d(x, y, z) + o));
        }
      }
    }
  }
  std::stable_sort(sites.begin(), sites.end(),
                   [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return a.norm() < b.norm() - 1e-12; });
  sites.resize(static_cast<std::size_t>(count));
  return sites;
}

/// Spheres of jam_radius_m at `sites` + `offset`, jostling at ~3 mm/s and spinning at
/// ~3000 rad/s; the last one 1000 times heavier than the rest, to drive into them.
Particles jammable_cluster(const std::vector<Eigen::Vector3d>& sites, const Eigen::Vector3d& offset) {
  const auto n = static_cast<Eigen::Index>(sites.size());
  Particles p(n);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> normal;
  for (Eigen::Index i = 0; i < n; ++i) {
    p.radius_m[i] = jam_radius_m;
    p.mass_kg[i] = 3.5e-6;
    p.position_m.col(i) = sites[static_cast<std::size_t>(i)] + offset;
    p.velocity_m_s.col(i) = 0.003 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    p.angular_velocity_rad_s.col(i) = 3000.0 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  }
  p.mass_kg[n - 1] *= 1000.0;
  return p;
}

/// The benchmark's gas (pdamp_bench) at solid fraction 0.3, with fixed walls.
Scenario benchmark_gas(int n) { return bench::benchmark_gas(n, 0.3, false); }

}  // namespace

TEST_CASE(
    "elastic frictionless gas at solid fraction 0.3: energy conserved to 1e-12 over 10^7 collisions, Maxwell-Boltzmann "
    "velocities") {
  // The conservation target on the benchmark's gas, 1,000 spheres all at one
  // speed to start.
  const Scenario s = benchmark_gas(1000);
  HardEngine engine(s, moving_spheres(s, 1.0, 0.0, 5));
  const double e0 = test::kinetic_energy(engine.state().particles);
  // A chunk holds about 10 collisions per sphere (mean free time ~0.1 ms at 1 m/s), so
  // the velocities sampled at successive chunks are nearly independent.
  constexpr double chunk_s = 1e-3;
  double worst_energy_error = 0.0, worst_overlap_m = 0.0;
  std::vector<double> components;
  double t = 0.0;
  while (engine.collisions() < 10'000'000) {
    engine.advance_to(t += chunk_s);
    const Particles p = engine.state().particles;
    worst_energy_error = std::max(worst_energy_error, std::abs(test::kinetic_energy(p) - e0) / e0);
    worst_overlap_m = std::max(worst_overlap_m, engine.max_overlap_m());
    if (engine.collisions() < 100'000) continue;  // relaxing from one speed
    for (Eigen::Index i = 0; i < p.size(); ++i) {
      for (int axis = 0; axis < 3; ++axis) components.push_back(p.velocity_m_s(axis, i));
    }
  }
  CHECK(worst_energy_error <= 1e-12);
  CHECK(worst_overlap_m <= engine.overlap_tolerance_m());
  MESSAGE("energy error " << worst_energy_error << " over " << engine.collisions() << " collisions");

  // Gaussian components of one variance in every direction (a gas in a closed box has
  // no drift): kurtosis 3, 68.27 % within one standard deviation, and the empirical
  // distribution within Kolmogorov–Smirnov distance 2e-3 of the normal one. With ~3e6
  // samples the statistical spread of these is ~1e-3 of each, ~3e-4 and ~5e-4 (the
  // microcanonical gas of 1,000 spheres differs from Gaussian by O(1/N) ≈ 1e-3 in its
  // kurtosis).
  const auto count = static_cast<double>(components.size());
  std::array<double, 3> axis_second{};
  double second = 0, fourth = 0;
  for (std::size_t k = 0; k < components.size(); ++k) {
    const double v2 = components[k] * components[k];
    axis_second[k % 3] += v2;
    second += v2;
    fourth += v2 * v2;
  }
  second /= count;
  fourth /= count;
  for (const double a : axis_second) CHECK(a / (count / 3) == test::relative(second).epsilon(0.01));
  CHECK(fourth / (second * second) == doctest::Approx(3.0).scale(1.0).epsilon(0.006));
  const double sigma = std::sqrt(second);
  std::sort(components.begin(), components.end());
  double ks = 0.0, within_sigma = 0.0;
  for (std::size_t k = 0; k < components.size(); ++k) {
    const double normal_cdf = 0.5 * std::erfc(-components[k] / (sigma * std::numbers::sqrt2));
    ks = std::max({ks, std::abs(normal_cdf - static_cast<double>(k) / count),
                   std::abs(normal_cdf - static_cast<double>(k + 1) / count)});
    within_sigma += std::abs(components[k]) < sigma ? 1.0 : 0.0;
  }
  CHECK(within_sigma / count == doctest::Approx(0.6827).scale(1.0).epsilon(0.003));
  CHECK(ks <= 2e-3);
  CHECK(test::statistic(engine, "events_wall") > 0);
  CHECK(test::statistic(engine, "events_cap") > 0);
  MESSAGE("kurtosis " << fourth / (second * second) << ", within one sigma " << within_sigma / count
                      << ", Kolmogorov-Smirnov distance " << ks);
}

TEST_CASE("the gas of 10^5 spheres, where the engine prefetches records and cells: energy conserved, no overlaps") {
  // The prefetches are hints and change no result; this runs the paths they sit on (and,
  // under the sanitizers, the addresses they form) where they are on. All spheres start
  // at one speed: a plain sum of their 10^5 equal energies is off by ~10^-12 of itself,
  // which the ledger's compensated sums are not (a plain sum here read 1.6e-12).
  const Scenario s = benchmark_gas(100'000);
  HardEngine engine(s, moving_spheres(s, 1.0, 0.0, 11));
  if (!engine.prefetching()) MESSAGE("this machine's L2 holds the records and cells of 10^5 spheres: no prefetching");
  const double e0 = engine.observe().energy.stored_J();
  double worst_energy_error = 0.0;
  double t = 0.0;
  while (engine.collisions() < 300'000) {
    engine.advance_to(t += 1e-4);  // about 3·10^4 collisions
    worst_energy_error = std::max(worst_energy_error, std::abs(engine.observe().energy.stored_J() - e0) / e0);
    CHECK(engine.max_overlap_m() <= engine.overlap_tolerance_m());
  }
  CHECK(worst_energy_error <= 1e-14);
  CHECK(test::statistic(engine, "events_sphere_sphere") >= 300'000 * 9 / 10);
  MESSAGE("energy error " << worst_energy_error << " over " << engine.collisions() << " collisions");
}

TEST_CASE("angular momentum about the origin is conserved by a frictional sphere-sphere collision") {
  Scenario s = test::fixed_walls(
      "[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = 0.02\nheight_m = 0.02\n"
      "[particles]\ncount = 2\ndiameter_m = 0.001\n[hard]\nen = 0.6\nmu = 0.3\nbeta0 = 0.4\n");
  Particles p(2);
  for (int i = 0; i < 2; ++i) {
    p.radius_m[i] = 0.0005;
    p.mass_kg[i] = 4e-6 * (1 + i);
  }
  p.position_m.col(0) = Eigen::Vector3d(-0.002, 0.0003, 0.01);
  p.position_m.col(1) = Eigen::Vector3d(0.002, -0.0002, 0.0102);
  p.velocity_m_s.col(0) = Eigen::Vector3d(0.5, 0.02, 0.01);
  p.velocity_m_s.col(1) = Eigen::Vector3d(-0.4, 0.0, -0.03);
  p.angular_velocity_rad_s.col(0) = Eigen::Vector3d(100, -50, 300);
  p.angular_velocity_rad_s.col(1) = Eigen::Vector3d(-200, 80, 10);
  HardEngine engine(s, p);
  const Eigen::Vector3d l0 = test::angular_momentum(engine.state().particles);
  engine.advance_to(0.006);  // one collision, no wall reached
  REQUIRE(test::statistic(engine, "events_sphere_sphere") == 1);
  REQUIRE(test::statistic(engine, "events_wall") + test::statistic(engine, "events_cap") == 0);
  const Particles after = engine.state().particles;
  CHECK((test::angular_momentum(after) - l0).norm() <= 1e-15 * l0.norm());
  CHECK(engine.observe().energy.dissipated_friction_J > 0.0);
}

// The energy books in every mode are the contract's (test_engine_contract.cpp).
TEST_CASE("no overlaps in any excitation mode") {
  for (const auto& mode : test::excitation_modes()) {
    CAPTURE(mode.empty() ? std::string("free") : mode[0]);
    const Scenario s = load_scenario(test::scenario_file("small"), mode);
    HardEngine engine(s, placed(s));
    for (int k = 1; k <= 100; ++k) {
      engine.advance_to(0.001 * k);
      REQUIRE(engine.max_overlap_m() <= engine.overlap_tolerance_m());
    }
    CHECK(engine.observe().energy.dissipated_impact_J > 0);
  }
}

namespace {

/// One sphere of diameter 2 mm dropped from `height_m` on a floor moving as z = A sin(ωt),
/// with e_n = 0.3: a ball that bounces this inelastically chatters to rest on the floor
/// in every cycle (the classic bouncing ball), which makes its lift-offs countable.
struct BouncingBall {
  Scenario scenario;
  BouncingBall(double gamma, double frequency_hz, double height_m) {
    const double w = 2 * std::numbers::pi * frequency_hz;
    scenario = test::scenario_from(
        "[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = " + std::to_string(frequency_hz) +
        "\n[cavity]\ndiameter_m = 0.01\nheight_m = 0.03\n[particles]\ncount = 1\n"
        "diameter_m = 0.002\n[hard_wall]\nen = 0.3\n");
    scenario.excitation.amplitude_m = gamma * 9.81 / (w * w);
    drop_height_m = height_m;
  }
  double drop_height_m;
  Particles ball() const {
    Particles p(1);
    p.radius_m[0] = 0.001;
    p.mass_kg[0] = 1e-5;
    p.position_m.col(0) = Eigen::Vector3d(0.0005, 0.0, 0.001 + drop_height_m);
    p.velocity_m_s.col(0) = Eigen::Vector3d(0.01, 0.0, 0.0);
    return p;
  }
};

}  // namespace

TEST_CASE("resting: a ball dropped on a floor vibrating below Gamma = 1 comes to rest and rides with it") {
  const BouncingBall setup(0.5, 30.0, 0.005);
  HardEngine engine(setup.scenario, setup.ball());
  engine.advance_to(1.0);
  CHECK(engine.riding_count() == 1);
  const std::int64_t collisions = engine.collisions();
  CHECK(collisions < 200);  // bounces die out geometrically, then it rides: no more events
  engine.advance_to(3.0);
  CHECK(engine.collisions() == collisions);
  const State st = engine.state();
  CHECK(st.particles.velocity_m_s(2, 0) == st.observation.host.v_m_s);
  // On the scale of the sum's terms: the host may sit near -1 mm.
  CHECK(
      st.particles.position_m(2, 0) ==
      doctest::Approx(st.observation.host.z_m + 0.001).scale(std::abs(st.observation.host.z_m) + 0.001).epsilon(1e-9));
  CHECK(test::statistic(engine, "bed_releases") == 0);
  const EnergyLedger e = engine.observe().energy;
  CHECK(e.balance_relative_error(HardEngine(setup.scenario, setup.ball()).observe().energy.stored_J()) <= 1e-9);
}

TEST_CASE("resting: just above Gamma = 1 the ball lifts off the floor every cycle") {
  const BouncingBall above(1.2, 30.0, 0.002);
  HardEngine engine(above.scenario, above.ball());
  engine.advance_to(1.0);
  const std::int64_t releases = test::statistic(engine, "bed_releases");
  engine.advance_to(2.0);
  CHECK(test::statistic(engine, "bed_releases") - releases >= 20);  // 30 cycles in that second
  CHECK(engine.max_overlap_m() <= engine.overlap_tolerance_m());
  const BouncingBall below(0.9, 30.0, 0.002);
  HardEngine calm(below.scenario, below.ball());
  calm.advance_to(2.0);
  CHECK(test::statistic(calm, "bed_releases") == 0);
  CHECK(calm.riding_count() == 1);
}

TEST_CASE(
    "resting: a settled bed under Gamma < 1 rides with the host, which rings at sqrt(K/(M+m_p))/2pi, and a 10 s decay "
    "finishes") {
  // 60 spheres (7.7 g) on the Table 1 host released from z0 = 0.5 mm: Gamma = z0 K/(M g) = 0.64.
  const Scenario s = test::scenario_from(
      "[host]\nz0_m = 0.0005\n[cavity]\ndiameter_m = 0.012\nheight_m = 0.01\n"
      "[particles]\ncount = 60\ndiameter_m = 0.0015\n");
  const Particles initial = placed(s);
  HardEngine engine(s, initial);
  engine.advance_to(2.0);
  CHECK(engine.riding_count() == 60);
  const std::int64_t settled_events = engine.collisions();
  // Zero crossings of the host about the bed-loaded equilibrium over 2 .. 4 s.
  const double m_p = initial.total_mass_kg();
  const double equilibrium = m_p * s.gravity_m_s2.z() / s.host.stiffness_N_m;
  std::vector<double> crossings;
  double previous = engine.observe().host.z_m - equilibrium;
  const double dt = 1e-4;
  for (double t = 2.0 + dt; t <= 4.0; t += dt) {
    engine.advance_to(t);
    const double now = engine.observe().host.z_m - equilibrium;
    if (previous < 0 && now >= 0) crossings.push_back(t - dt * now / (now - previous));
    previous = now;
  }
  REQUIRE(crossings.size() >= 10);
  const double measured = static_cast<double>(crossings.size() - 1) / (crossings.back() - crossings.front());
  const double loaded = std::sqrt(s.host.stiffness_N_m / (s.host.mass_kg + m_p)) / (2 * std::numbers::pi);
  CHECK(measured == doctest::Approx(loaded).scale(1.0).epsilon(2e-3));
  engine.advance_to(10.0);
  CHECK(engine.collisions() - settled_events < 1000);
  CHECK(engine.max_overlap_m() <= engine.overlap_tolerance_m());
}

TEST_CASE("overlapping initial spheres (a soft-settled bed) are pushed just apart, and a large push is reported") {
  const Scenario s = test::fixed_walls("[particles]\ncount = 2\ndiameter_m = 0.001\n");
  Particles p(2);
  for (int i = 0; i < 2; ++i) p.radius_m[i] = 0.0005, p.mass_kg[i] = 1e-6;
  p.position_m.col(0) = Eigen::Vector3d(0, 0, 0.002);
  p.position_m.col(1) = Eigen::Vector3d(0.00099999, 0, 0.002);  // 10 nm overlap: a resting soft contact
  const HardEngine slight(s, p);
  CHECK(slight.max_overlap_m() == 0.0);
  CHECK(slight.warnings().empty());
  p.position_m.col(1) = Eigen::Vector3d(0.0009, 0, 0.002);  // 100 um
  const HardEngine pushed(s, p);
  CHECK(pushed.max_overlap_m() == 0.0);
  REQUIRE(pushed.warnings().size() == 1);
  CHECK(pushed.warnings()[0].find("overlapped") != std::string::npos);
}

TEST_CASE("a host impulse cannot drive a cap into a sphere that touches it while receding") {
  // Regression: a sphere within a tier's margin of a cap but receding (a bed just released
  // from the top cap) stayed in the outer tier, whose host_margin event is a lower bound on
  // contact only for a host that strays less than the sphere's gap, not the margin. A host
  // impulse (here another sphere hitting the top cap) then drove the floor into it unseen.
  // A free host (10 rad/s) carrying sphere A on its floor, A moving with the floor and
  // receding from it only as the host decelerates (no gravity); sphere B hits the top cap
  // after 0.4 ms and pushes the host up by 1.6e-4 m/s, far within the outer tier's budget.
  const Scenario s = test::scenario_from(
      "[host]\nmass_kg = 0.01\nstiffness_N_m = 1\ndamping_N_s_m = 0\nz0_m = 0\nv0_m_s = 0.1\n"
      "[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = 0.008\nheight_m = 0.006\n"
      "[particles]\ncount = 2\ndiameter_m = 0.0015\n[hard]\nen = 1\nmu = 0\n[hard_wall]\nen = 1\nmu = 0\n");
  const double r = 0.00075;
  Particles p(2);
  for (int i = 0; i < 2; ++i) p.radius_m[i] = r, p.mass_kg[i] = 1.6e-5;
  p.position_m.col(0) = Eigen::Vector3d(-0.002, 0, r);                // A: touching the floor
  p.velocity_m_s.col(0) = Eigen::Vector3d(0, 0, 0.1);                 // the floor's velocity
  p.position_m.col(1) = Eigen::Vector3d(0.002, 0, 0.006 - r - 2e-5);  // B: 20 um below the top cap
  p.velocity_m_s.col(1) = Eigen::Vector3d(0, 0, 0.15);                // closing at 0.05 m/s
  HardEngine engine(s, p);
  for (int k = 1; k <= 200; ++k) {
    engine.advance_to(5e-6 * k);
    REQUIRE(engine.max_overlap_m() <= engine.overlap_tolerance_m());
  }
  CHECK(test::statistic(engine, "events_cap") >= 2);  // B on the top cap, then the floor catches A
}

TEST_CASE(
    "touching spheres keep their predictions through host impulses that move the walls away, and nothing overlaps") {
  // The small damper: spheres raining on the riding bed push the host down at most
  // impulses, which moves the floor and the bed away from the spheres touching them; those
  // predictions stand as lower bounds (touching_deferrals) instead of being redone. A
  // missed contact would show as an overlap: checked every 20 us.
  const Scenario s = load_scenario(test::scenario_file("small"));
  HardEngine engine(s, placed(s));
  const double e0 = engine.observe().energy.stored_J();
  for (int k = 1; k <= 10000; ++k) {
    engine.advance_to(2e-5 * k);
    REQUIRE(engine.max_overlap_m() <= engine.overlap_tolerance_m());
  }
  CHECK(test::statistic(engine, "touching_deferrals") > 1000);
  CHECK(test::statistic(engine, "touching_repredictions") > 0);  // the impulses that move walls towards them
  CHECK(engine.observe().energy.balance_relative_error(e0) <= 1e-9);
}

TEST_CASE(
    "jam: a heavy sphere driven into a touching cluster in flight merges the wedged spheres instead of colliding "
    "without end") {
  // 54 touching spheres (the sites of a face-centred cubic packing nearest its centre),
  // spinning at ~3000 rad/s, and a 1000 times heavier sphere driven into them at 3 m/s,
  // like a cap into a dense bed: the pairwise collisions through the touching cluster
  // converge ever more slowly (300 000 of them before the jam rule); jammed spheres merge
  // into a rigid body instead. No gravity, walls out of reach.
  const Scenario s = test::fixed_walls(
      "[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = 0.05\nheight_m = 0.05\n"
      "[particles]\ncount = 55\ndiameter_m = 0.0012\n[hard]\nen = 0.154\nmu = 0.55\nbeta0 = 0.35\n");
  const std::vector<Eigen::Vector3d> sites = fcc_sites_nearest_origin(55, jam_radius_m);
  Particles p = jammable_cluster(sites, Eigen::Vector3d(0, 0, 0.025));
  p.velocity_m_s.col(54) = -3.0 * sites[54].normalized();
  HardEngine engine(s, p);
  auto momentum = [&] {
    const Particles q = engine.state().particles;
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    for (int i = 0; i < 55; ++i) total += q.mass_kg[i] * q.velocity_m_s.col(i);
    return total;
  };
  const Eigen::Vector3d p0 = momentum();
  const double e0 = engine.observe().energy.stored_J();
  for (int k = 1; k <= 10; ++k) {
    engine.advance_to(1e-5 * k);
    CHECK(engine.max_overlap_m() <= engine.overlap_tolerance_m());
  }
  CHECK(test::statistic(engine, "events_sphere_sphere") < 30000);
  CHECK(test::statistic(engine, "jam_merges") > 0);
  CHECK((momentum() - p0).norm() <= 1e-13 * p0.norm());
  CHECK(engine.observe().energy.balance_relative_error(e0) <= 1e-9);
  CHECK(engine.observe().energy.dissipated_friction_J > 0);
}

TEST_CASE("jam: a cluster driven against the side wall sticks to the host instead of colliding without end") {
  // The same cluster touching the side wall of a free host, and the heavy sphere driven
  // into it towards the wall. Merged into a rigid body, the wedged spheres would be driven
  // back into the wall at the same instant, and the wall back into them (Table 4 at 250 Hz
  // stalled so after 486 000 collisions at one instant); held by the wall, they stick to
  // the host. A free host with a negligible spring and no gravity: M v_h + Σ m v_z is
  // constant, the side wall's friction being the only vertical impulse.
  const Scenario s = test::scenario_from(
      "[host]\nmass_kg = 0.01\nstiffness_N_m = 1e-20\ndamping_N_s_m = 0\nz0_m = 0\nv0_m_s = 0\n"
      "[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = 0.012\nheight_m = 0.012\n"
      "[particles]\ncount = 55\ndiameter_m = 0.0012\n[hard]\nen = 0.154\nmu = 0.55\nbeta0 = 0.35\n"
      "[hard_wall]\nen = 0.3\nmu = 0.55\nbeta0 = 0.35\n");
  std::vector<Eigen::Vector3d> sites = fcc_sites_nearest_origin(54, jam_radius_m);
  const double edge = 2.0 * jam_radius_m * std::sqrt(2.0);
  sites.emplace_back(-2.0 * edge, 0, 0);  // the heavy sphere, 0.5 mm from the cluster
  // The sphere at (edge, 0, 0) touches the side wall (1 nm apart).
  const Eigen::Vector3d offset(0.006 - jam_radius_m - edge - 1e-9, 0, 0.006);
  Particles p = jammable_cluster(sites, offset);
  p.velocity_m_s.col(54) = Eigen::Vector3d(3.0, 0, 0);
  HardEngine engine(s, p);
  auto momentum = [&] {
    const State st = engine.state();
    double total = s.host.mass_kg * st.observation.host.v_m_s;
    for (int i = 0; i < 55; ++i) total += st.particles.mass_kg[i] * st.particles.velocity_m_s(2, i);
    return total;
  };
  const double p0 = momentum();
  const double scale = p.mass_kg[54] * 3.0;
  const double e0 = engine.observe().energy.stored_J();
  for (int k = 1; k <= 20; ++k) {
    engine.advance_to(2e-5 * k);
    CHECK(engine.max_overlap_m() <= engine.overlap_tolerance_m());
    CHECK(std::abs(momentum() - p0) <= 1e-13 * scale);
  }
  CHECK(test::statistic(engine, "jam_stuck_to_host") > 0);
  CHECK(test::statistic(engine, "events_sphere_sphere") + test::statistic(engine, "events_wall") < 30000);
  CHECK(engine.observe().energy.balance_relative_error(e0) <= 1e-9);
  test::check_dissipation_by_sphere(engine);  // the merges' and the sticking's losses shared out
  // The heavy sphere is stopped against the wedged spheres.
  const State end = engine.state();
  const Eigen::Vector3d relative =
      end.particles.velocity_m_s.col(54) - end.observation.host.v_m_s * Eigen::Vector3d::UnitZ();
  CHECK(relative.norm() <= 1e-4 * 3.0);
}

TEST_CASE("jam: Table 4's 250 Hz bed, hit by a cap at 15 m/s, gets past the wedges against the side wall") {
  // Regression: spheres wedged between the side wall and their neighbours collided
  // 486 000 times at t = 1.317 ms, each wall collision turning them back into a rigid
  // cluster that the jam rule drove into the wall again, and the run stalled. The bed is
  // the soft engine's settled one, and the run loop observes as `pdamp run` does (the
  // event sequence depends on those times at round-off level).
  Scenario s = load_scenario(test::scenario_file("table4_f250"));
  s.run.duration_s = 0.0015;
  std::ifstream file(test::source_dir() / "tests" / "data" / "table4_f250_settled_bed.txt");
  REQUIRE(file);
  file.ignore(std::numeric_limits<std::streamsize>::max(), '\n');  // the header
  Particles p(s.particles.count);
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    for (auto* column : {&p.position_m, &p.velocity_m_s, &p.angular_velocity_rad_s}) {
      file >> (*column)(0, i) >> (*column)(1, i) >> (*column)(2, i);
    }
    file >> p.radius_m[i] >> p.mass_kg[i];
  }
  REQUIRE(file);
  HardEngine engine(s, p);
  struct Discard final : RunRecorder {
    void record_sample(const Observation&, double) override {}
    void record_cycle(const CycleRecord&) override {}
    void flush() override {}
    void flush_with_checkpoint(const RunCheckpoint&) override {}
  } discard;
  const RunOutcome outcome = run_simulation(engine, s, discard);
  CHECK_MESSAGE(outcome.status == RunStatus::completed, outcome.message);
  CHECK(engine.max_overlap_m() <= engine.overlap_tolerance_m());
  CHECK(test::statistic(engine, "jam_stuck_to_host") > 0);
  CHECK(outcome.energy_balance_rel_err <= 1e-9);
  test::check_dissipation_by_sphere(engine);
}

TEST_CASE("a stop request ends advance_to within 4096 events, and run.max_events ends the run there") {
  Scenario s = benchmark_gas(200);
  std::atomic<bool> stop{false};
  {
    HardEngine engine(s, moving_spheres(s, 1.0, 0.0, 3));
    engine.set_stop_request(&stop);
    engine.advance_to(0.01);
    const std::int64_t before = engine.collisions();
    CHECK(before > 4096);
    stop = true;
    CHECK_THROWS_AS(engine.advance_to(10.0), Interrupted);
    CHECK(engine.collisions() - before <= 4096);
  }
  s.run.max_events = 5000;
  HardEngine engine(s, moving_spheres(s, 1.0, 0.0, 3));
  CHECK_THROWS_WITH_AS(engine.advance_to(10.0), doctest::Contains("reached run.max_events = 5000"), RuntimeFailure);
  std::int64_t events = 0;
  for (const auto& [name, value] : engine.statistics()) {
    if (name.starts_with("events_")) events += value;
  }
  CHECK(events <= 5000);  // the one past the bound is popped, not handled
  CHECK(events > 4000);
}

TEST_CASE("SIMD paths: the hard engine gives the same bits on every instruction set the CPU runs (--simd)") {
  // The gas screens many neighbours per prediction: the screen of each path does the work.
  const Scenario s = benchmark_gas(1000);
  const Particles initial = moving_spheres(s, 1.0, 0.0, 7);
  auto run_on = [&](simd::SimdPath path) {
    simd::set_default_simd_path(path, "the test's path");
    HardEngine engine(s, initial);
    engine.advance_to(0.01);
    CHECK(engine.collisions() > 10'000);
    return engine.state();
  };
  const State reference = run_on(simd::SimdPath::sse2);
  int compared = 0;
  for (const simd::SimdPath path : {simd::SimdPath::avx2, simd::SimdPath::avx512}) {
    if (!simd::is_available(path)) continue;
    ++compared;
    CAPTURE(simd::to_string(path));
    test::check_same_state(run_on(path), reference);
  }
  simd::set_default_simd_path(simd::widest_simd_path(), "the test's path");
  // CTest reports a test whose output says [skipped] as skipped (tests/CMakeLists.txt).
  if (compared == 0) MESSAGE("[skipped] this build or CPU runs sse2 only: no other path to compare with");
}
