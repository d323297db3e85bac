/// The hard engine's host coupling (HostCoupling) on its own, with the free flight it
/// predicts for and the books it writes to: the tiers' margin events as lower bounds on
/// contact, the riders' attachment and release, when a sphere rests and when the bed is
/// released.
#include <doctest/doctest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "hard/free_flight.hpp"
#include "hard/hard_ledger.hpp"
#include "hard/host_coupling.hpp"
#include "pdamp/model/hertz_contact.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::hard;

namespace {

/// The parts the host coupling works with, as the engine holds them.
struct Parts {
  FreeFlight flight;
  HardLedger ledger;
  HostCoupling host;
  Parts(const Scenario& s, const Particles& p)
      : flight(s, p), ledger(static_cast<int>(p.size())), host(s, p, flight, ledger) {
    flight.start(p);
  }
};

constexpr double r_m = 0.0005;

/// A free host (10 g on a 400 N/m spring, moving up at 0.2 m/s through its equilibrium)
/// with gravity, and `count` spheres of 1 mm.
Scenario free_host(int count) {
  return test::scenario_from(
      "[host]\nmass_kg = 0.01\nstiffness_N_m = 400\ndamping_N_s_m = 0.05\nz0_m = 0\nv0_m_s = 0.2\n"
      "[cavity]\ndiameter_m = 0.02\nheight_m = 0.01\n[particles]\ncount = " +
      std::to_string(count) + "\ndiameter_m = 0.001\n");
}

/// The gap of a free sphere on `flight` to the floor or the top cap of a host on `host` at t.
double cap_gap(const Ballistic& flight, const HostTrajectory& host, double height_m, double t_s) {
  const double z = flight.position_at(t_s, Eigen::Vector3d(0, 0, -9.81)).z() - host.at(t_s).z_m;
  return std::min(z - r_m, height_m - z - r_m);
}

}  // namespace

TEST_CASE("host tiers: a sphere is in every tier whose margin it is within, and touching within the innermost") {
  const Scenario s = free_host(5);
  // Gaps to the floor (at rest relative to it) of 0.5 r, 0.05 r, 0.001 r, 1e-5 r, and one
  // at 0.5 r but 1e-5 r below the top cap.
  const std::vector<double> gaps{0.5 * r_m, 0.05 * r_m, 0.001 * r_m, 1e-5 * r_m};
  std::vector<Eigen::Vector3d> positions, velocities;
  for (std::size_t k = 0; k < gaps.size(); ++k) {
    positions.emplace_back(-0.006 + 0.003 * static_cast<double>(k), 0, r_m + gaps[k]);
    velocities.emplace_back(0, 0, 0.2);
  }
  positions.emplace_back(0.006, 0, 0.01 - r_m - 1e-5 * r_m);
  velocities.emplace_back(0, 0, 0.2);
  Parts parts(s, test::spheres(positions, velocities, r_m));
  for (int i = 0; i < 5; ++i) parts.host.enter_near(i, 0.0);
  CHECK(parts.host.tier_of(0) == 0);
  CHECK(parts.host.tier_of(1) == 1);
  CHECK(parts.host.tier_of(2) == 2);
  CHECK(parts.host.tier_of(3) == 3);
  CHECK(parts.host.tier_of(4) == 3);
  // Each near sphere has one host-dependent event: a margin event of its innermost tier,
  // or (touching) its contact or a margin event at the touching horizon.
  for (const Event& e : test::drain(parts.flight.queue())) {
    CAPTURE(e.i);
    if (e.kind == EventKind::host_margin) {
      CHECK(e.j == std::min(parts.host.tier_of(e.i), 2));
    } else {
      CHECK((e.kind == EventKind::bottom_cap || e.kind == EventKind::top_cap));
      CHECK(parts.host.tier_of(e.i) == 3);
    }
  }
  // Far again: in no tier.
  parts.host.leave_sets(3);
  CHECK(parts.host.tier_of(3) == -1);
}

TEST_CASE("host tiers: a margin event is a lower bound on contact for any host that strays less than the margin") {
  // Spheres above the floor of a free host, rising and falling; each tier's margin event
  // must come before the sphere could touch a cap on any host trajectory within the
  // tier's margin of the one predicted with: here the host given another velocity at
  // t = 0, ±|Δv| with |Δv| τ the margin (the trajectories then differ by at most |Δv| s).
  const Scenario s = free_host(40);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::Vector3d> positions, velocities;
  for (int k = 0; k < 40; ++k) {
    const double gap = r_m * std::pow(10.0, -5.0 * unit(rng));  // 1e-5 r to r
    positions.emplace_back(-0.0078 + 0.0004 * k, 0, r_m + gap);
    velocities.emplace_back(0, 0, 0.2 + 0.05 * (unit(rng) - 0.5));
  }
  Parts parts(s, test::spheres(positions, velocities, r_m));
  for (int i = 0; i < 40; ++i) parts.host.enter_near(i, 0.0);
  const HostModel model(s);
  int margin_events = 0;
  for (const Event& e : test::drain(parts.flight.queue())) {
    if (e.kind != EventKind::host_margin) continue;
    ++margin_events;
    const auto level = static_cast<std::size_t>(e.j);
    const double allowed_dv = parts.host.margin_m(level) / parts.host.horizon_s(level);
    const Ballistic flight = parts.flight.flight(e.i);
    for (const double dv : {-allowed_dv, allowed_dv}) {
      const HostTrajectory strayed(model, 0.0, {0.0, 0.2 + dv});
      for (int k = 0; k <= 2000; ++k) {
        const double t = e.t_s * k / 2000.0;
        REQUIRE(cap_gap(flight, strayed, 0.01, t) > -parts.flight.contact_tolerance_m());
      }
    }
  }
  CHECK(margin_events > 10);
}

TEST_CASE("riders: a sphere comes to rest on the floor of a free host, which takes its momentum, and leaves with it") {
  const Scenario s = free_host(1);
  const double z0 = 0.0;  // the host starts at its equilibrium
  Parts parts(s, test::spheres({Eigen::Vector3d(0.001, 0.002, z0 + r_m)}, {Eigen::Vector3d(0.01, -0.02, 0.19)}, r_m));
  PackedParticles& p = parts.flight.particles();
  p.angular_velocity_rad_s.col(0) = Eigen::Vector3d(3, 1, -2);
  const double m = p.mass_kg[0], host_mass = s.host.mass_kg;
  const double vz = 0.19, host_v = 0.2;
  REQUIRE(parts.host.rests(0, -1, vz - host_v, 1.0, parts.host.now(0.0), 0.0));
  const HostCoupling::Attached attached = parts.host.attach(0, 1, -1, parts.host.now(0.0), 0.0);
  CHECK(parts.host.riding_count() == 1);
  CHECK(parts.flight.sphere(0).riding == 1);
  CHECK(attached.host_after.v_m_s == test::relative((host_mass * host_v + m * vz) / (host_mass + m)).epsilon(1e-15));
  CHECK(attached.lab_position_m.isApprox(Eigen::Vector3d(0.001, 0.002, z0 + r_m)));
  // The sphere now holds its host-frame position, and no motion of its own.
  CHECK(p.position_m.col(0).isApprox(Eigen::Vector3d(0.001, 0.002, r_m)));
  CHECK(p.velocity_m_s.col(0).isZero());
  CHECK(p.angular_velocity_rad_s.col(0).isZero());
  // The loss: the normal part is impact, the stopped sliding and spin friction.
  const double reduced = m * host_mass / (m + host_mass);
  CHECK(parts.ledger.impact_J == test::relative(0.5 * reduced * (vz - host_v) * (vz - host_v)).epsilon(1e-14));
  CHECK(parts.ledger.friction_J ==
        test::relative(0.5 * m * (0.01 * 0.01 + 0.02 * 0.02) + 0.5 * 0.4 * m * r_m * r_m * 14.0).epsilon(1e-14));
  // All of it the sphere's own.
  CHECK(parts.ledger.by_sphere.impact_J[0] == parts.ledger.impact_J);
  CHECK(parts.ledger.by_sphere.friction_J[0] == parts.ledger.friction_J);
  // The host carries it from now on.
  REQUIRE(parts.host.restart(attached.host_after, 0.0));
  CHECK(parts.host.carried_mass_kg() == host_mass + m);
  CHECK(parts.host.inverse_mass_1_kg() == 1.0 / (host_mass + m));
  const double t = 0.003;
  const HostState host = parts.host.trajectory().at(t);
  parts.host.detach(0, host, t);
  CHECK(parts.host.riding_count() == 0);
  CHECK(parts.flight.sphere(0).riding == 0);
  CHECK(p.position_m.col(0).isApprox(Eigen::Vector3d(0.001, 0.002, host.z_m + r_m)));
  CHECK(p.velocity_m_s.col(0) == Eigen::Vector3d(0, 0, host.v_m_s));
  CHECK(p.t_ref_s[0] == t);
  CHECK(parts.host.carried_mass_kg() == host_mass);
}

TEST_CASE(
    "riders: a sphere rests only slower than the rest speed, pressed by the host's acceleration, on the bed's side") {
  // A floor moving as z = A sin(ωt) with A ω² = 2 g: at t = 0 its acceleration is 0, and a
  // quarter period later −2 g, when it falls away from anything on it.
  constexpr double f_hz = 30.0, w = 2 * std::numbers::pi * f_hz;
  Scenario s = test::scenario_from(
      "[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = 30\n"
      "[cavity]\ndiameter_m = 0.02\nheight_m = 0.01\n[particles]\ncount = 2\ndiameter_m = 0.001\n");
  s.excitation.amplitude_m = 2 * 9.81 / (w * w);
  Parts parts(s, test::spheres({Eigen::Vector3d(0.003, 0, r_m), Eigen::Vector3d(-0.003, 0, 0.005)},
                               {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, r_m));
  const double rest = s.hard_resting.rest_speed_m_s;
  const double quarter = 0.25 / f_hz;
  const HostState still = parts.host.now(0.0), falling = parts.host.now(quarter);
  CHECK(parts.host.rests(0, -1, 0.5 * rest, 1.0, still, 0.0));
  CHECK_FALSE(parts.host.rests(0, -1, 2.0 * rest, 1.0, still, 0.0));
  CHECK_FALSE(parts.host.rests(0, -1, 0.5 * rest, 1.0, falling, quarter));  // the floor falls away at 2 g
  CHECK_FALSE(parts.host.rests(0, -1, 0.5 * rest, -1.0, still, 0.0));       // gravity pulls it off the top cap
  CHECK(parts.host.rests(0, -1, 0.5 * rest, -1.0, falling, quarter));       // the top cap comes down at 2 g
  // With a bed on the floor, the top cap holds none.
  const HostCoupling::Attached attached = parts.host.attach(0, 1, -1, parts.host.now(0.0), 0.0);
  CHECK(attached.host_after.v_m_s == parts.host.trajectory().at(0.0).v_m_s);  // a prescribed host keeps its motion
  CHECK_FALSE(parts.host.rests(0, -1, 0.5 * rest, -1.0, parts.host.now(quarter), quarter));
}

TEST_CASE("riders: with a rest window, a sphere rests below the soft law's enduring speed under the pressing") {
  // The floor moves as z = A sin(ωt) with A ω² = 2 g: a quarter period on the top cap
  // presses at g, three quarters on the floor at 3 g.
  constexpr double f_hz = 30.0, w = 2 * std::numbers::pi * f_hz, g = 9.81;
  Scenario s = test::scenario_from(
      "[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = 30\n"
      "[cavity]\ndiameter_m = 0.02\nheight_m = 0.01\n[particles]\ncount = 2\ndiameter_m = 0.001\n"
      "[hard]\nrest_tc_window = 50\n[soft_wall]\nkn_N_m1_5 = 7.2e5\n");
  s.excitation.amplitude_m = 2 * g / (w * w);
  REQUIRE(s.soft_particle.kn_N_m1_5 != s.soft_wall.kn_N_m1_5);
  Parts parts(s, test::spheres({Eigen::Vector3d(0.003, 0, r_m), Eigen::Vector3d(-0.003, 0, 0.005)},
                               {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, r_m));
  const double m = parts.flight.particles().mass_kg[0], rest = s.hard_resting.rest_speed_m_s;
  const double quarter = 0.25 / f_hz, three_quarters = 0.75 / f_hz;
  const auto rest_speed = [&](int i, int support, double normal_z, double t) {
    return parts.host.rest_speed_m_s(i, support, normal_z, parts.host.now(t), t);
  };
  // On a cap: the sphere's own mass against the wall law.
  const double on_floor = hertz_enduring_speed_m_s(m, s.soft_wall.kn_N_m1_5, 3 * g, 50);
  REQUIRE(on_floor > 10 * rest);
  CHECK(rest_speed(0, -1, 1.0, three_quarters) == test::relative(on_floor).epsilon(1e-12));
  CHECK(rest_speed(0, -1, -1.0, quarter) ==
        test::relative(hertz_enduring_speed_m_s(m, s.soft_wall.kn_N_m1_5, g, 50)).epsilon(1e-12));
  // Where nothing presses, the rest speed alone.
  CHECK(rest_speed(0, -1, -1.0, three_quarters) == rest);
  CHECK(rest_speed(0, -1, 1.0, quarter) == rest);
  CHECK(parts.host.rests(0, -1, 0.9 * on_floor, 1.0, parts.host.now(three_quarters), three_quarters));
  CHECK_FALSE(parts.host.rests(0, -1, 1.1 * on_floor, 1.0, parts.host.now(three_quarters), three_quarters));
  // On a rider: the pair's reduced mass against the sphere law, along the normal's share of the pressing.
  parts.host.attach(0, 1, -1, parts.host.now(0.0), 0.0);
  CHECK(rest_speed(1, 0, 0.6, three_quarters) ==
        test::relative(hertz_enduring_speed_m_s(0.5 * m, s.soft_particle.kn_N_m1_5, 0.6 * 3 * g, 50)).epsilon(1e-12));
  // Without a window, the rest speed whatever presses.
  s.hard_resting.rest_tc_window = 0;
  Parts plain(s, test::spheres({Eigen::Vector3d(0.003, 0, r_m), Eigen::Vector3d(-0.003, 0, 0.005)},
                               {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, r_m));
  CHECK(plain.host.rest_speed_m_s(0, -1, 1.0, plain.host.now(three_quarters), three_quarters) == rest);
}

TEST_CASE(
    "riders: a sphere coming to rest sits at contact with its cap or rider, however far within tolerance it came") {
  // The root finders report a contact up to their tolerance beyond it. A rider keeps its
  // place, so without this a rider knocked off and landing again, over and over, went a
  // tolerance deeper each time: 6e-13 m, ten tolerances, on Table 4 at 100 Hz, against the
  // top cap and, in another run, against the rider it hung from.
  const Scenario s = test::scenario_from(
      "[excitation]\nmode = prescribed\namplitude_m = 0.0001\nfrequency_hz = 30\n"
      "[cavity]\ndiameter_m = 0.02\nheight_m = 0.01\n[particles]\ncount = 5\ndiameter_m = 0.001\n");
  const double beyond = 5e-14, height = s.cavity.height_m;
  const Eigen::Vector3d rider(0, 0.003, r_m), slant = Eigen::Vector3d(0.6, 0, 0.8);
  Parts parts(s, test::spheres(
                     {Eigen::Vector3d(0.003, 0, r_m - beyond), Eigen::Vector3d(-0.003, 0, height - r_m + beyond), rider,
                      rider + (2 * r_m - beyond) * slant, rider + (2 * r_m + 1e-9) * Eigen::Vector3d(-0.6, 0, 0.8)},
                     std::vector<Eigen::Vector3d>(5, Eigen::Vector3d::Zero()), r_m));
  const PackedParticles& p = parts.flight.particles();
  parts.host.attach(0, 1, -1, parts.host.now(0.0), 0.0);
  CHECK(p.position_m(2, 0) == r_m);
  CHECK(p.position_m(2, 0) - r_m >= 0.0);  // the floor's gap
  // The top cap's side (no bed on the floor needed for the test of the place).
  parts.host.detach(0, parts.host.trajectory().at(0.0), 0.0);
  parts.host.attach(1, -1, -1, parts.host.now(0.0), 0.0);
  CHECK(p.position_m(2, 1) == height - r_m);
  CHECK(height - p.position_m(2, 1) - r_m >= 0.0);
  // On a rider: moved out along the line of centres to contact, clear of it by no more
  // than round-off.
  parts.host.detach(1, parts.host.trajectory().at(0.0), 0.0);
  parts.host.attach(2, 1, -1, parts.host.now(0.0), 0.0);
  parts.host.attach(3, 1, 2, parts.host.now(0.0), 0.0);
  const Eigen::Vector3d out = p.position_m.col(3) - p.position_m.col(2);
  CHECK(out.norm() == test::relative(2 * r_m).epsilon(1e-15));
  CHECK(out.norm() - 2 * r_m > -1e-18);
  CHECK(out.normalized().isApprox(slant, 1e-12));
  // One clear of its rider and its cap stays where it is.
  const Eigen::Vector3d clear = p.position_m.col(4);
  parts.host.attach(4, 1, 2, parts.host.now(0.0), 0.0);
  CHECK(p.position_m.col(4) == clear);
}

TEST_CASE("riders: the bed's release is predicted when the floor's acceleration falls to -g") {
  constexpr double f_hz = 30.0, w = 2 * std::numbers::pi * f_hz;
  Scenario s = test::scenario_from(
      "[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = 30\n"
      "[cavity]\ndiameter_m = 0.02\nheight_m = 0.01\n[particles]\ncount = 1\ndiameter_m = 0.001\n");
  s.excitation.amplitude_m = 2 * 9.81 / (w * w);
  Parts parts(
      s, test::spheres({Eigen::Vector3d(0.003, 0, r_m)}, {Eigen::Vector3d(0, 0, s.excitation.amplitude_m * w)}, r_m));
  REQUIRE(parts.host.restart(parts.host.attach(0, 1, -1, parts.host.now(0.0), 0.0).host_after, 0.0));
  std::vector<Event> releases;
  for (const Event& e : test::drain(parts.flight.queue())) {
    if (e.kind == EventKind::bed_release) releases.push_back(e);
  }
  REQUIRE(releases.size() == 1);
  CHECK(releases[0].j == 1);
  CHECK(releases[0].count_j == parts.host.epoch());
  // −A ω² sin(ωt) = −g: ωt = π/6.
  CHECK(releases[0].t_s == test::relative(std::numbers::pi / 6 / w).epsilon(1e-9));
}

TEST_CASE("riders: a rider's departure re-predicts the spheres near it, and on a prescribed host no others") {
  // Rider 0 on the floor, sphere 1 touching it from above, sphere 2 touching the floor far
  // from both. When the rider leaves, sphere 1's exact prediction (which may be a collision
  // with it) must be redone. A free host, lighter by the rider that pressed on it, rises
  // into sphere 2: its prediction is redone as well; a prescribed host moves on as before,
  // so sphere 2's prediction stands.
  for (const bool prescribed : {true, false}) {
    CAPTURE(prescribed);
    const Scenario s = prescribed ? test::scenario_from(
                                        "[excitation]\nmode = prescribed\namplitude_m = 0.0001\nfrequency_hz = 30\n"
                                        "[cavity]\ndiameter_m = 0.02\nheight_m = 0.01\n[particles]\ncount = 3\n"
                                        "diameter_m = 0.001\n")
                                  : free_host(3);
    const double touching_gap = 1e-5 * r_m;
    Parts parts(s, test::spheres({Eigen::Vector3d(0.003, 0, r_m), Eigen::Vector3d(0.003, 0, 3 * r_m + touching_gap),
                                  Eigen::Vector3d(-0.006, 0, r_m + touching_gap)},
                                 {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, r_m));
    REQUIRE(parts.host.restart(parts.host.attach(0, 1, -1, parts.host.now(0.0), 0.0).host_after, 0.0));
    parts.host.enter_near(1, 0.0);
    parts.host.enter_near(2, 0.0);
    REQUIRE(parts.host.tier_of(1) == 3);
    REQUIRE(parts.host.tier_of(2) == 3);
    const std::uint32_t near_stamp = parts.flight.sphere(1).host_stamp;
    const std::uint32_t far_stamp = parts.flight.sphere(2).host_stamp;
    const double t = 1e-4;
    const HostState host = parts.host.trajectory().at(t);
    parts.host.detach(0, host, t);
    REQUIRE(parts.host.restart(host, t));
    CHECK(parts.flight.sphere(1).host_stamp != near_stamp);
    CHECK((parts.flight.sphere(2).host_stamp != far_stamp) == !prescribed);
    if (prescribed) CHECK(parts.ledger.counts.touching_repredictions == 0);
  }
}

TEST_CASE("riders: a sphere coming to rest re-predicts the near spheres whose last search could reach it, no others") {
  // A prescribed host, whose restart leaves the touching spheres' predictions standing. Rider
  // 3 far off, so that spheres 1 (a diameter above the floor, near) and 2 (touching the
  // floor) search boxes for riders when predicted (with no bed they search none, and any
  // rider re-predicts them). Then sphere 0 comes to rest under sphere 1, whose box holds
  // its place, and 1.5 mm from sphere 2, at rest, whose box reaches a diameter (1 mm)
  // around it sideways: though within a cell of the new rider, sphere 2 keeps its prediction.
  const Scenario s = test::scenario_from(
      "[excitation]\nmode = prescribed\namplitude_m = 0.0001\nfrequency_hz = 30\n"
      "[cavity]\ndiameter_m = 0.02\nheight_m = 0.01\n[particles]\ncount = 4\ndiameter_m = 0.001\n");
  const double touching_gap = 1e-5 * r_m;
  const Eigen::Vector3d new_rider(0.003, 0, r_m), sphere_2(0.0045, 0, r_m + touching_gap);
  Parts parts(s, test::spheres({new_rider, Eigen::Vector3d(0.003, 0, 3 * r_m + touching_gap), sphere_2,
                                Eigen::Vector3d(-0.006, 0, r_m)},
                               std::vector<Eigen::Vector3d>(4, Eigen::Vector3d::Zero()), r_m));
  REQUIRE(parts.host.restart(parts.host.attach(3, 1, -1, parts.host.now(0.0), 0.0).host_after, 0.0));
  parts.host.enter_near(1, 0.0);
  parts.host.enter_near(2, 0.0);
  REQUIRE(parts.host.tier_of(1) == 0);
  REQUIRE(parts.host.tier_of(2) == 3);
  const CellGrid& grid = parts.flight.grid();
  const CellCoord rider_cell = grid.coord_of(new_rider), cell_2 = grid.coord_of(sphere_2);
  REQUIRE(std::abs(rider_cell.ix - cell_2.ix) <= 1);  // where the spheres re-predicted are sought
  REQUIRE(rider_cell.iz == cell_2.iz);
  const std::uint32_t stamp_1 = parts.flight.sphere(1).host_stamp, stamp_2 = parts.flight.sphere(2).host_stamp;
  const double t = 1e-4;
  const HostCoupling::Attached attached = parts.host.attach(0, 1, -1, parts.host.now(t), t);
  REQUIRE(parts.host.restart(attached.host_after, t));
  REQUIRE(parts.flight.sphere(1).host_stamp == stamp_1);  // the restart predicted neither
  REQUIRE(parts.flight.sphere(2).host_stamp == stamp_2);
  parts.host.repredict_near_around(attached.lab_position_m, t);
  CHECK(parts.flight.sphere(1).host_stamp != stamp_1);
  CHECK(parts.flight.sphere(2).host_stamp == stamp_2);
  // Sphere 1's new prediction is its collision with the new rider, which the floor lifts into it.
  bool collides = false;
  for (const Event& e : test::drain(parts.flight.queue())) {
    collides |= e.i == 1 && e.kind == EventKind::rider && e.j == 0 && e.count_j == parts.flight.sphere(1).host_stamp;
  }
  CHECK(collides);
}

TEST_CASE(
    "riders: a collision and the sticking that ends it move a free host one way: what it leaves keeps its "
    "prediction") {
  // A host of 1 kg on a stiff spring, so that a sphere's rest spends no tier's budget.
  // Rider 3 far off makes a bed. Sphere 1 touches the floor, sphere 2 the top cap, both at
  // rest and far from sphere 0, which comes to rest on the floor. As in the engine, the
  // host restarts once, from the state the collision left it in, with the sticking added.
  // After a collision that slowed the host by 1 µm/s, the net change pulls it down, and
  // sphere 0's weight pushes it down while the bed is pressed: the floor leaves sphere 1,
  // whose prediction stands as a lower bound, and the top cap nears sphere 2, whose
  // prediction is redone. Without a collision, sphere 0 leaving the floor at 1 mm/s pulls
  // the host up while its weight pushes it down: not one way, so both are redone.
  struct Case {
    double collision_m_s, leaving_m_s;
    bool one_way;
  };
  const Scenario s = test::scenario_from(
      "[host]\nmass_kg = 1\nstiffness_N_m = 1e6\ndamping_N_s_m = 0.05\nz0_m = 0\nv0_m_s = 0.001\n"
      "[cavity]\ndiameter_m = 0.02\nheight_m = 0.01\n[particles]\ncount = 4\ndiameter_m = 0.001\n");
  for (const Case c : {Case{-1e-6, 0.001, true}, Case{0.0, 0.001, false}}) {
    CAPTURE(c.collision_m_s);
    const double touching_gap = 1e-6 * r_m, height = 0.01, host_v = 0.001;
    Parts parts(
        s, test::spheres({Eigen::Vector3d(0.003, 0, r_m), Eigen::Vector3d(0.006, 0.003, r_m + touching_gap),
                          Eigen::Vector3d(0.006, -0.003, height - r_m - touching_gap), Eigen::Vector3d(-0.006, 0, r_m)},
                         {Eigen::Vector3d(0, 0, host_v + c.collision_m_s + c.leaving_m_s),
                          Eigen::Vector3d(0, 0, host_v), Eigen::Vector3d(0, 0, host_v), Eigen::Vector3d(0, 0, host_v)},
                         r_m));
    REQUIRE(parts.host.restart(parts.host.attach(3, 1, -1, parts.host.now(0.0), 0.0).host_after, 0.0));
    parts.host.enter_near(1, 0.0);
    parts.host.enter_near(2, 0.0);
    REQUIRE(parts.host.tier_of(1) == 3);
    REQUIRE(parts.host.tier_of(2) == 3);
    const HardStatistics before = parts.ledger.counts;
    HostState collided = parts.host.now(0.0);
    collided.v_m_s += c.collision_m_s;
    REQUIRE(parts.host.rests(0, -1, c.leaving_m_s, 1.0, collided, 0.0));
    const HostCoupling::Attached attached = parts.host.attach(0, 1, -1, collided, 0.0);
    REQUIRE(parts.host.restart(attached.host_after, 0.0));
    CHECK(parts.ledger.counts.touching_deferrals - before.touching_deferrals == (c.one_way ? 1 : 0));
    CHECK(parts.ledger.counts.touching_repredictions - before.touching_repredictions == (c.one_way ? 1 : 2));
  }
}

TEST_CASE("riders: a departed rider's restart predicts anew a touching sphere that may have been about to hit it") {
  // A free host that loses a rider moves up, away from sphere 1 below the rider: a restart
  // would leave sphere 1's prediction standing, but that prediction is its collision with
  // the rider, which is no longer there.
  const Scenario s = test::scenario_from(
      "[host]\nmass_kg = 1\nstiffness_N_m = 1e6\ndamping_N_s_m = 0.05\nz0_m = 0\nv0_m_s = 0.001\n"
      "[cavity]\ndiameter_m = 0.02\nheight_m = 0.01\n[particles]\ncount = 2\ndiameter_m = 0.001\n");
  const double host_v = 0.001, touching_gap = 1e-6 * r_m;
  Parts parts(s, test::spheres({Eigen::Vector3d(0.003, 0, 5 * r_m), Eigen::Vector3d(0.003, 0, 3 * r_m - touching_gap)},
                               {Eigen::Vector3d(0, 0, host_v), Eigen::Vector3d(0, 0, host_v + 0.001)}, r_m));
  REQUIRE(parts.host.restart(parts.host.attach(0, 1, -1, parts.host.now(0.0), 0.0).host_after, 0.0));
  parts.host.enter_near(1, 0.0);
  REQUIRE(parts.host.tier_of(1) == 3);
  bool hits_rider = false;
  for (const Event& e : test::drain(parts.flight.queue())) hits_rider |= e.i == 1 && e.kind == EventKind::rider;
  REQUIRE(hits_rider);
  parts.host.enter_near(1, 0.0);  // its events again, after the drain
  const HardStatistics before = parts.ledger.counts;
  const HostState host = parts.host.now(0.0);
  parts.host.detach(0, host, 0.0);
  REQUIRE(parts.host.restart(host, 0.0));
  CHECK(parts.ledger.counts.touching_deferrals == before.touching_deferrals);
  CHECK(parts.ledger.counts.touching_repredictions - before.touching_repredictions == 1);
}

TEST_CASE("books: the host's damping and excitation booked in stretches add up to one booking of the whole") {
  const Scenario s = test::scenario_from(
      "[host]\nmass_kg = 0.02\nstiffness_N_m = 900\ndamping_N_s_m = 0.3\nz0_m = 0.002\nv0_m_s = 0\n"
      "[excitation]\nmode = base\namplitude_m = 0.001\nfrequency_hz = 40\n[particles]\ncount = 0\n");
  const HostModel model(s);
  const HostTrajectory trajectory(model, 0.0, model.initial_state());
  const Riders none{0.0, -9.81, false};
  HardLedger whole(0), stretches(0);
  whole.book_host(trajectory, 0.1, none);
  for (int k = 1; k <= 10; ++k) stretches.book_host(trajectory, 0.01 * k, none);
  CHECK(whole.viscous_J > 0.0);
  CHECK(stretches.viscous_J == test::relative(whole.viscous_J).epsilon(1e-12));
  CHECK(stretches.excitation_J == test::relative(whole.excitation_J).epsilon(1e-12));
  // An observation adds what the trajectory did since the last booking.
  HardLedger booked(0);
  booked.book_host(trajectory, 0.04, none);
  Observation observed;
  booked.write_to(observed, trajectory, 0.1, none);
  CHECK(observed.energy.dissipated_viscous_J == test::relative(whole.viscous_J).epsilon(1e-12));
  CHECK(observed.energy.excitation_work_J == test::relative(whole.excitation_J).epsilon(1e-12));
  CHECK(observed.host_load.z_m_s == test::relative(whole.load.value().z_m_s).epsilon(1e-12));
}

TEST_CASE("books: a prescribed host's work on its riders is the change of their energy that moves with it") {
  Scenario s = test::scenario_from(
      "[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = 25\n[particles]\ncount = 0\n");
  const HostModel model(s);
  const HostTrajectory trajectory(model, 0.0, model.initial_state());
  const Riders riders{0.003, -9.81, true};
  HardLedger ledger(0);
  ledger.book_host(trajectory, 0.007, riders);
  const HostState a = trajectory.at(0.0), b = trajectory.at(0.007);
  const double expected =
      0.003 * (0.5 * b.v_m_s * b.v_m_s + 9.81 * b.z_m) - 0.003 * (0.5 * a.v_m_s * a.v_m_s + 9.81 * a.z_m);
  CHECK(ledger.excitation_J == test::relative(expected).epsilon(1e-14));
  CHECK(ledger.viscous_J == 0.0);
}

TEST_CASE("books: every count has a name of its own, and collisions are the four kinds of contact") {
  const HardStatistics counts{.sphere_sphere = 1, .side_wall = 20, .cap = 300, .rider = 4000, .cell_crossing = 50000};
  CHECK(counts.collisions() == 4321);
  const EngineStatistics named = counts.named();
  std::vector<std::string> names;
  for (const auto& [name, value] : named) names.push_back(name);
  std::sort(names.begin(), names.end());
  CHECK(std::adjacent_find(names.begin(), names.end()) == names.end());
  CHECK(names.size() == 25);
}
