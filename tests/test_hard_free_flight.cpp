/// The hard engine's free flight (FreeFlight) on its own: what it predicts for a free
/// sphere without the host (contacts with other spheres, face crossings, the side wall,
/// the host check that bounds where the host's predictions take over), how its cells
/// follow a crossing, and when a prediction goes out of date.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "hard/free_flight.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::hard;

namespace {

constexpr double r_m = 0.0005;

/// Spheres in a wide cavity without gravity (fixed walls).
Scenario weightless(int count) {
  return test::fixed_walls(
      "[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = 0.02\nheight_m = 0.02\n[particles]\ncount = " +
      std::to_string(count) + "\ndiameter_m = 0.001\n");
}

/// The host at rest for good (speed envelope 0) and no bed: out of reach of a sphere that
/// moves only sideways, between its caps.
constexpr HostReach unreachable{0.0, 0.0, 0.0};

std::vector<Event> of_kind(const std::vector<Event>& events, EventKind kind) {
  std::vector<Event> found;
  std::copy_if(events.begin(), events.end(), std::back_inserter(found), [&](const Event& e) { return e.kind == kind; });
  return found;
}

}  // namespace

TEST_CASE("free flight: two spheres closing in get their exact contact time, out of date once the partner moves on") {
  // Centres 1.2 mm apart (in neighbouring cells) closing at 0.5 m/s: contact after 0.2 mm, at 0.4 ms.
  const Scenario s = weightless(2);
  FreeFlight flight(s, test::spheres({Eigen::Vector3d(-0.0004, 0, 0.01), Eigen::Vector3d(0.0008, 0, 0.01)},
                                     {Eigen::Vector3d(0.2, 0, 0), Eigen::Vector3d(-0.3, 0, 0)}, r_m));
  flight.start(flight.particles().unpacked());
  CHECK_FALSE(flight.predict(0, flight.around(0), 0.0, unreachable));
  const std::vector<Event> events = test::drain(flight.queue());
  const std::vector<Event> contacts = of_kind(events, EventKind::sphere_sphere);
  REQUIRE(contacts.size() == 1);
  CHECK(contacts[0].i == 0);
  CHECK(contacts[0].j == 1);
  CHECK(contacts[0].t_s == test::relative(0.0004).epsilon(1e-12));
  CHECK(of_kind(events, EventKind::host_check).empty());  // the host is out of reach
  CHECK(flight.is_current(contacts[0], 0));
  flight.new_trajectory(1);
  CHECK_FALSE(flight.is_current(contacts[0], 0));
  // Its next crossing: the face ahead in x, at 0.2 m/s.
  const std::vector<Event> crossings = of_kind(events, EventKind::cell_crossing);
  REQUIRE(crossings.size() == 1);
  CHECK(crossings[0].j == FreeFlight::x_upper);
  CHECK(crossings[0].t_s == test::relative((flight.grid().x_lower_m(flight.sphere(0).cell.ix + 1) + 0.0004) / 0.2));
  CHECK(flight.sphere(0).t_cross_s == crossings[0].t_s);
}

TEST_CASE("free flight: a crossing moves the sphere into the next cell and brings in the layer of cells beyond it") {
  const Scenario s = weightless(1);
  FreeFlight flight(s,
                    test::spheres({Eigen::Vector3d(0.0002, -0.0003, 0.0101)}, {Eigen::Vector3d(0.1, 0.1, 0.1)}, r_m));
  flight.start(flight.particles().unpacked());
  const CellGrid& grid = flight.grid();
  for (const FreeFlight::Face face : {FreeFlight::x_upper, FreeFlight::y_lower, FreeFlight::z_upper}) {
    CAPTURE(static_cast<int>(face));
    const CellCoord before = flight.sphere(0).cell;
    const FreeFlight::Layer layer = flight.cross_face(0, face);
    const CellCoord after = flight.sphere(0).cell;
    const int axis = face / 2, step = face % 2 == 1 ? 1 : -1;
    CHECK(after.ix - before.ix == (axis == 0 ? step : 0));
    CHECK(after.iy - before.iy == (axis == 1 ? step : 0));
    CHECK(after.iz - before.iz == (axis == 2 ? step : 0));
    // The layer: the cells around the new one that were not around the old one.
    FreeFlight::Around old_block{}, new_block{};
    grid.block(before, grid.cell_count(), old_block);
    grid.block(after, grid.cell_count(), new_block);
    std::vector<int> entered;
    for (const int c : new_block) {
      if (std::find(old_block.begin(), old_block.end(), c) == old_block.end()) entered.push_back(c);
    }
    std::vector<int> got(layer.begin(), layer.end());
    std::sort(got.begin(), got.end());
    std::sort(entered.begin(), entered.end());
    CHECK(got == entered);
  }
}

TEST_CASE("free flight: the host check comes when the bed could first be reached at the envelope's speed") {
  // A sphere at rest 1 mm above the floor (the host at z = 0), alone in the cavity: no
  // crossing, no contact. A host moving at most 0.1 m/s reaches it in 10 ms.
  const Scenario s = weightless(1);
  FreeFlight flight(s, test::spheres({Eigen::Vector3d(0.0002, 0, r_m + 0.001)}, {Eigen::Vector3d::Zero()}, r_m));
  flight.start(flight.particles().unpacked());
  CHECK_FALSE(flight.predict(0, flight.around(0), 0.0, {0.0, 0.1, 0.0}));
  std::vector<Event> checks = of_kind(test::drain(flight.queue()), EventKind::host_check);
  REQUIRE(checks.size() == 1);
  CHECK(checks[0].t_s == test::relative(0.01).epsilon(1e-14));
  // A bed 0.4 mm deep is reached sooner; one up to the sphere is within reach now.
  CHECK_FALSE(flight.predict(0, flight.around(0), 0.0, {0.0, 0.1, 0.0004}));
  checks = of_kind(test::drain(flight.queue()), EventKind::host_check);
  REQUIRE(checks.size() == 1);
  CHECK(checks[0].t_s == test::relative(0.006).epsilon(1e-12));
  CHECK(flight.predict(0, flight.around(0), 0.0, {0.0, 0.1, 0.001}));
  CHECK(of_kind(test::drain(flight.queue()), EventKind::host_check).empty());
}

TEST_CASE("free flight: a sphere inside the bed's reach is within reach now, however fast it moves away") {
  // The sphere's underside 1 mm above the floor, rising at 0.5 m/s, and a bed up to 2 mm
  // deep: it is among the riders already, so the host's predictions must take over now,
  // not when a host at the envelope's 0.1 m/s would catch up with it (with gravity: when
  // it comes back down; without: never), which let it fly into a rider unseen.
  for (const double g : {0.0, 9.81}) {
    CAPTURE(g);
    const Scenario s = test::fixed_walls("[gravity]\ng_m_s2 = " + std::to_string(g) +
                                         "\n[cavity]\ndiameter_m = 0.02\nheight_m = 0.02\n[particles]\ncount = 1\n"
                                         "diameter_m = 0.001\n");
    for (const double vz : {0.5, -0.5}) {
      CAPTURE(vz);
      // Rising from the floor's bed, or sinking towards the top cap's (the mirror).
      const double z = vz > 0 ? r_m + 0.001 : 0.02 - r_m - 0.001;
      FreeFlight flight(s, test::spheres({Eigen::Vector3d(0.0002, 0, z)}, {Eigen::Vector3d(0, 0, vz)}, r_m));
      flight.start(flight.particles().unpacked());
      CHECK(flight.predict(0, flight.around(0), 0.0, {0.0, 0.1, 0.002}));
      CHECK(of_kind(test::drain(flight.queue()), EventKind::host_check).empty());
    }
  }
}

TEST_CASE("free flight: the side wall is predicted where the sphere's cell reaches it") {
  // Moving out along x from near the axis at 1 m/s: the wall (reach R − r = 9.5 mm) at 9.5 ms,
  // predicted from the cell the sphere reaches it from; a sphere that leaves a cell first
  // is predicted anew there.
  const Scenario s = weightless(1);
  FreeFlight flight(s, test::spheres({Eigen::Vector3d(0.0, 0, 0.01)}, {Eigen::Vector3d(1.0, 0, 0)}, r_m));
  flight.start(flight.particles().unpacked());
  double t = 0.0;
  CHECK_FALSE(flight.predict(0, flight.around(0), t, unreachable));
  for (int step = 0; step < 100; ++step) {
    const std::vector<Event> events = test::drain(flight.queue());
    const std::vector<Event> walls = of_kind(events, EventKind::side_wall);
    if (!walls.empty()) {
      CHECK(walls[0].t_s == test::relative(0.0095).epsilon(1e-12));
      return;
    }
    const std::vector<Event> crossings = of_kind(events, EventKind::cell_crossing);
    REQUIRE(crossings.size() == 1);
    t = crossings[0].t_s;
    flight.bring_to_now(0, t);
    const FreeFlight::Layer layer = flight.cross_face(0, static_cast<FreeFlight::Face>(crossings[0].j));
    CHECK_FALSE(flight.predict(0, layer, t, unreachable));
  }
  FAIL("no side-wall contact predicted");
}
