#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include "pdamp/model/host.hpp"
#include "test_support.hpp"

using namespace pdamp;
using pdamp::test::scenario_from;

namespace {

/// Classical RK4 on M z'' = force(t, z, z') + extra: an independent check of the closed form.
HostState integrate_rk4(const HostModel& model, HostState s, double t_end, int steps, double added_mass = 0.0,
                        double added_force = 0.0) {
  const double m = model.mass_kg() + added_mass;
  const double dt = t_end / steps;
  auto accel = [&](double t, double z, double v) { return (model.force_N(t, {z, v}) + added_force) / m; };
  double t = 0.0;
  for (int i = 0; i < steps; ++i, t = i * dt) {
    const double k1z = s.v_m_s, k1v = accel(t, s.z_m, s.v_m_s);
    const double k2z = s.v_m_s + 0.5 * dt * k1v, k2v = accel(t + 0.5 * dt, s.z_m + 0.5 * dt * k1z, k2z);
    const double k3z = s.v_m_s + 0.5 * dt * k2v, k3v = accel(t + 0.5 * dt, s.z_m + 0.5 * dt * k2z, k3z);
    const double k4z = s.v_m_s + dt * k3v, k4v = accel(t + dt, s.z_m + dt * k3z, k4z);
    s.z_m += dt / 6 * (k1z + 2 * k2z + 2 * k3z + k4z);
    s.v_m_s += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
  }
  return s;
}

const std::string host_only = "[particles]\ncount = 0\n";

}  // namespace

TEST_CASE("free decay of the Table 1 host matches the textbook solution") {
  const Scenario s = scenario_from(host_only);
  const HostModel model(s);
  const HostTrajectory trajectory(model, 0.0, model.initial_state());
  const double w0 = std::sqrt(470.0 / 0.0376), alpha = 0.1 / (2 * 0.0376), wd = std::sqrt(w0 * w0 - alpha * alpha);
  CHECK(w0 / (2 * std::numbers::pi) == doctest::Approx(17.79).scale(1.0).epsilon(1e-3));
  for (double t = 0.0; t < 2.0; t += 0.0137) {
    const double z = 0.0157 * std::exp(-alpha * t) * (std::cos(wd * t) + alpha / wd * std::sin(wd * t));
    const double v = -0.0157 * std::exp(-alpha * t) * (w0 * w0 / wd) * std::sin(wd * t);
    CHECK(std::abs(trajectory.at(t).z_m - z) <= 1e-15);
    CHECK(std::abs(trajectory.at(t).v_m_s - v) <= 1e-13);
  }
}

TEST_CASE("the closed form agrees with RK4 on the host ODE for every mode and damping regime") {
  struct Case {
    const char* name;
    std::string text;
  };
  // Critical damping of M = 0.0376, K = 470: C = 2 sqrt(K M) = 8.4076...
  const double critical = 2 * std::sqrt(470.0 * 0.0376);
  const Case cases[] = {
      {"under-damped free", ""},
      {"critically damped free", "[host]\ndamping_N_s_m = " + std::to_string(critical) + "\n"},
      {"nearly critical (just under)", "[host]\ndamping_N_s_m = " + std::to_string(critical * (1 - 1e-7)) + "\n"},
      {"nearly critical (just over)", "[host]\ndamping_N_s_m = " + std::to_string(critical * (1 + 1e-7)) + "\n"},
      {"over-damped free", "[host]\ndamping_N_s_m = 30\nv0_m_s = 0.3\n"},
      {"undamped free", "[host]\ndamping_N_s_m = 0\nv0_m_s = -0.2\n"},
      {"base motion", "[excitation]\nmode = base\namplitude_m = 0.002\nfrequency_hz = 13\nphase_rad = 0.4\n"},
      {"force", "[excitation]\nmode = force\nforce_N = 0.7\nfrequency_hz = 25\nphase_rad = -1\n"},
      {"force near resonance", "[excitation]\nmode = force\nforce_N = 0.7\nfrequency_hz = 17.7\n"},
      {"over-damped base motion",
       "[host]\ndamping_N_s_m = 30\n[excitation]\nmode = base\namplitude_m = 0.002\nfrequency_hz = 40\n"},
  };
  for (const auto& c : cases) {
    CAPTURE(c.name);
    const Scenario s = scenario_from(host_only + c.text);
    const HostModel model(s);
    for (const auto& [added_mass, added_force] : {std::pair{0.0, 0.0}, std::pair{0.004, -0.004 * 9.81}}) {
      const HostTrajectory trajectory(model, 0.0, model.initial_state(), added_mass, added_force);
      for (double t : {0.01, 0.1, 0.37}) {
        const HostState reference = integrate_rk4(model, model.initial_state(), t, 20000, added_mass, added_force);
        const HostState exact = trajectory.at(t);
        CHECK(exact.z_m == doctest::Approx(reference.z_m).epsilon(1e-9).scale(0.0157));
        CHECK(exact.v_m_s == doctest::Approx(reference.v_m_s).epsilon(1e-9).scale(0.0157 * 112));
        // The acceleration is the ODE's right-hand side at the exact state.
        const double h = 1e-6;
        const double numeric = (trajectory.at(t + h).v_m_s - trajectory.at(t - h).v_m_s) / (2 * h);
        CHECK(trajectory.acceleration_m_s2(t) == doctest::Approx(numeric).epsilon(1e-6).scale(20.0));
      }
    }
  }
}

TEST_CASE("restarting the trajectory from any of its own states changes nothing") {
  const Scenario s = scenario_from(host_only + "[excitation]\nmode = base\namplitude_m = 0.002\nfrequency_hz = 13\n");
  const HostModel model(s);
  const HostTrajectory first(model, 0.0, model.initial_state());
  const HostTrajectory restarted(model, 0.23, first.at(0.23));
  for (double t : {0.25, 0.5, 1.7}) {
    CHECK(restarted.at(t).z_m == doctest::Approx(first.at(t).z_m).epsilon(1e-12).scale(0.0157));
    CHECK(restarted.at(t).v_m_s == doctest::Approx(first.at(t).v_m_s).epsilon(1e-12).scale(1.0));
  }
}

TEST_CASE("forced steady state has the textbook amplitude") {
  const Scenario s =
      scenario_from(host_only + "[host]\nz0_m = 0\n[excitation]\nmode = force\nforce_N = 0.5\nfrequency_hz = 20\n");
  const HostModel model(s);
  const HostTrajectory trajectory(model, 0.0, model.initial_state());
  const double w = 2 * std::numbers::pi * 20;
  const double expected = 0.5 / std::hypot(470 - 0.0376 * w * w, 0.1 * w);
  double peak = 0.0;
  for (double t = 30.0; t < 30.1; t += 1e-5) peak = std::max(peak, std::abs(trajectory.at(t).z_m));
  CHECK(peak == test::relative(expected).epsilon(1e-6));
}

TEST_CASE("energy: viscous dissipation and excitation work balance the host's energy to round-off") {
  const char* const modes[] = {
      "",
      "[host]\ndamping_N_s_m = 30\nv0_m_s = 0.3\n",
      "[excitation]\nmode = base\namplitude_m = 0.002\nfrequency_hz = 13\nphase_rad = 0.4\n",
      "[excitation]\nmode = force\nforce_N = 0.7\nfrequency_hz = 25\n",
  };
  for (const std::string text : modes) {
    CAPTURE(text);
    const Scenario s = scenario_from(host_only + text);
    const HostModel model(s);
    const HostTrajectory trajectory(model, 0.0, model.initial_state());
    auto energy = [&](double t) {
      const HostState st = trajectory.at(t);
      return 0.5 * model.mass_kg() * st.v_m_s * st.v_m_s + model.spring_energy_J(t, st.z_m);
    };
    double dissipated = 0.0, work = 0.0;
    for (double t = 0.0; t < 1.5; t += 0.0371) {  // piecewise, as an engine integrates between events
      const HostTrajectory::Stretch stretch = trajectory.stretch(t, t + 0.0371, 0.0, 0.0);
      dissipated += stretch.viscous_J;
      work += stretch.excitation_J;
    }
    const double t_end = 0.0371 * std::ceil(1.5 / 0.0371);
    const double residual = energy(0.0) + work - energy(t_end) - dissipated;
    CHECK(std::abs(residual) <= 1e-12 * (energy(0.0) + std::abs(work)));
    CHECK(dissipated > 0.0);
  }
}

TEST_CASE("speed, acceleration and jerk bounds hold for every later time") {
  const char* const modes[] = {
      "",
      "[host]\ndamping_N_s_m = 30\nv0_m_s = 0.3\n",
      "[host]\ndamping_N_s_m = 0\n",
      "[excitation]\nmode = base\namplitude_m = 0.002\nfrequency_hz = 13\n",
      "[excitation]\nmode = force\nforce_N = 0.7\nfrequency_hz = 17.5\n",
      "[excitation]\nmode = prescribed\namplitude_m = 0.002\nfrequency_hz = 60\n",
  };
  for (const std::string text : modes) {
    CAPTURE(text);
    const Scenario s = scenario_from(host_only + text);
    const HostModel model(s);
    const HostTrajectory trajectory(model, 0.1, model.initial_state());
    double max_speed = 0, max_accel = 0, max_jerk = 0;
    const double dt = 1.3e-4;
    for (double t = 0.1; t < 5.0; t += dt) {
      max_speed = std::max(max_speed, std::abs(trajectory.at(t).v_m_s));
      max_accel = std::max(max_accel, std::abs(trajectory.acceleration_m_s2(t)));
      // The mean jerk over a step never exceeds the largest jerk inside it.
      max_jerk =
          std::max(max_jerk, std::abs(trajectory.acceleration_m_s2(t + dt) - trajectory.acceleration_m_s2(t)) / dt);
    }
    CHECK(max_speed <= trajectory.speed_bound_m_s());
    CHECK(max_accel <= trajectory.acceleration_bound_m_s2());
    CHECK(max_jerk <= trajectory.jerk_bound_m_s3());
    CHECK(trajectory.jerk_bound_m_s3() <= 10 * max_jerk);
    // ... and they are not uselessly loose.
    CHECK(trajectory.speed_bound_m_s() <= 3 * max_speed);
    CHECK(trajectory.acceleration_bound_m_s2() <= 4 * max_accel);
  }
}

TEST_CASE("a prescribed host follows A sin(wt + phi) exactly") {
  const Scenario s = scenario_from(
      host_only + "[excitation]\nmode = prescribed\namplitude_m = 0.002\nfrequency_hz = 60\nphase_rad = 0.5\n");
  const HostModel model(s);
  const HostTrajectory trajectory(model, 0.0, model.initial_state());
  const double w = 2 * std::numbers::pi * 60;
  for (double t : {0.0, 0.001, 0.3}) {
    CHECK(trajectory.at(t).z_m == doctest::Approx(0.002 * std::sin(w * t + 0.5)).scale(0.002).epsilon(1e-14));
    CHECK(trajectory.at(t).v_m_s == doctest::Approx(0.002 * w * std::cos(w * t + 0.5)).scale(0.002 * w).epsilon(1e-14));
    CHECK(trajectory.acceleration_m_s2(t) ==
          doctest::Approx(-0.002 * w * w * std::sin(w * t + 0.5)).scale(0.002 * w * w).epsilon(1e-14));
  }
  CHECK(model.has_infinite_mass());
  CHECK(trajectory.stretch(0, 1, 0.0, 0.0).viscous_J == 0.0);
}
