#include "pdamp/sim/observation_grid.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pdamp/model/host.hpp"

namespace pdamp {

double observation_interval_s(const Scenario& scenario) {
  double fastest = scenario.excitation.angular_frequency_rad_s();
  if (!scenario.host_has_infinite_mass()) {
    fastest = std::max(fastest, HostModel(scenario).natural_angular_frequency_rad_s());
  }
  return std::min(scenario.run.sample_interval_s, 2.0 * std::numbers::pi / fastest / 256.0);
}

ObservationGrid observation_grid(const Scenario& scenario) {
  const double sample_interval = scenario.run.sample_interval_s;
  const auto steps = static_cast<long>(std::ceil(sample_interval / observation_interval_s(scenario) - 1e-9));
  return {steps, sample_interval / static_cast<double>(steps), sample_interval};
}

}  // namespace pdamp
