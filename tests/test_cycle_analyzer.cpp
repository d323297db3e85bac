#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "pdamp/analysis/cycle_analyzer.hpp"

using namespace pdamp;

namespace {

/// A damped oscillation about `offset` with viscous losses booked as the host's energy loss.
struct DampedOscillation {
  double mass = 0.0376, z0 = 0.0157, alpha = 1.33, wd = 111.8, offset = 0.0;
  Observation at(double t) const {
    Observation o;
    o.t_s = t;
    const double e = std::exp(-alpha * t);
    o.host.z_m = offset + z0 * e * (std::cos(wd * t) + alpha / wd * std::sin(wd * t));
    o.host.v_m_s = -z0 * e * (alpha * alpha + wd * wd) / wd * std::sin(wd * t);
    const double k = mass * (alpha * alpha + wd * wd);
    const double energy =
        0.5 * mass * o.host.v_m_s * o.host.v_m_s + 0.5 * k * (o.host.z_m - offset) * (o.host.z_m - offset);
    o.energy.dissipated_viscous_J = 0.5 * k * z0 * z0 - energy;
    return o;
  }
};

std::vector<CycleRecord> analyse(const DampedOscillation& osc, double dt, double t_end, double g, double jitter = 0.0) {
  CycleAnalyzer analyzer(osc.mass, osc.offset, g);
  std::vector<CycleRecord> cycles;
  for (int i = 0; i * dt <= t_end; ++i) {
    Observation o = osc.at(i * dt);
    // Impacts near the crest: the velocity flips sign briefly without a new cycle.
    if (jitter > 0 && i > 0 && i % 3 == 0) o.host.v_m_s += jitter * (i % 2 ? 1 : -1);
    if (auto c = analyzer.feed(o)) cycles.push_back(*c);
  }
  return cycles;
}

}  // namespace

TEST_CASE("cycle analysis of a viscous free decay") {
  const DampedOscillation osc;
  const double period = 2 * std::numbers::pi / osc.wd;
  const auto cycles = analyse(osc, period / 256, 1.0, 9.81);
  REQUIRE(cycles.size() >= 16);
  const double expected_psi_start = 1 - std::exp(-2 * osc.alpha * period);  // energy lost over one period at the crests
  for (std::size_t i = 0; i < cycles.size(); ++i) {
    const auto& c = cycles[i];
    CAPTURE(i);
    CHECK(c.cycle == static_cast<int>(i) + 1);
    CHECK(c.freq_hz == doctest::Approx(osc.wd / (2 * std::numbers::pi)).scale(1.0).epsilon(1e-5));
    const double a = osc.z0 * std::exp(-osc.alpha * c.t_start_s);
    CHECK(c.amplitude_m == doctest::Approx(a * (1 + std::exp(-osc.alpha * period / 2)) / 2).scale(0.0).epsilon(2e-3));
    REQUIRE(c.gamma.has_value());
    CHECK(*c.gamma == doctest::Approx(c.amplitude_m * std::pow(2 * std::numbers::pi * c.freq_hz, 2) / 9.81).scale(0.0));
    CHECK(c.psi == doctest::Approx(c.psi_viscous).scale(0.0));
    CHECK(c.psi_impact == 0.0);
    // Energy lost over the cycle relative to the peak kinetic energy, which comes a quarter cycle in.
    CHECK(c.psi ==
          doctest::Approx(expected_psi_start / std::exp(-2 * osc.alpha * period / 4)).scale(0.0).epsilon(2e-3));
  }
  CHECK(cycles.front().t_start_s == doctest::Approx(0.0).scale(period).epsilon(1e-9));
}

TEST_CASE("velocity jitter near crests does not split cycles, and no gravity gives no Gamma") {
  DampedOscillation osc;
  osc.offset = -0.0008;
  const double period = 2 * std::numbers::pi / osc.wd;
  const auto clean = analyse(osc, period / 300, 0.8, 0.0);
  const auto jittery = analyse(osc, period / 300, 0.8, 0.0, 0.02);
  REQUIRE(clean.size() >= 12);
  CHECK(jittery.size() == clean.size());
  CHECK_FALSE(clean.front().gamma.has_value());
}
