// A program outside pdamp's tree, built against an installed pdamp (find_package): loads
// a scenario file, runs it for 0.01 s with the hard engine from its placement, and checks
// that the energy ledger closes. Exit 0 if it does, 1 if not, 2 on a usage error.
#include <cstdio>
#include <exception>

#include "pdamp/model/placement.hpp"
#include "pdamp/model/scenario_loader.hpp"
#include "pdamp/sim/engine_factory.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: pdamp_consumer SCENARIO.ini\n");
    return 2;
  }
  try {
    const pdamp::Scenario scenario = pdamp::load_scenario(argv[1]);
    const pdamp::Particles placed = pdamp::place_particles(scenario.particles, scenario.cavity, scenario.host.z0_m);
    const auto engine = pdamp::make_engine(pdamp::prepare_engine(pdamp::Model::hard, scenario), scenario, placed);
    const double initial_J = engine->observe().energy.stored_J();
    engine->advance_to(0.01);
    const pdamp::Observation end = engine->observe();
    const double error = end.energy.balance_relative_error(initial_J);
    std::printf("%d spheres, t = %g s, %lld collisions, energy balance error %.3g\n", scenario.particles.count, end.t_s,
                static_cast<long long>(end.counters.collisions.value_or(0)), error);
    // The hard engine books every joule to round-off (docs/architecture.md, the contract).
    return end.t_s == 0.01 && end.counters.collisions.value_or(0) > 0 && error < 1e-9 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pdamp_consumer: %s\n", e.what());
    return 1;
  }
}
