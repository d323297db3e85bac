#include "pdamp/model/restitution.hpp"

#include <algorithm>
#include <cmath>

namespace pdamp {
namespace {

double interpolate(const std::vector<double>& speeds, const std::vector<double>& values, double speed) {
  if (speed <= speeds.front()) return values.front();
  if (speed >= speeds.back()) return values.back();
  const auto upper = std::upper_bound(speeds.begin(), speeds.end(), speed);
  const auto k = static_cast<std::size_t>(upper - speeds.begin());
  const double f = std::log(speed / speeds[k - 1]) / std::log(speeds[k] / speeds[k - 1]);
  return values[k - 1] + f * (values[k] - values[k - 1]);
}

}  // namespace

double RestitutionCurve::en_at(double speed_m_s) const { return interpolate(impact_speed_m_s, en, speed_m_s); }

double RestitutionCurve::beta0_at(double speed_m_s) const { return interpolate(impact_speed_m_s, beta0, speed_m_s); }

}  // namespace pdamp
