/// Walton's collision law and the event predictions of the hard-sphere engine, against
/// hand-derived results and brute-force sampling.
#include <doctest/doctest.h>

#include <Eigen/Geometry>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "hard/collision_rules.hpp"
#include "hard/event_prediction.hpp"
#include "hard/neighbour_screen.hpp"
#include "hard/packed_particles.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::hard;

namespace {

HardContactLaw law(double en, double mu, double beta0) { return {en, mu, beta0}; }

/// The kinetic energy a collision removes: −(P·u + ½ P·K P).
double total_loss(const CollisionOutcome& out, const Eigen::Vector3d& u, const Eigen::Vector3d& n, const Mobility& k) {
  const Eigen::Vector3d& p = out.impulse_N_s;
  return -(p.dot(u) + 0.5 * p.dot(apply_mobility(k, n, p)));
}

}  // namespace

TEST_CASE("Walton: head-on frictionless impact of two spheres") {
  const double m1 = 2e-6, m2 = 5e-6, e = 0.7, u_n = 0.9;
  const Eigen::Vector3d n = Eigen::Vector3d(1, 2, 2) / 3.0;
  const Mobility k = sphere_mobility(m1) + sphere_mobility(m2);
  const CollisionOutcome out = walton_collision(u_n * n, n, u_n, k, law(e, 0.0, 0.35));
  const double reduced = m1 * m2 / (m1 + m2);
  CHECK((out.impulse_N_s + (1 + e) * reduced * u_n * n).norm() <= 1e-15 * reduced * u_n);
  CHECK(out.impact_J == test::relative(0.5 * (1 - e * e) * reduced * u_n * u_n).epsilon(1e-13));
  CHECK(std::abs(out.friction_J) <= 1e-28);
  // Separating bodies do not collide.
  CHECK(walton_collision(-u_n * n, n, -u_n, k, law(e, 0.5, 0.35)).impulse_N_s.norm() == 0.0);
}

TEST_CASE("Walton: an oblique frictionless impact is normal, the limit of the sliding law as mu -> 0") {
  const double m = 3e-6, e = 0.6, u_n = 0.7;
  const Eigen::Vector3d n = Eigen::Vector3d(2, -1, 2) / 3.0;
  const Eigen::Vector3d u = u_n * n + Eigen::Vector3d(0.3, 0.4, -0.1);  // slip of either sign along n's plane
  // A sphere on a sphere, and a sphere on a light host (whose vertical mobility couples
  // the tangential direction into the normal one).
  for (const Mobility& k :
       {sphere_mobility(m) + sphere_mobility(2 * m), sphere_mobility(m) + Mobility{0, 0, 1 / (5 * m)}}) {
    const CollisionOutcome out = walton_collision(u, n, u_n, k, law(e, 0.0, 0.35));
    CHECK(!out.sticking);
    CHECK(out.impulse_N_s.cross(n).norm() <= 1e-15 * out.impulse_N_s.norm());
    // Normal restitution holds: n·(u + K P) = −e u_n.
    CHECK(n.dot(u + apply_mobility(k, n, out.impulse_N_s)) == doctest::Approx(-e * u_n).scale(1.0).epsilon(1e-13));
    const CollisionOutcome nearly = walton_collision(u, n, u_n, k, law(e, 1e-9, 0.35));
    CHECK((out.impulse_N_s - nearly.impulse_N_s).norm() <= 1e-8 * out.impulse_N_s.norm());
    CHECK(std::abs(out.friction_J) <= 1e-15 * out.impact_J);
    CHECK(out.impact_J == test::relative(total_loss(out, u, n, k)).epsilon(1e-13));
  }
}

TEST_CASE("Walton: a sticking oblique impact reverses the contact slip by beta0") {
  const double m = 3e-6, e = 0.8, beta0 = 0.35, u_n = 0.5, u_t = 0.2;
  const Eigen::Vector3d n = -Eigen::Vector3d::UnitZ();  // sphere falling on a fixed floor
  const Eigen::Vector3d u(u_t, 0.0, -u_n);
  const Mobility k = sphere_mobility(m);
  const CollisionOutcome out = walton_collision(u, n, u_n, k, law(e, 10.0, beta0));
  CHECK(out.sticking);
  // P_t = −(1 + β0) u_t / (7/(2m)), P_n = (1 + e) m u_n.
  CHECK(out.impulse_N_s.x() == test::relative(-(1 + beta0) * u_t * 2 * m / 7).epsilon(1e-13));
  CHECK(out.impulse_N_s.z() == test::relative((1 + e) * m * u_n).epsilon(1e-13));
  const Eigen::Vector3d u_after = u + apply_mobility(k, n, out.impulse_N_s);
  CHECK(u_after.x() == test::relative(-beta0 * u_t).epsilon(1e-13));
  CHECK(u_after.z() == doctest::Approx(e * u_n).scale(1.0).epsilon(1e-13));
  CHECK(out.impact_J == test::relative(0.5 * (1 - e * e) * m * u_n * u_n).epsilon(1e-13));
  CHECK(out.friction_J == test::relative(0.5 * (1 - beta0 * beta0) * (2 * m / 7) * u_t * u_t).epsilon(1e-13));
}

TEST_CASE("Walton: a sliding impact is limited by mu times the normal impulse") {
  const double m = 3e-6, e = 0.6, mu = 0.1, u_n = 0.5, u_t = 0.4;
  const Eigen::Vector3d n = -Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d u(0.0, u_t, -u_n);
  const Mobility k = sphere_mobility(m);
  const CollisionOutcome out = walton_collision(u, n, u_n, k, law(e, mu, 0.35));
  CHECK_FALSE(out.sticking);
  const double lambda = (1 + e) * m * u_n, p_t = mu * lambda;
  CHECK(out.impulse_N_s.y() == test::relative(-p_t).epsilon(1e-13));
  CHECK(out.impulse_N_s.z() == test::relative(lambda).epsilon(1e-13));
  // Friction work: μλ|u_t| − ½ (7/(2m)) (μλ)².
  CHECK(out.friction_J == test::relative(p_t * u_t - 0.5 * 3.5 / m * p_t * p_t).epsilon(1e-13));
  CHECK(out.impact_J + out.friction_J == test::relative(total_loss(out, u, n, k)).epsilon(1e-13));
}

TEST_CASE("Walton: a finite host takes the normal impulse at a cap and the vertical friction at the side wall") {
  const double m = 3e-6, host = 0.04, e = 0.8, beta0 = 0.35;
  const Mobility k = sphere_mobility(m) + Mobility{0, 0, 1.0 / host};
  SUBCASE("cap: the pair's effective mass") {
    const Eigen::Vector3d n = -Eigen::Vector3d::UnitZ();
    const double u_n = 1.3;
    const CollisionOutcome out = walton_collision(Eigen::Vector3d(0, 0, -u_n), n, u_n, k, law(e, 0.5, beta0));
    CHECK(out.impulse_N_s.z() == test::relative((1 + e) * u_n / (1 / m + 1 / host)).epsilon(1e-13));
  }
  SUBCASE("side wall: the vertical slip sees 7/(2m) + 1/M") {
    const Eigen::Vector3d n = Eigen::Vector3d::UnitX();
    const double u_n = 0.3, u_z = 0.05;
    const CollisionOutcome out = walton_collision(Eigen::Vector3d(u_n, 0, u_z), n, u_n, k, law(e, 10.0, beta0));
    CHECK(out.sticking);
    CHECK(out.impulse_N_s.z() == test::relative(-(1 + beta0) * u_z / (3.5 / m + 1 / host)).epsilon(1e-13));
    CHECK(out.impulse_N_s.x() == test::relative(-(1 + e) * m * u_n).epsilon(1e-13));
  }
}

TEST_CASE("Walton: the loss splits exactly into impact and friction and is never negative") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Vector3d n(uniform(rng), uniform(rng), uniform(rng));
    n.normalize();
    Eigen::Vector3d u(uniform(rng), uniform(rng), uniform(rng));
    if (u.dot(n) < 0) u = -u;
    const double m = 1e-6 * (1.5 + uniform(rng));
    const Mobility k = sphere_mobility(m) + Mobility{0, 0, trial % 2 ? 1.0 / (0.01 + 0.005 * uniform(rng)) : 0.0};
    const HardContactLaw l = law(0.5 + 0.5 * uniform(rng), 0.6 + 0.5 * uniform(rng), uniform(rng));
    const CollisionOutcome out = walton_collision(u, n, u.dot(n), k, l);
    const double loss = total_loss(out, u, n, k);
    CAPTURE(trial);
    CHECK(out.impact_J + out.friction_J == test::relative(loss).epsilon(1e-12));
    CHECK(out.impact_J >= 0.0);
    CHECK(loss >= -1e-15 * m * u.squaredNorm());
    // Normal restitution holds exactly in both branches.
    const Eigen::Vector3d u_after = u + apply_mobility(k, n, out.impulse_N_s);
    CHECK(u_after.dot(n) == doctest::Approx(-l.en * u.dot(n)).scale(u.norm()).epsilon(1e-10));
  }
}

TEST_CASE("face and plane times: unaccelerated lanes divide, to time_to_close's bits unless rate² underflows") {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::array<double, 6> special{0.0, -0.0, 1e-300, -1e-300, 1e-18, -1e-18};
  for (int trial = 0; trial < 20000; ++trial) {
    const auto pick = [&](double scale) {
      return trial % 7 == 0 ? special[(trial / 7 + static_cast<int>(3 * u(rng) + 3)) % 6] : scale * u(rng);
    };
    const Lanes2 lower{pick(1e-3), pick(1e-3)}, upper{pick(1e-3), pick(1e-3)}, rate{pick(2.0), pick(2.0)};
    for (const Lanes2 accel : {Lanes2{0.0, 0.0}, Lanes2{-0.0, 0.0}, Lanes2{0.0, -9.81}, Lanes2{-9.81, 3.0}}) {
      const FaceTimes faces = time_to_faces(lower, upper, rate, accel);
      const Lanes2 to_lower = time_to_close(lower, rate, accel), to_upper = time_to_close(upper, -rate, -accel);
      const Lanes2 to_lower_plane = time_to_plane(lower, rate, accel);
      const Lanes2 to_upper_plane = time_to_plane(upper, -rate, -accel);
      for (int lane = 0; lane < 2; ++lane) {
        CAPTURE(trial);
        CAPTURE(lane);
        if (accel[0] == 0.0 && accel[1] == 0.0 && std::abs(rate[lane]) < 1e-150) {
          // rate² underflows: time_to_close's root loses |rate| and doubles the time; the
          // division gives the right one.
          const double gap = rate[lane] < 0.0 ? lower[lane] : upper[lane];
          const double exact = std::max(gap, 0.0) / std::abs(rate[lane]);
          CHECK(faces.to_lower[lane] == (rate[lane] < 0.0 ? exact : never));
          CHECK(faces.to_upper[lane] == (rate[lane] > 0.0 ? exact : never));
          CHECK(to_lower_plane[lane] == (rate[lane] < 0.0 ? std::max(lower[lane], 0.0) / -rate[lane] : never));
          CHECK(to_upper_plane[lane] == (rate[lane] > 0.0 ? std::max(upper[lane], 0.0) / rate[lane] : never));
          continue;
        }
        CHECK(std::bit_cast<std::uint64_t>(faces.to_lower[lane]) == std::bit_cast<std::uint64_t>(to_lower[lane]));
        CHECK(std::bit_cast<std::uint64_t>(faces.to_upper[lane]) == std::bit_cast<std::uint64_t>(to_upper[lane]));
        CHECK(std::bit_cast<std::uint64_t>(to_lower_plane[lane]) == std::bit_cast<std::uint64_t>(to_lower[lane]));
        CHECK(std::bit_cast<std::uint64_t>(to_upper_plane[lane]) == std::bit_cast<std::uint64_t>(to_upper[lane]));
      }
    }
  }
}

TEST_CASE("straight-line and quadratic event times") {
  CHECK(time_to_close(1.0, -2.0, 0.0) == doctest::Approx(0.5).scale(1.0));
  CHECK(time_to_close(1.0, 0.0, -2.0) == doctest::Approx(1.0).scale(1.0));
  CHECK(time_to_close(1.0, 1.0, 0.0) == never);
  CHECK(time_to_close(1.0, -1.0, 4.0) == never);   // turns back before reaching the plane
  CHECK(time_to_close(-1e-18, -1.0, 0.0) == 0.0);  // round-off past the plane counts as touching
  CHECK(time_to_close(0.0, 2.0, -1.0) == doctest::Approx(4.0).scale(1.0));  // leaves and falls back
  const double s = sphere_sphere_time(Eigen::Vector3d(3, 0, 0), Eigen::Vector3d(-1, 0, 0), 1.0);
  CHECK(s == doctest::Approx(2.0).scale(1.0));
  CHECK(sphere_sphere_time(Eigen::Vector3d(3, 0, 0), Eigen::Vector3d(1, 0, 0), 1.0) == never);
  CHECK(sphere_sphere_time(Eigen::Vector3d(3, 2, 0), Eigen::Vector3d(-1, 0, 0), 1.0) == never);  // misses
}

TEST_CASE("time_to_close in lanes gives each lane the bits of the scalar function") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    const Lanes2 gap{u(rng), trial % 3 == 0 ? 0.0 : u(rng)}, rate{u(rng), trial % 5 == 0 ? 0.0 : u(rng)};
    const Lanes2 accel{trial % 7 == 0 ? 0.0 : u(rng), u(rng)};
    const Lanes2 lanes = time_to_close(gap, rate, accel);
    for (int l = 0; l < 2; ++l) {
      const double scalar = time_to_close(gap[l], rate[l], accel[l]);
      CHECK(std::bit_cast<std::uint64_t>(lanes[l]) == std::bit_cast<std::uint64_t>(scalar));
    }
  }
}

TEST_CASE("neighbour screen: every instruction set finds the meetings of the scalar test, to the bit") {
  // A sphere among 61 neighbours in random flight since random times, under tilted
  // gravity; some overlap, some touch, most miss.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 62;
  Particles p(n);
  for (int k = 0; k < n; ++k) {
    p.position_m.col(k) = 3e-3 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    p.velocity_m_s.col(k) = Eigen::Vector3d(u(rng), u(rng), u(rng));
    p.radius_m[k] = 5e-4 * (1.5 + 0.5 * u(rng));
  }
  PackedParticles packed(p);
  for (int k = 0; k < n; ++k) packed.t_ref_s[k] = 1e-3 * u(rng);
  const Eigen::Vector3d g(0.3, -0.2, -9.81);
  const double t = 2e-3;
  const ScreenedSphere sphere{packed.position_m.col(0) + 1e-3 * Eigen::Vector3d::Ones(), packed.velocity_m_s.col(0),
                              packed.radius_m[0], t, 0};
  // The scalar test the engine made before the screen, neighbour by neighbour.
  std::vector<int> expected;
  std::vector<PairQuadratic> expected_pairs;
  for (int j = 1; j < n; ++j) {
    const Ballistic f{packed.position_m.col(j), packed.velocity_m_s.col(j), packed.t_ref_s[j]};
    const double contact = sphere.radius_m + packed.radius_m[j];
    const PairQuadratic pair =
        PairQuadratic::of(sphere.position_m - f.position_at(t, g), sphere.velocity_m_s - f.velocity_at(t, g), contact);
    if (pair.meets(contact)) expected.push_back(j), expected_pairs.push_back(pair);
  }
  REQUIRE(expected.size() >= 3);
  REQUIRE(expected.size() <= 40);
  ScreenResult result(n);
  for (const simd::SimdPath path : {simd::SimdPath::sse2, simd::SimdPath::avx2, simd::SimdPath::avx512}) {
    if (!simd::is_available(path)) {
      MESSAGE("this build or processor cannot run " << simd::to_string(path));
      continue;
    }
    for (const int count : {n - 1, 1, 4, 5, 8, 9, 33}) {  // whole groups of lanes and ragged ones
      CAPTURE(simd::to_string(path));
      CAPTURE(count);
      std::vector<int> neighbours(n + screen_width);
      for (int k = 0; k < count; ++k) neighbours[k] = k + 1;
      neighbour_screen(path)(sphere, g, &packed.record(0), neighbours.data(), count, result);
      std::vector<int> met;
      std::vector<PairQuadratic> pairs;
      result.for_each_met(count, [&](int k, const PairQuadratic& pair) {
        met.push_back(neighbours[k]);
        pairs.push_back(pair);
      });
      std::size_t expected_met = 0;
      while (expected_met < expected.size() && expected[expected_met] <= count) ++expected_met;
      REQUIRE(met.size() == expected_met);
      for (std::size_t k = 0; k < met.size(); ++k) {
        CHECK(met[k] == expected[k]);
        CHECK(std::bit_cast<std::uint64_t>(pairs[k].b) == std::bit_cast<std::uint64_t>(expected_pairs[k].b));
        CHECK(std::bit_cast<std::uint64_t>(pairs[k].c) == std::bit_cast<std::uint64_t>(expected_pairs[k].c));
        CHECK(std::bit_cast<std::uint64_t>(pairs[k].discriminant) ==
              std::bit_cast<std::uint64_t>(expected_pairs[k].discriminant));
      }
    }
  }
}

namespace {

/// A prescribed host moving as z = A sin(ωt) (amplitude 0 for fixed walls).
struct PrescribedHost {
  Scenario scenario;
  HostModel model;
  HostTrajectory trajectory;
  PrescribedHost(double amplitude_m, double frequency_hz)
      : scenario(make(amplitude_m, frequency_hz)), model(scenario), trajectory(model, 0.0, model.initial_state()) {}
  static Scenario make(double amplitude_m, double frequency_hz) {
    Scenario s = test::scenario_from("[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = 1\n");
    s.excitation.amplitude_m = amplitude_m;
    s.excitation.frequency_hz = frequency_hz;
    return s;
  }
};

}  // namespace

TEST_CASE("cap contacts under a fast host: never an earlier contact than the one found (adversarial)") {
  const PrescribedHost host(0.002, 400.0);  // 5 m/s, 12 600 m/s²
  const Eigen::Vector3d g(0, 0, -9.81);
  const double r = 5e-4, height = 0.01, tolerance = 1e-14;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int contacts = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const double t0 = uniform(rng) * 0.01;
    const HostState h0 = host.trajectory.at(t0);
    // Gaps from 1e-12 m to a few mm, particle speeds up to 2 m/s either way.
    const double gap = std::pow(10.0, -12.0 + 9.5 * uniform(rng));
    const bool top = trial % 2 == 1;
    const double z = top ? h0.z_m + height - r - gap : h0.z_m + r + gap;
    const Ballistic flight{Eigen::Vector3d(0, 0, z), Eigen::Vector3d(0, 0, 4.0 * (uniform(rng) - 0.5)), t0};
    const double t1 = t0 + 0.004;
    const Approach found = cap_contact(flight, r, top, height, host.trajectory, h0, g, t0, t1, tolerance);
    auto gap_at = [&](double t) {
      const double zt = flight.position_at(t, g).z(), zh = host.trajectory.at(t).z_m;
      return top ? zh + height - zt - r : zt - zh - r;
    };
    // Brute force: no sample before the found time has the spheres overlapping.
    const int samples = 20000;
    for (int k = 0; k < samples; ++k) {
      const double t = t0 + (found.t_s - t0) * k / samples;
      REQUIRE(gap_at(t) >= -tolerance);
    }
    if (found.contact) {
      ++contacts;
      CHECK(gap_at(found.t_s) <= tolerance);
      CHECK(gap_at(found.t_s) >= -tolerance);
    } else {
      CHECK(found.t_s == t1);
    }
  }
  CHECK(contacts > 100);
}

TEST_CASE("a sphere left behind by a floor that accelerates away is caught again at the right time, in few steps") {
  // A floor z_h = A sin ωt at Γ = 1.05, and a sphere that leaves it at its top dead centre
  // with its velocity (0): the floor drops away a little faster than gravity, turns and
  // catches the sphere. The curvature bound alone (g + Aω²) lets the steps grow by only
  // ~5 % each while the gap opens at 0.05 g (78 evaluations); the jerk bound lets the
  // search wait for the floor's acceleration to turn (20).
  const double amplitude = 0.001, omega = std::sqrt(1.05 * 9.81 / amplitude);
  const PrescribedHost host(amplitude, omega / (2 * std::numbers::pi));
  const Eigen::Vector3d g(0, 0, -9.81);
  const double r = 5e-4, tolerance = 1e-14;
  const double t0 = 0.5 * std::numbers::pi / omega;  // the top: z_h = A, v_h = 0
  const HostState h0 = host.trajectory.at(t0);
  const Ballistic flight{Eigen::Vector3d(0, 0, h0.z_m + r), Eigen::Vector3d(0, 0, h0.v_m_s), t0};
  const double t1 = t0 + 2 * std::numbers::pi / omega;
  int evaluations = 0;
  auto gap = [&](double t) {
    ++evaluations;
    const HostState h = host.trajectory.at(t);
    return GapSample{flight.position_at(t, g).z() - r - h.z_m, flight.velocity_at(t, g).z() - h.v_m_s,
                     g.z() - host.trajectory.acceleration_m_s2(t)};
  };
  const double bound = 9.81 + host.trajectory.acceleration_bound_m_s2();
  const Approach found =
      earliest_contact(gap, t0, t1, bound, tolerance, min_approach_speed_m_s, host.trajectory.jerk_bound_m_s3());
  REQUIRE(found.contact);
  // Brute force: the gap is positive between leaving and the contact found, which is the
  // first time it returns to zero.
  auto gap_at = [&](double t) { return flight.position_at(t, g).z() - r - host.trajectory.at(t).z_m; };
  for (int k = 1; k < 20000; ++k) REQUIRE(gap_at(t0 + (found.t_s - t0) * k / 20000.0) >= -tolerance);
  CHECK(std::abs(gap_at(found.t_s)) <= tolerance);
  CHECK(found.t_s - t0 > 0.25 / omega);
  CHECK(evaluations < 60);
  // And cap_contact, which supplies the acceleration and the jerk bound itself, agrees.
  const Approach cap = cap_contact(flight, r, false, 0.01, host.trajectory, h0, g, t0, t1, tolerance);
  REQUIRE(cap.contact);
  CHECK(cap.t_s == test::relative(found.t_s).epsilon(1e-12));
}

TEST_CASE("grazing: a path that just misses the floor is not a contact, one that just touches is") {
  // Gravity pointing up: a sphere moving down at v towards a fixed floor decelerates and
  // comes closest, gap0 − v²/2g, at t = v/g.
  Scenario s = PrescribedHost::make(0.0, 1.0);
  s.gravity_m_s2 = Eigen::Vector3d(0, 0, 9.81);
  const HostModel model(s);
  const HostTrajectory host(model, 0.0, model.initial_state());
  const double r = 5e-4, tolerance = 1e-14, v = 0.3, g = 9.81, approach_depth = v * v / (2 * g);
  for (const double minimum_gap : {3 * tolerance, 0.5 * tolerance, -0.5 * tolerance}) {
    const Ballistic flight{Eigen::Vector3d(0, 0, r + approach_depth + minimum_gap), Eigen::Vector3d(0, 0, -v), 0.0};
    const Approach found = cap_contact(flight, r, false, 0.01, host, host.at(0.0), s.gravity_m_s2, 0.0, 0.1, tolerance);
    CAPTURE(minimum_gap);
    CHECK(found.contact == (minimum_gap <= tolerance));
    if (found.contact) CHECK(found.t_s == test::relative(v / g).epsilon(1e-3));
  }
}

TEST_CASE("rider contacts: the first contact with a sphere riding on a fast host, checked by sampling") {
  const PrescribedHost host(0.001, 200.0);
  const Eigen::Vector3d g(0, 0, -9.81);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const double sigma = 1e-3, tolerance = 1e-14;
  int contacts = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d rider(0, 0, 0.002);
    const HostState h0 = host.trajectory.at(0.0);
    Eigen::Vector3d offset(uniform(rng), uniform(rng), uniform(rng));
    offset = offset.normalized() * (sigma + std::pow(10.0, -11.0 + 8.0 * (0.5 + 0.5 * uniform(rng))));
    const Ballistic flight{rider + offset + h0.z_m * Eigen::Vector3d::UnitZ(),
                           Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)), 0.0};
    const Approach found = rider_contact(flight, rider, sigma, host.trajectory, h0, g, 0.0, 0.003, tolerance);
    auto gap_at = [&](double t) {
      return (flight.position_at(t, g) - rider - host.trajectory.at(t).z_m * Eigen::Vector3d::UnitZ()).norm() - sigma;
    };
    for (int k = 0; k < 5000; ++k) REQUIRE(gap_at(found.t_s * k / 5000) >= -tolerance);
    if (found.contact) {
      ++contacts;
      CHECK(std::abs(gap_at(found.t_s)) <= tolerance);
    }
  }
  CHECK(contacts > 50);
}

TEST_CASE("stays_apart: where it holds, the cap and rider root finders find no contact on the span") {
  // The engine skips the root finders where stays_apart holds; they must then have had
  // nothing to find. Gaps from 1e-14 m (within the tolerance) to mm, a fast host.
  const PrescribedHost host(0.002, 400.0);
  const Eigen::Vector3d g(0, 0, -9.81);
  const double r = 5e-4, height = 0.01, sigma = 1e-3, tolerance = 1e-14;
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int apart = 0, not_apart = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const double t0 = uniform(rng) * 0.01, span = std::pow(10.0, -7.0 + 5.0 * uniform(rng));
    const HostState h0 = host.trajectory.at(t0);
    const double gap = std::pow(10.0, -14.0 + 11.0 * uniform(rng));
    const Eigen::Vector3d v(uniform(rng) - 0.5, uniform(rng) - 0.5, 4.0 * (uniform(rng) - 0.5));
    const double relative_vz = v.z() - h0.v_m_s;
    const bool top = trial % 2 == 1;
    const double z = top ? h0.z_m + height - r - gap : h0.z_m + r + gap;
    const Ballistic to_cap{Eigen::Vector3d(0, 0, z), v, t0};
    const double cap_curvature = std::abs(g.z()) + host.trajectory.acceleration_bound_m_s2();
    const bool cap_apart = stays_apart(cap_gap_m(to_cap, r, top, height, h0, g, t0), top ? -relative_vz : relative_vz,
                                       cap_curvature, span, tolerance);
    if (cap_apart) {
      const Approach found = cap_contact(to_cap, r, top, height, host.trajectory, h0, g, t0, t0 + span, tolerance);
      REQUIRE(!found.contact);
      CHECK(found.t_s == t0 + span);
    }
    // A rider below the sphere's path, at host-frame (0, 0, 2 mm).
    const Eigen::Vector3d rider(0, 0, 0.002);
    Eigen::Vector3d offset(uniform(rng) - 0.5, uniform(rng) - 0.5, uniform(rng) - 0.5);
    offset = offset.normalized() * (sigma + gap);
    const Ballistic to_rider{rider + offset + h0.z_m * Eigen::Vector3d::UnitZ(), v, t0};
    Eigen::Vector3d relative_v = v;
    relative_v.z() -= h0.v_m_s;
    const bool rider_apart = stays_apart(rider_offset_m(to_rider, rider, h0, g, t0).norm() - sigma, -relative_v.norm(),
                                         g.norm() + host.trajectory.acceleration_bound_m_s2(), span, tolerance);
    if (rider_apart) {
      const Approach found = rider_contact(to_rider, rider, sigma, host.trajectory, h0, g, t0, t0 + span, tolerance);
      REQUIRE(!found.contact);
      CHECK(found.t_s == t0 + span);
    }
    apart += cap_apart + rider_apart;
    not_apart += !cap_apart + !rider_apart;
  }
  // Both answers come up often.
  CHECK(apart > 1000);
  CHECK(not_apart > 1000);
}

TEST_CASE("surely_farther: where it holds, the square root's tests it stands for fail too") {
  // The rider searches skip the square root where surely_farther holds: the tests they
  // would have made, |dx| − reach ≤ tolerance (the margin test) and |dx| − σ − closing ≤
  // slack (the touching bound; stays_apart's likewise), must then have failed. Distances
  // from nm to m, within a few ulps to a part in 10⁶ of the boundary either way.
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int farther = 0, not_farther = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const double scale = std::pow(10.0, -9.0 + 9.0 * uniform(rng));
    const Eigen::Vector3d dx =
        scale * Eigen::Vector3d(uniform(rng) - 0.5, uniform(rng) - 0.5, uniform(rng) - 0.5).normalized();
    const double squared = dx.squaredNorm();
    const double offset = (uniform(rng) < 0.5 ? -1.0 : 1.0) * std::pow(10.0, -16.0 + 10.0 * uniform(rng));
    const double total = dx.norm() * (1.0 + offset);
    const double tolerance = total * std::pow(10.0, -12.0 + 10.0 * uniform(rng));
    const double reach = total - tolerance;
    if (surely_farther(squared, reach + tolerance)) {
      ++farther;
      REQUIRE(!(dx.norm() - reach <= tolerance));
      const double closing = 0.3 * reach, sigma = reach - closing;
      REQUIRE(!(dx.norm() - sigma - closing <= tolerance));
    } else {
      ++not_farther;
    }
  }
  CHECK(farther > 3000);
  CHECK(not_farther > 3000);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  CHECK(!surely_farther(nan, 1.0));
  CHECK(!surely_farther(1.0, nan));
  CHECK(!surely_farther(inf, inf));
  CHECK(surely_farther(4.0, 1.0));
  CHECK(!surely_farther(1.0, 1.0));
}

TEST_CASE("side wall under tilted gravity: the quartic's first root, checked by sampling") {
  const Eigen::Vector3d g(3.0, -2.0, -9.0);
  const double reach = 0.005, tolerance = 1e-14;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d x(0.004 * uniform(rng), 0.003 * uniform(rng), 0.0);
    const Ballistic flight{x, Eigen::Vector3d(0.3 * uniform(rng), 0.3 * uniform(rng), 0.0), 0.0};
    const Approach found = side_wall_contact(flight, reach, g, 0.0, 0.2, tolerance);
    auto gap_at = [&](double t) { return reach - flight.position_at(t, g).head<2>().norm(); };
    for (int k = 0; k < 5000; ++k) REQUIRE(gap_at(found.t_s * k / 5000) >= -tolerance);
    CHECK(found.contact);  // gravity pushes every sphere to the wall within 0.2 s
    CHECK(std::abs(gap_at(found.t_s)) <= 2 * tolerance);
  }
}

TEST_CASE("the host's acceleration crossing -g: the time the bed lifts off a sinusoidal floor") {
  const double amplitude = 0.0005, frequency = 30.0, w = 2 * std::numbers::pi * frequency;
  const PrescribedHost host(amplitude, frequency);
  // z'' = −A ω² sin(ωt) first reaches −g at ωt = asin(g / (A ω²)).
  const Approach lift = host_acceleration_crossing(host.trajectory, -9.81, true, 0.0, 0.02, 1e-9);
  REQUIRE(lift.contact);
  CHECK(lift.t_s == test::relative(std::asin(9.81 / (amplitude * w * w)) / w).epsilon(1e-6));
}

TEST_CASE(
    "contact laws: slow first approaches are elastic, repeats at one instant keep the law, calibration sets e_n") {
  Scenario s = test::scenario_from("[hard]\nen = 0.6\nmu = 0.3\nbeta0 = 0.2\n[hard_wall]\nen = 0.4\n");
  const ContactLaws constant(s, nullptr);
  const double slow = 0.5 * s.hard_resting.elastic_speed_m_s, fast = 2.0 * s.hard_resting.elastic_speed_m_s;
  CHECK(constant.at(fast, Partner::sphere, false).en == 0.6);
  CHECK(constant.at(fast, Partner::cap, false).en == 0.4);
  CHECK(constant.at(fast, Partner::sphere, false).mu == 0.3);
  CHECK(constant.at(slow, Partner::sphere, false).en == 1.0);
  CHECK(constant.at(slow, Partner::cap, false).en == 1.0);
  CHECK(constant.at(slow, Partner::sphere, true).en == 0.6);  // wedged: the sequence must die out
  CHECK(constant.at(fast, Partner::side_wall, false).en == 0.4);
  CHECK(constant.at(slow, Partner::side_wall, false).en == 1.0);
  // The side wall has an elastic speed of its own: raising the others' leaves its law.
  Scenario raised = s;
  raised.hard_resting.elastic_speed_m_s = 0.1;
  const ContactLaws dense(raised, nullptr);
  CHECK(dense.at(0.05, Partner::sphere, false).en == 1.0);
  CHECK(dense.at(0.05, Partner::cap, false).en == 1.0);
  CHECK(dense.at(0.05, Partner::side_wall, false).en == 0.4);
  CHECK(dense.at(0.5 * raised.hard_resting.side_wall_elastic_speed_m_s, Partner::side_wall, false).en == 1.0);
  RestitutionTable table;
  table.sphere_sphere = {{0.01, 1.0}, {0.9, 0.5}, {0.3, 0.1}};
  table.sphere_wall = {{0.01, 1.0}, {0.8, 0.4}, {0.2, 0.0}};
  const ContactLaws calibrated(s, &table);
  CHECK(calibrated.at(0.1, Partner::sphere, false).en ==
        doctest::Approx(0.7).scale(1.0).epsilon(1e-12));  // halfway in log(speed)
  CHECK(calibrated.at(0.1, Partner::cap, false).beta0 == test::relative(0.1).epsilon(1e-12));
  CHECK(calibrated.at(slow, Partner::sphere, false).en == 1.0);
}

TEST_CASE("sticking to the host: a free host shares the body's vertical momentum, a prescribed one does the work") {
  const double m = 3e-5, vz = -0.4, host_v = 0.25, carried = 0.02;
  const VerticalSticking free = stick_vertically(m, vz, host_v, false, carried);
  CHECK(carried * free.host_v_m_s + m * free.host_v_m_s == test::relative(carried * host_v + m * vz).epsilon(1e-15));
  const double before = 0.5 * m * vz * vz + 0.5 * carried * host_v * host_v;
  const double after = 0.5 * (m + carried) * free.host_v_m_s * free.host_v_m_s;
  CHECK(free.loss_J == test::relative(before - after).epsilon(1e-12));
  CHECK(free.host_work_J == 0.0);
  const VerticalSticking prescribed = stick_vertically(m, vz, host_v, true, 0.0);
  CHECK(prescribed.host_v_m_s == host_v);
  // The body's energy change is the host's work less the loss.
  CHECK(0.5 * m * host_v * host_v - 0.5 * m * vz * vz ==
        test::relative(prescribed.host_work_J - prescribed.loss_J).epsilon(1e-14));
}

TEST_CASE("side wall: a sphere barely leaving the curved wall is turned away at the floor speed, its energy kept") {
  const Eigen::Vector2d outward(0.6, 0.8);
  const double floor_speed = 1e-4;
  // Sliding along the wall, leaving at a tenth of the floor speed.
  const Eigen::Vector2d along(-0.8, 0.6);
  const Eigen::Vector2d v = 0.02 * along - 1e-5 * outward;
  const Eigen::Vector2d turned = turned_along_side_wall(v, outward, floor_speed);
  CHECK(turned.squaredNorm() == test::relative(v.squaredNorm()).epsilon(1e-14));
  CHECK(-turned.dot(outward) == test::relative(floor_speed).epsilon(1e-12));
  CHECK(turned.dot(along) > 0.0);
  // Leaving fast enough, or too slow to reach the floor speed at all: unchanged.
  const Eigen::Vector2d leaving = 0.02 * along - 0.001 * outward;
  CHECK(turned_along_side_wall(leaving, outward, floor_speed) == leaving);
  const Eigen::Vector2d crawling = 5e-5 * along;
  CHECK(turned_along_side_wall(crawling, outward, floor_speed) == crawling);
}
