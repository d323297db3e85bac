#pragma once
/// Helpers shared by the tests.

#include <doctest/doctest.h>
#include <unistd.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine_models.hpp"
#include "hard/event_queue.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/model/particles.hpp"
#include "pdamp/model/scenario_loader.hpp"
#include "pdamp/sim/engine_factory.hpp"

namespace pdamp::test {

/// Approx relative to `value` alone: doctest's default scale of 1 makes comparisons of
/// quantities far below 1 (joules, metres, seconds of a millimetre sphere) vacuous. Not
/// for a value that may be exactly 0: doctest's test is strict, so 0 == relative(0) fails.
inline doctest::Approx relative(double value) { return doctest::Approx(value).scale(0.0); }

inline std::filesystem::path source_dir() { return PDAMP_SOURCE_DIR; }
inline std::filesystem::path scenario_file(const std::string& name) {
  return source_dir() / "data" / "scenarios" / (name + ".ini");
}
/// data/scenarios/small.ini, as a study file names its base scenario.
inline std::string small() { return scenario_file("small").string(); }

inline void write_file(const std::filesystem::path& file, const std::string& text) { std::ofstream(file) << text; }

/// The engine's statistic `name` (Engine::statistics); throws if it has none.
inline std::int64_t statistic(const Engine& engine, const std::string& name) {
  for (const auto& [key, value] : engine.statistics()) {
    if (key == name) return value;
  }
  throw std::invalid_argument("no engine statistic '" + name + "'");
}

/// Each sphere's share of the losses (Engine::dissipation_by_sphere) adds up to the
/// ledger's impact and friction losses, to the rounding of summing them in another order.
inline void check_dissipation_by_sphere(const Engine& engine) {
  const SphereDissipation by_sphere = engine.dissipation_by_sphere();
  const EnergyLedger ledger = engine.observe().energy;
  const double total_J = ledger.dissipated_impact_J + ledger.dissipated_friction_J;
  CAPTURE(total_J);
  REQUIRE(by_sphere.impact_J.size() == engine.state().particles.size());
  REQUIRE(by_sphere.friction_J.size() == by_sphere.impact_J.size());
  CHECK(std::abs(by_sphere.impact_J.sum() - ledger.dissipated_impact_J) <= 1e-12 * total_J);
  CHECK(std::abs(by_sphere.friction_J.sum() - ledger.dissipated_friction_J) <= 1e-12 * total_J);
}

/// The four excitation modes on small.ini's host, each with a drive that shakes its bed
/// ({} is the free decay): for tests that hold in every mode.
inline std::vector<ScenarioOverrides> excitation_modes() {
  return {
      {},
      {"excitation.mode=prescribed", "excitation.amplitude_m=0.001", "excitation.frequency_hz=30"},
      {"excitation.mode=base", "excitation.amplitude_m=0.002", "excitation.frequency_hz=22"},
      {"excitation.mode=force", "excitation.force_N=2", "excitation.frequency_hz=15"},
  };
}

/// Two engine states are the same bits: spheres, host and the energy books.
inline void check_same_state(const State& a, const State& b) {
  CHECK(a.particles.position_m == b.particles.position_m);
  CHECK(a.particles.velocity_m_s == b.particles.velocity_m_s);
  CHECK(a.particles.angular_velocity_rad_s == b.particles.angular_velocity_rad_s);
  CHECK(a.observation.host.z_m == b.observation.host.z_m);
  CHECK(a.observation.energy.dissipated_impact_J == b.observation.energy.dissipated_impact_J);
  CHECK(a.observation.energy.dissipated_friction_J == b.observation.energy.dissipated_friction_J);
  CHECK(a.observation.energy.contact_elastic_J == b.observation.energy.contact_elastic_J);
}

/// A scenario from inline text (every unspecified key takes its default).
inline Scenario scenario_from(const std::string& text, const ScenarioOverrides& overrides = {}) {
  return parse_scenario(text, "test", "test scenario", overrides);
}

/// A scenario from inline text whose walls do not move: a prescribed host of zero amplitude.
inline Scenario fixed_walls(const std::string& text) {
  Scenario s = scenario_from(text + "\n[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = 1\n");
  s.excitation.amplitude_m = 0.0;
  return s;
}

/// Spheres at the given positions and velocities, at rest otherwise; 1 mm lead by default.
inline Particles spheres(const std::vector<Eigen::Vector3d>& positions, const std::vector<Eigen::Vector3d>& velocities,
                         double radius_m = 0.0005, double density_kg_m3 = 9000) {
  Particles p(static_cast<Eigen::Index>(positions.size()));
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    p.position_m.col(k) = positions[i];
    p.velocity_m_s.col(k) = velocities[i];
    p.radius_m[k] = radius_m;
    p.mass_kg[k] = density_kg_m3 * 4.0 / 3.0 * std::numbers::pi * radius_m * radius_m * radius_m;
  }
  return p;
}

/// Of any spheres with the fields of Particles (PackedParticles too): their kinetic
/// energy, translational and rotational.
template <class Spheres>
double kinetic_energy(const Spheres& p) {
  double e = 0;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    e += 0.5 * p.mass_kg[i] * p.velocity_m_s.col(i).squaredNorm() +
         0.5 * p.moment_of_inertia(i) * p.angular_velocity_rad_s.col(i).squaredNorm();
  }
  return e;
}
/// Their momentum.
template <class Spheres>
Eigen::Vector3d momentum(const Spheres& p) {
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (Eigen::Index i = 0; i < p.size(); ++i) total += p.mass_kg[i] * p.velocity_m_s.col(i);
  return total;
}
/// Their angular momentum about the origin, spins included.
template <class Spheres>
Eigen::Vector3d angular_momentum(const Spheres& p) {
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    total += p.mass_kg[i] * Eigen::Vector3d(p.position_m.col(i)).cross(Eigen::Vector3d(p.velocity_m_s.col(i))) +
             p.moment_of_inertia(i) * p.angular_velocity_rad_s.col(i);
  }
  return total;
}

/// Every event in a hard engine's queue, earliest first (the queue is emptied).
inline std::vector<hard::Event> drain(hard::EventQueue& queue) {
  std::vector<hard::Event> events;
  const auto all = [](const hard::Event&) { return true; };
  for (const hard::Event* e = queue.top(all); e; e = queue.top(all)) {
    events.push_back(*e);
    queue.pop();
  }
  return events;
}

/// The 1D Hertz-dashpot contact m* δ'' = −max(0, k δ^{3/2} + c δ'), advanced by RK4.
/// `kn` in N/m^1.5, `cn` in N·s/m.
struct HertzDashpotContact {
  double effective_mass_kg, kn, cn;
  double delta = 0.0;  ///< overlap (m)
  double rate = 0.0;   ///< its rate δ' (m/s)

  void step(double dt_s) {
    auto accel = [&](double d, double r) {
      return -std::max(0.0, kn * std::pow(std::max(d, 0.0), 1.5) + cn * r) / effective_mass_kg;
    };
    const double k1d = rate, k1r = accel(delta, rate);
    const double k2d = rate + 0.5 * dt_s * k1r, k2r = accel(delta + 0.5 * dt_s * k1d, k2d);
    const double k3d = rate + 0.5 * dt_s * k2r, k3r = accel(delta + 0.5 * dt_s * k2d, k3d);
    const double k4d = rate + dt_s * k3r, k4r = accel(delta + dt_s * k3d, k4d);
    delta += dt_s / 6 * (k1d + 2 * k2d + 2 * k3d + k4d);
    rate += dt_s / 6 * (k1r + 2 * k2r + 2 * k3r + k4r);
  }
};

/// A single normal impact by the soft law, integrated far more finely than any engine step.
struct ReferenceImpact {
  double restitution;  ///< rebound speed over impact speed
  double contact_time_s;
};

/// The impact from δ = 0 at `speed_m_s` until the bodies part, by RK4 at `dt_s`.
inline ReferenceImpact reference_hertz_impact(double effective_mass_kg, double kn, double cn, double speed_m_s,
                                              double dt_s) {
  HertzDashpotContact contact{effective_mass_kg, kn, cn, 0.0, speed_m_s};
  double t = 0.0;
  do {
    contact.step(dt_s);
    t += dt_s;
  } while (contact.delta > 0.0);
  return {-contact.rate / speed_m_s, t};
}

/// A fresh directory under the build tree's temporary folder, removed when destroyed.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() / ("pdamp-test-" + name + "-" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& file) const { return path_ / file; }

 private:
  std::filesystem::path path_;
};

/// The steady response of M z'' + C z' + K z = F0 sin θ (force) or of the host on a base
/// y = Y sin θ: amplitude X and phase against the excitation.
struct ClosedForm {
  double amplitude_m, phase_rad;
};
inline ClosedForm host_alone(const Scenario& s) {
  const double k = s.host.stiffness_N_m, c = s.host.damping_N_s_m, m = s.host.mass_kg;
  const double w = s.excitation.angular_frequency_rad_s();
  const double dynamic = std::hypot(k - m * w * w, c * w), lag = std::atan2(c * w, k - m * w * w);
  if (s.excitation.mode == ExcitationMode::force) return {s.excitation.force_N / dynamic, -lag};
  return {s.excitation.amplitude_m * std::hypot(k, c * w) / dynamic, std::atan2(c * w, k) - lag};
}

}  // namespace pdamp::test
