#pragma once
/// The hard engine's benchmark case, written once for the benchmark (pdamp_bench) and for
/// the tests that check what it measures: n elastic, frictionless spheres of 1 mm
/// (8,000 kg/m^3), no gravity, in a closed cylinder with D = H at solid fraction
/// `packing`. The walls are fixed, or with `free_host` belong to a free undamped host of
/// ten times the spheres' mass on a 20 Hz spring, so that every cap collision moves it.

#include <cmath>
#include <numbers>
#include <string>

#include "pdamp/model/scenario_loader.hpp"

namespace pdamp::bench {

inline constexpr double gas_sphere_diameter_m = 0.001;
inline constexpr double gas_density_kg_m3 = 8000;

inline Scenario benchmark_gas(int n, double packing, bool free_host) {
  const double d = gas_sphere_diameter_m;
  const double volume_m3 = n * std::numbers::pi / 6 * d * d * d / packing;
  const double diameter_m = std::cbrt(4 * volume_m3 / std::numbers::pi);
  const double host_mass_kg = 10.0 * n * gas_density_kg_m3 * std::numbers::pi / 6 * d * d * d;
  const double host_stiffness_N_m = host_mass_kg * std::pow(2 * std::numbers::pi * 20.0, 2);
  std::string text = "[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = " + std::to_string(diameter_m) +
                     "\nheight_m = " + std::to_string(diameter_m) + "\n[particles]\ncount = " + std::to_string(n) +
                     "\ndiameter_m = " + std::to_string(d) + "\ndensity_kg_m3 = " + std::to_string(gas_density_kg_m3) +
                     "\n[hard]\nen = 1\nmu = 0\n[hard_wall]\nen = 1\nmu = 0\n";
  text += free_host ? "[host]\nz0_m = 0\ndamping_N_s_m = 0\nmass_kg = " + std::to_string(host_mass_kg) +
                          "\nstiffness_N_m = " + std::to_string(host_stiffness_N_m) + "\n"
                    : "[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = 1\n";
  Scenario scenario = parse_scenario(text, "bench", "pdamp_bench");
  if (!free_host) scenario.excitation.amplitude_m = 0.0;  // fixed walls: a prescribed host that stays put
  return scenario;
}

}  // namespace pdamp::bench
