/// Rigid clusters (`[hard] cluster_speed_m_s`): RigidClusters' records on their own, and in
/// the engine a cluster formed by a slow collision and broken by a fast one, the books
/// and momentum with a free host, no overlaps, and determinism.
#include <doctest/doctest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <random>
#include <vector>

#include "hard/hard_engine_class.hpp"
#include "hard/rigid_clusters.hpp"
#include "pdamp/model/placement.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::hard;

namespace {

std::vector<int> sorted(std::span<const int> members) {
  std::vector<int> v(members.begin(), members.end());
  std::sort(v.begin(), v.end());
  return v;
}

}  // namespace

TEST_CASE("rigid clusters: joins merge clusters, a sphere that leaves is alone, a cluster of one ends") {
  RigidClusters clusters(6, 0.01);
  CHECK(clusters.enabled());
  CHECK(clusters.merges(0.009));
  CHECK_FALSE(clusters.merges(0.01));
  CHECK_FALSE(RigidClusters(6, 0.0).enabled());

  CHECK(sorted(clusters.join(0, 1)) == std::vector<int>{0, 1});
  CHECK(sorted(clusters.join(3, 2)) == std::vector<int>{2, 3});
  CHECK(clusters.cluster_of(0) == clusters.cluster_of(1));
  CHECK(clusters.cluster_of(2) != clusters.cluster_of(0));
  CHECK(sorted(clusters.join(1, 2)) == std::vector<int>{0, 1, 2, 3});
  CHECK(sorted(clusters.join(4, 3)) == std::vector<int>{0, 1, 2, 3, 4});
  CHECK(clusters.cluster_of(5) == -1);

  clusters.leave(2);
  CHECK(clusters.cluster_of(2) == -1);
  CHECK(sorted(clusters.members(clusters.cluster_of(0))) == std::vector<int>{0, 1, 3, 4});
  clusters.leave(5);  // alone already: nothing happens
  for (const int k : {0, 1, 3}) clusters.leave(k);
  CHECK(clusters.cluster_of(4) == -1);  // the last one is alone again
  // The freed cluster is reused.
  CHECK(sorted(clusters.join(5, 4)) == std::vector<int>{4, 5});

  const EngineStatistics counts = clusters.named();
  CHECK(counts == EngineStatistics{
                      {"cluster_joins", 5}, {"cluster_joined_spheres", 2 + 2 + 4 + 5 + 2}, {"cluster_departures", 4}});
}

namespace {

constexpr double r_m = 0x1p-11;
constexpr double sigma_m = 2 * r_m;

/// Without gravity, fixed walls far away: spheres 0 and 1 a gap apart closing at 1 mm/s
/// (slower than the cluster speed, 1 cm/s), spinning; sphere 2 comes at sphere 1 from
/// behind at 1 m/s, later.
struct SlowThenFast {
  Scenario scenario = test::fixed_walls(
      "[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = 0.03125\nheight_m = 0.03125\n"
      "[particles]\ncount = 3\ndiameter_m = 0.001\n[hard]\nen = 0.5\nmu = 0.3\ncluster_speed_m_s = 0.01\n");
  Particles initial = test::spheres(
      {Eigen::Vector3d(0, 0, 0.015625), Eigen::Vector3d(sigma_m + 1e-6, 0, 0.015625),
       Eigen::Vector3d(sigma_m + 1e-6 + 8 * sigma_m, 0.2 * r_m, 0.015625)},
      {Eigen::Vector3d(0.0005, 0.0002, 0), Eigen::Vector3d(-0.0005, 0, 0.0001), Eigen::Vector3d(-1.0, 0, 0)}, r_m);
  SlowThenFast() {
    for (Eigen::Index i = 0; i < 3; ++i) initial.mass_kg[i] = 4e-6;
    initial.angular_velocity_rad_s.col(0) = Eigen::Vector3d(3, -2, 5);
    initial.angular_velocity_rad_s.col(1) = Eigen::Vector3d(-1, 4, 2);
  }
};

}  // namespace

TEST_CASE("rigid clusters in the engine: a slow collision merges two spheres into one body, a fast one breaks it") {
  const SlowThenFast c;
  // The slow pair meets after 1 ms; sphere 2 reaches the pair after about 7 ms.
  HardEngine engine(c.scenario, c.initial);
  const double e0 = engine.observe().energy.stored_J();
  const Particles start = engine.state().particles;
  engine.advance_to(1.5e-3);
  CHECK(test::statistic(engine, "cluster_joins") == 1);
  CHECK(test::statistic(engine, "events_sphere_sphere") == 1);
  const Particles merged = engine.state().particles;
  // One rigid body, flown on: momentum kept, its spheres spinning alike, their relative
  // velocity the spin's about the centre at the merge, so they part (slowly: they touched).
  CHECK((merged.angular_velocity_rad_s.col(0) - merged.angular_velocity_rad_s.col(1)).norm() == 0.0);
  const Eigen::Vector3d relative = merged.velocity_m_s.col(0) - merged.velocity_m_s.col(1);
  const Eigen::Vector3d arm = merged.position_m.col(0) - merged.position_m.col(1);
  CHECK(relative.norm() > 0.0);
  CHECK(relative.dot(arm) > 0.0);
  CHECK(std::abs(arm.norm() - sigma_m) <= 1e-3 * sigma_m);
  CHECK((test::momentum(merged) - test::momentum(start)).norm() <= 1e-15);
  const EnergyLedger merged_books = engine.observe().energy;
  CHECK(merged_books.dissipated_impact_J > 0);
  CHECK(merged_books.dissipated_friction_J > 0);
  CHECK(merged_books.balance_relative_error(e0) <= 1e-12);
  test::check_dissipation_by_sphere(engine);
  // No more collisions between them while they fly on.
  engine.advance_to(6e-3);
  CHECK(test::statistic(engine, "events_sphere_sphere") == 1);

  // Sphere 2 hits sphere 1 at 1 m/s: a binary collision; both leave, the cluster ends.
  engine.advance_to(10e-3);
  CHECK(test::statistic(engine, "events_sphere_sphere") >= 2);
  CHECK(test::statistic(engine, "cluster_departures") == 1);  // sphere 1, which leaves 0 alone
  CHECK(engine.observe().energy.balance_relative_error(e0) <= 1e-12);
  CHECK(engine.max_overlap_m() <= engine.overlap_tolerance_m());
  test::check_dissipation_by_sphere(engine);

  // Without clusters the slow pair bounces apart (e_n = 0.5) and no body forms.
  Scenario off = c.scenario;
  off.hard_resting.cluster_speed_m_s = 0.0;
  HardEngine plain(off, c.initial);
  plain.advance_to(1.5e-3);
  const Particles bounced = plain.state().particles;
  CHECK((bounced.velocity_m_s.col(0) - bounced.velocity_m_s.col(1)).x() < -1e-4);
  const EngineStatistics plain_counts = plain.statistics();
  CHECK(std::none_of(plain_counts.begin(), plain_counts.end(),
                     [](const auto& named) { return named.first.starts_with("cluster_"); }));
}

namespace {

/// The small damper's 100 spheres jostling in its host made free (negligible spring, no
/// damping, no gravity), one of them fast: slow collisions merge, fast ones break.
Scenario free_host_cloud(double cluster_speed_m_s) {
  Scenario s = load_scenario(test::scenario_file("small"));
  s.gravity_m_s2.setZero();
  s.host.stiffness_N_m = 1e-20;
  s.host.damping_N_s_m = 0.0;
  s.hard_resting.cluster_speed_m_s = cluster_speed_m_s;
  return s;
}

Particles jostling(const Scenario& s) {
  Particles p = place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    p.velocity_m_s.col(i) = 0.02 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    p.angular_velocity_rad_s.col(i) = 20.0 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  }
  p.velocity_m_s.col(0) = Eigen::Vector3d(0.5, -0.3, 0.4);
  return p;
}

}  // namespace

TEST_CASE("rigid clusters in the engine: a jostling cloud in a free host keeps its books, momentum, no overlaps") {
  const Scenario s = free_host_cloud(0.01);
  const Particles initial = jostling(s);
  HardEngine engine(s, initial);
  auto vertical_momentum = [&] {
    const State st = engine.state();
    return s.host.mass_kg * st.observation.host.v_m_s + test::momentum(st.particles).z();
  };
  const double p0 = vertical_momentum();
  const double e0 = engine.observe().energy.stored_J();
  for (int k = 1; k <= 50; ++k) {
    engine.advance_to(0.002 * k);
    REQUIRE(engine.max_overlap_m() <= engine.overlap_tolerance_m());
  }
  CHECK(test::statistic(engine, "cluster_joins") > 10);
  CHECK(test::statistic(engine, "cluster_departures") > 0);
  CHECK(vertical_momentum() == test::relative(p0).epsilon(1e-12));
  const EnergyLedger books = engine.observe().energy;
  CHECK(books.balance_relative_error(e0) <= 1e-9);
  CHECK(books.dissipated_impact_J > 0);
  CHECK(books.dissipated_friction_J > 0);
  test::check_dissipation_by_sphere(engine);

  // The same run again gives the same bits.
  HardEngine again(s, initial);
  again.advance_to(0.1);
  test::check_same_state(again.state(), engine.state());
  CHECK(again.statistics() == engine.statistics());
}

TEST_CASE("rigid clusters in the engine: a shaken bed keeps its books and has no overlaps") {
  Scenario s = load_scenario(test::scenario_file("small"));
  s.hard_resting.cluster_speed_m_s = 0.02;
  HardEngine engine(s, place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m));
  const double e0 = engine.observe().energy.stored_J();
  for (int k = 1; k <= 100; ++k) {
    engine.advance_to(0.002 * k);
    REQUIRE(engine.max_overlap_m() <= engine.overlap_tolerance_m());
  }
  CHECK(test::statistic(engine, "cluster_joins") > 0);
  const EnergyLedger books = engine.observe().energy;
  CHECK(books.balance_relative_error(e0) <= 1e-9);
  test::check_dissipation_by_sphere(engine);
}
