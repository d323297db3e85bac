/// The hard engine's jam resolution (JamResolver) on its own — the records of one
/// instant, the cluster, the rigid merge and the sticking to the host, each against the
/// conservation laws and the books — and in the engine: touching spheres driven into each
/// other, whose collisions at one instant must end.
#include <doctest/doctest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "hard/hard_engine_class.hpp"
#include "hard/jam_resolution.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::hard;

namespace {

/// A radius and contact distance that are powers of two: spheres placed whole contact
/// distances apart touch exactly, so that their collisions all fall at one instant.
constexpr double r_m = 0x1p-11;  // 0.49 mm
constexpr double sigma_m = 2 * r_m;
constexpr double mass_kg = 4e-6;

/// Spheres of radius r_m at `positions` moving at `velocities`, spinning at `spins`.
Particles spheres(const std::vector<Eigen::Vector3d>& positions, const std::vector<Eigen::Vector3d>& velocities,
                  const std::vector<Eigen::Vector3d>& spins = {}) {
  Particles p = test::spheres(positions, velocities, r_m);
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    p.mass_kg[i] = mass_kg;
    if (!spins.empty()) p.angular_velocity_rad_s.col(i) = spins[static_cast<std::size_t>(i)];
  }
  return p;
}

/// Three touching spheres in a triangle (a wedge), moving and spinning at random.
Particles wedge(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  auto random = [&](double scale) -> Eigen::Vector3d {
    return scale * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  };
  const Eigen::Vector3d apex(r_m, std::sqrt(3.0) * r_m, 0.0);
  return spheres({Eigen::Vector3d::Zero(), Eigen::Vector3d(sigma_m, 0, 0), apex},
                 {random(0.3), random(0.3), random(0.3)}, {random(500), random(500), random(500)});
}

/// The wedge's three collisions at one instant, the apex also against a cap.
JamResolver::Cluster merged_wedge_cluster(JamResolver& jams) {
  jams.note_collision(0, 1, 0.5);
  jams.note_collision(1, 2, 0.5);
  jams.note_collision(2, 0, 0.5);
  jams.note_collision(2, -1, 0.5, JamResolver::held_by_cap_or_bed);
  return jams.cluster_of(0, [](int) { return false; });
}

}  // namespace

TEST_CASE("jam records: a sphere is jammed once it collides more than 64 times at one instant") {
  JamResolver jams(4);
  double t = 1e-3;
  // One collision an instant, however many instants: never a jam.
  for (int k = 0; k < 200; ++k) CHECK_FALSE(jams.note_collision(0, 1, t += 1e-9));
  // The same pair at one instant: the 65th collision jams them.
  t += 1e-9;
  for (int k = 1; k <= JamResolver::repeats; ++k) REQUIRE_FALSE(jams.note_collision(0, 1, t));
  CHECK(jams.note_collision(0, 1, t));
  // Time moves on: the counts start again.
  CHECK_FALSE(jams.note_collision(0, 1, t + 1e-9));
  // Collisions with the host count too.
  t += 2e-9;
  for (int k = 1; k <= JamResolver::repeats; ++k)
    REQUIRE_FALSE(jams.note_collision(2, -1, t, JamResolver::held_by_side_wall));
  CHECK(jams.note_collision(2, -1, t, JamResolver::held_by_side_wall));
}

TEST_CASE("jam cluster: the free spheres linked by this instant's collisions, in order, with what holds them") {
  JamResolver jams(6);
  jams.note_collision(4, 1, 0.25);
  jams.note_collision(1, 3, 0.25);
  jams.note_collision(3, -1, 0.25, JamResolver::held_by_side_wall);
  jams.note_collision(0, 5, 0.25);  // another cluster at the same instant
  const JamResolver::Cluster cluster = jams.cluster_of(3, [](int) { return false; });
  CHECK(cluster.members == std::vector<int>{1, 3, 4});
  CHECK(cluster.hold == JamResolver::held_by_side_wall);
  // A sphere that has come to rest since is no longer part of it; the other cluster holds nothing.
  CHECK(jams.cluster_of(4, [](int j) { return j == 3; }).members == std::vector<int>{1, 4});
  const JamResolver::Cluster other = jams.cluster_of(5, [](int) { return false; });
  CHECK(other.members == std::vector<int>{0, 5});
  CHECK(other.hold == 0);
  // A collision at a later instant starts new records: the first one alone links nothing yet.
  jams.note_collision(4, 1, 0.5);
  CHECK(jams.cluster_of(4, [](int) { return false; }).members == std::vector<int>{4});
}

TEST_CASE("jam merge: a three-sphere wedge becomes one rigid body with its momentum and angular momentum") {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    CAPTURE(seed);
    JamResolver jams(3);
    PackedParticles p(wedge(seed));
    const Eigen::Vector3d p0 = test::momentum(p), l0 = test::angular_momentum(p);
    const double e0 = test::kinetic_energy(p);
    HardLedger ledger(3);
    jams.merge_rigidly(merged_wedge_cluster(jams), p, ledger);
    CHECK((test::momentum(p) - p0).norm() <= 1e-15 * p0.norm());
    CHECK((test::angular_momentum(p) - l0).norm() <= 1e-14 * l0.norm());
    // Rigid: one spin, and no pair approaches or recedes (nothing left to collide).
    for (int i = 0; i < 3; ++i) {
      CHECK((p.angular_velocity_rad_s.col(i) - p.angular_velocity_rad_s.col(0)).norm() == 0.0);
      const int j = (i + 1) % 3;
      const Eigen::Vector3d dx = p.position_m.col(j) - p.position_m.col(i);
      const Eigen::Vector3d dv = p.velocity_m_s.col(j) - p.velocity_m_s.col(i);
      CHECK(std::abs(dx.dot(dv)) <= 1e-14 * dx.norm() * (p.velocity_m_s.col(i).norm() + 1.0));
    }
    // The energy of the relative motion is the loss, split between impact and friction.
    const double loss = e0 - test::kinetic_energy(p);
    CHECK(loss > 0.0);
    CHECK(ledger.impact_J + ledger.friction_J == test::relative(loss).epsilon(1e-12));
    CHECK(ledger.impact_J >= 0.0);
    CHECK(ledger.friction_J >= 0.0);
    // Each sphere's share is the energy its own motion lost: they add up to the books.
    CHECK(ledger.by_sphere.impact_J.sum() == doctest::Approx(ledger.impact_J).scale(loss).epsilon(1e-14));
    CHECK(ledger.by_sphere.friction_J.sum() == doctest::Approx(ledger.friction_J).scale(loss).epsilon(1e-14));
    CHECK(ledger.by_sphere.impact_J.minCoeff() >= 0.0);
  }
}

TEST_CASE("jam merge: spheres closing along their line of centres without spin lose only to impact") {
  JamResolver jams(3);
  PackedParticles p(spheres({Eigen::Vector3d(-sigma_m, 0, 0), Eigen::Vector3d::Zero(), Eigen::Vector3d(sigma_m, 0, 0)},
                            {Eigen::Vector3d(1.0, 0, 0), Eigen::Vector3d(0.2, 0, 0), Eigen::Vector3d(-0.4, 0, 0)}));
  jams.note_collision(0, 1, 0.5);
  jams.note_collision(1, 2, 0.5);
  const double e0 = test::kinetic_energy(p);
  HardLedger ledger(3);
  jams.merge_rigidly(jams.cluster_of(1, [](int) { return false; }), p, ledger);
  for (int i = 0; i < 3; ++i) CHECK(p.velocity_m_s.col(i).isApprox(Eigen::Vector3d(0.8 / 3, 0, 0), 1e-15));
  CHECK(ledger.friction_J == 0.0);
  CHECK(ledger.impact_J == test::relative(e0 - test::kinetic_energy(p)).epsilon(1e-14));
}

TEST_CASE("jam sticking: a merged wedge held by a cap sticks to a free host, momentum and energy booked") {
  constexpr double host_mass_kg = 0.01, host_v_m_s = -0.05;
  for (const std::uint8_t hold :
       {std::uint8_t{JamResolver::held_by_cap_or_bed}, std::uint8_t{JamResolver::held_by_side_wall}}) {
    CAPTURE(static_cast<int>(hold));
    JamResolver jams(3);
    PackedParticles p(wedge(7));
    JamResolver::Cluster cluster = merged_wedge_cluster(jams);
    HardLedger ledger(3);
    jams.merge_rigidly(cluster, p, ledger);
    cluster.hold = hold;
    const HardLedger merged = ledger;
    const double vertical0 = host_mass_kg * host_v_m_s + test::momentum(p).z();
    const double body_vz = test::momentum(p).z() / (3 * mass_kg);
    const double horizontal_J = 0.5 * test::momentum(p).head<2>().squaredNorm() / (3 * mass_kg);
    const double vertical_J = 0.5 * (3 * mass_kg) * host_mass_kg / (3 * mass_kg + host_mass_kg) *
                              (body_vz - host_v_m_s) * (body_vz - host_v_m_s);
    const double e0 = test::kinetic_energy(p) + 0.5 * host_mass_kg * host_v_m_s * host_v_m_s;
    const double after = jams.stick_to_host(cluster, {0.0, host_v_m_s}, false, host_mass_kg, p, ledger).host_v_m_s;
    CHECK(host_mass_kg * after + test::momentum(p).z() == test::relative(vertical0).epsilon(1e-15));
    for (int i = 0; i < 3; ++i) {
      CHECK(p.velocity_m_s.col(i) == Eigen::Vector3d(0, 0, after));
      CHECK(p.angular_velocity_rad_s.col(i).isZero());
    }
    const double loss = e0 - test::kinetic_energy(p) - 0.5 * host_mass_kg * after * after;
    const double impact = ledger.impact_J - merged.impact_J, friction = ledger.friction_J - merged.friction_J;
    CHECK(impact + friction == test::relative(loss).epsilon(1e-12));
    CHECK(ledger.excitation_J == 0.0);
    // Impact is the part normal to the holding wall: the horizontal motion at the side
    // wall, the vertical at a cap; the rest (and the spin) is friction.
    CHECK(impact == test::relative(hold == JamResolver::held_by_side_wall ? horizontal_J : vertical_J).epsilon(1e-14));
    // The spheres' shares of it add up to the books.
    CHECK(ledger.by_sphere.impact_J.sum() - merged.by_sphere.impact_J.sum() == test::relative(impact).epsilon(1e-12));
    CHECK(ledger.by_sphere.friction_J.sum() - merged.by_sphere.friction_J.sum() ==
          test::relative(friction).epsilon(1e-12));
  }
}

TEST_CASE("jam sticking: a prescribed host keeps its velocity and does the work the body's energy change needs") {
  JamResolver jams(3);
  PackedParticles p(wedge(3));
  const JamResolver::Cluster cluster = merged_wedge_cluster(jams);
  HardLedger ledger(3);
  jams.merge_rigidly(cluster, p, ledger);
  const double e0 = test::kinetic_energy(p);
  const HardLedger merged = ledger;
  const double after = jams.stick_to_host(cluster, {0.0, 0.3}, true, 0.0, p, ledger).host_v_m_s;
  CHECK(after == 0.3);
  const double loss = ledger.impact_J - merged.impact_J + ledger.friction_J - merged.friction_J;
  CHECK(test::kinetic_energy(p) - e0 == test::relative(ledger.excitation_J - loss).epsilon(1e-12));
}

namespace {

/// A heavy sphere (1000 times the others' mass) driven at 1 m/s along x into `count`
/// spheres that touch it and each other in a line, without gravity, far from the walls;
/// e_n as given, no friction.
struct DrivenLine {
  Scenario scenario;
  Particles initial{0};
  DrivenLine(int count, double en) {
    scenario = test::fixed_walls(
        "[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = 0.03125\nheight_m = 0.03125\n"
        "[particles]\ncount = " +
        std::to_string(count + 1) + "\ndiameter_m = 0.001\n[hard]\nen = " + std::to_string(en) + "\nmu = 0\n");
    std::vector<Eigen::Vector3d> positions, velocities;
    const int middle = count / 2;  // at x = 0
    for (int k = 0; k <= count; ++k) {
      positions.emplace_back(sigma_m * (k - middle), 0, 0.015625);
      velocities.emplace_back(k == 0 ? 1.0 : 0.0, 0, 0);
    }
    initial = spheres(positions, velocities);
    initial.mass_kg[0] *= 1000.0;
  }
};

}  // namespace

TEST_CASE("jam in the engine: a sphere driven into two touching ones with e_n = 0 collapses, and they merge") {
  // Pairwise, the collisions at the instant of contact never end: each sphere takes half
  // the relative speed of the next, and 80 collisions bring it below 10^-12 m/s. The
  // middle sphere's 65th collision at the instant merges the three.
  const DrivenLine line(2, 0.0);
  hard::HardEngine engine(line.scenario, line.initial);
  const Eigen::Vector3d p0 = test::momentum(engine.state().particles);
  const double e0 = engine.observe().energy.stored_J();
  engine.advance_to(1e-3);
  CHECK(test::statistic(engine, "jam_merges") == 1);
  CHECK(test::statistic(engine, "jam_merged_spheres") == 3);
  CHECK(test::statistic(engine, "events_sphere_sphere") <= 2 * JamResolver::repeats);
  const Particles after = engine.state().particles;
  CHECK((test::momentum(after) - p0).norm() <= 1e-15 * p0.norm());
  for (int i = 1; i < 3; ++i) CHECK((after.velocity_m_s.col(i) - after.velocity_m_s.col(0)).norm() <= 1e-15);
  CHECK(engine.max_overlap_m() <= engine.overlap_tolerance_m());
  const EnergyLedger ledger = engine.observe().energy;
  CHECK(ledger.balance_relative_error(e0) <= 1e-12);
  // Frictionless, along the line of centres: all impact (friction to round-off of the split).
  CHECK(std::abs(ledger.dissipated_friction_J) <= 1e-12 * ledger.dissipated_impact_J);
}

TEST_CASE("jam in the engine: collapses end, by themselves where they converge fast, else by a merge") {
  // e_n = 0.154 (Table 4's spheres): two touching spheres stop taking the driver's impulses
  // after 44 collisions at the instant; three would need 194, with 130 on one sphere.
  for (const int count : {2, 3}) {
    CAPTURE(count);
    const DrivenLine line(count, 0.154);
    hard::HardEngine engine(line.scenario, line.initial);
    const double e0 = engine.observe().energy.stored_J();
    engine.advance_to(1e-3);
    const std::int64_t collisions = test::statistic(engine, "events_sphere_sphere");
    CHECK(collisions <= 2 * JamResolver::repeats);
    CHECK(test::statistic(engine, "jam_merges") == (count == 2 ? 0 : 1));
    CHECK(engine.max_overlap_m() <= engine.overlap_tolerance_m());
    CHECK(engine.observe().energy.balance_relative_error(e0) <= 1e-12);
    // Nothing approaches any more: every sphere moves ahead at least as fast as the one behind.
    const Particles after = engine.state().particles;
    for (Eigen::Index i = 1; i <= count; ++i) CHECK(after.velocity_m_s(0, i) >= after.velocity_m_s(0, i - 1) - 1e-12);
    MESSAGE(count << " spheres: " << collisions << " collisions");
  }
}

TEST_CASE("jam in the engine: a line driven against the side wall of a free host sticks to it") {
  // The line touches the side wall (x = R exactly) and moves up at 0.1 m/s besides, the
  // host (10 g, negligible spring, no gravity) at rest: the jam held by the wall sticks to
  // the host, which takes the line's vertical momentum; M v_h + Σ m v_z stays constant.
  Scenario s = test::scenario_from(
      "[host]\nmass_kg = 0.01\nstiffness_N_m = 1e-20\ndamping_N_s_m = 0\nz0_m = 0\nv0_m_s = 0\n"
      "[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = 0.03125\nheight_m = 0.03125\n"
      "[particles]\ncount = 3\ndiameter_m = 0.001\n[hard]\nen = 0\nmu = 0.5\nbeta0 = 0.3\n"
      "[hard_wall]\nen = 0\nmu = 0.5\nbeta0 = 0.3\n");
  constexpr double wall_m = 0.015625;
  Particles p =
      spheres({Eigen::Vector3d(wall_m - r_m - 2 * sigma_m, 0, 0.015625),
               Eigen::Vector3d(wall_m - r_m - sigma_m, 0, 0.015625), Eigen::Vector3d(wall_m - r_m, 0, 0.015625)},
              {Eigen::Vector3d(1.0, 0, 0.1), Eigen::Vector3d(0, 0, 0.1), Eigen::Vector3d(0, 0, 0.1)});
  p.mass_kg[0] *= 1000.0;
  hard::HardEngine engine(s, p);
  auto vertical_momentum = [&] {
    const State st = engine.state();
    return s.host.mass_kg * st.observation.host.v_m_s + test::momentum(st.particles).z();
  };
  const double p0 = vertical_momentum();
  const double e0 = engine.observe().energy.stored_J();
  engine.advance_to(1e-4);
  CHECK(test::statistic(engine, "jam_stuck_to_host") >= 1);
  CHECK(vertical_momentum() == test::relative(p0).epsilon(1e-14));
  CHECK(engine.observe().energy.balance_relative_error(e0) <= 1e-12);
  CHECK(engine.max_overlap_m() <= engine.overlap_tolerance_m());
  const State end = engine.state();
  for (int i = 0; i < 3; ++i) {
    CHECK((end.particles.velocity_m_s.col(i) - end.observation.host.v_m_s * Eigen::Vector3d::UnitZ()).norm() <= 1e-12);
  }
}
