#include "pdamp/sim/initial_bed.hpp"

#include <chrono>
#include <set>
#include <sstream>

#include "pdamp/model/host.hpp"
#include "pdamp/model/placement.hpp"
#include "pdamp/soft/settling.hpp"
#include "pdamp/soft/time_step.hpp"

namespace pdamp {

std::string settle_key(const Scenario& scenario) {
  static const std::set<std::string> sections{"cavity", "gravity", "particles", "soft", "soft_wall"};
  std::istringstream canonical(scenario.canonical_text);
  std::ostringstream key;
  std::string section;
  for (std::string line; std::getline(canonical, line);) {
    if (line.starts_with('[')) section = line.substr(1, line.find(']') - 1);
    if (sections.contains(section) && !line.empty()) key << line << "\n";
  }
  key.precision(17);
  key << "[settling]\nhost_z_m = " << HostModel(scenario).initial_state().z_m
      << "\ndt_s = " << soft::choose_time_step_s(scenario) << "\nrule = mean kinetic energy below "
      << soft::settled_energy_fraction << " m g d, checked every " << soft::settling_check_interval_s << " s\n";
  return key.str();
}

InitialBed prepare_initial_bed(const Scenario& scenario, RunStore& store, const std::atomic<bool>* stop,
                               const std::function<void(double, double)>& progress) {
  const double host_z = HostModel(scenario).initial_state().z_m;
  if (scenario.particles.count == 0) return {Particles(0), std::nullopt, false, 0.0};
  const std::string key = settle_key(scenario);
  if (auto stored = store.find_initial_state(key)) {
    return {std::move(stored->particles), stored->state_id, true, stored->settle_time_s};
  }
  const auto wall_start = std::chrono::steady_clock::now();
  const soft::SettledBed bed =
      soft::settle_bed(scenario, place_particles(scenario.particles, scenario.cavity, host_z), stop, progress);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const SavedInitialState saved =
      store.save_initial_state(key, bed.particles, bed.settle_time_s, bed.kinetic_J, wall_s);
  // Another process that settled the same bed meanwhile stored it first: the same bits,
  // which this run reuses as if it had found them.
  return {bed.particles, saved.state_id, !saved.stored, bed.settle_time_s};
}

Particles moved_with_host(Particles spheres, const HostState& shift) {
  for (Eigen::Index i = 0; i < spheres.size(); ++i) {
    spheres.position_m(2, i) += shift.z_m;
    spheres.velocity_m_s(2, i) += shift.v_m_s;
  }
  return spheres;
}

}  // namespace pdamp
