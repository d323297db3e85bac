#include "pdamp/rom/table_interpolation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pdamp::rom {
namespace {

/// Knots mapped from one column to another carry rounding: points this close in ln A are one.
constexpr double same_log_amplitude = 1e-12;

DamperValues lerp(const DamperValues& a, const DamperValues& b, double u) {
  return {a.m_app_kg + u * (b.m_app_kg - a.m_app_kg), a.c_eq_N_s_m + u * (b.c_eq_N_s_m - a.c_eq_N_s_m),
          a.m_app_spread_kg + u * (b.m_app_spread_kg - a.m_app_spread_kg),
          a.c_eq_spread_N_s_m + u * (b.c_eq_spread_N_s_m - a.c_eq_spread_N_s_m)};
}

void add_scaled(DamperValues& sum, const DamperValues& v, double weight) {
  sum.m_app_kg += weight * v.m_app_kg;
  sum.c_eq_N_s_m += weight * v.c_eq_N_s_m;
  sum.m_app_spread_kg += weight * v.m_app_spread_kg;
  sum.c_eq_spread_N_s_m += weight * v.c_eq_spread_N_s_m;
}

}  // namespace

double AmplitudeProfile::lowest_amplitude_m() const { return std::exp(log_amplitude.front()); }
double AmplitudeProfile::highest_amplitude_m() const { return std::exp(log_amplitude.back()); }

DamperValues AmplitudeProfile::in_segment(std::size_t k, double s) const {
  const double u = (s - log_amplitude[k]) / (log_amplitude[k + 1] - log_amplitude[k]);
  return lerp(values[k], values[k + 1], u);
}

TableInterpolator::TableInterpolator(DamperTable table, const std::string& where) : table_(std::move(table)) {
  validate_damper_table(table_, where);
  for (const double row : table_.rows) log_rows_.push_back(std::log(row));
}

std::vector<TableInterpolator::ColumnWeight> TableInterpolator::columns_at(double frequency_hz) const {
  const auto& f = table_.frequencies_hz;
  if (!(frequency_hz >= f.front() && frequency_hz <= f.back())) return {};
  const std::size_t j = static_cast<std::size_t>(std::lower_bound(f.begin(), f.end(), frequency_hz) - f.begin());
  if (f[j] == frequency_hz) return {{j, 1.0}};
  const double t = (frequency_hz - f[j - 1]) / (f[j] - f[j - 1]);
  return {{j - 1, 1.0 - t}, {j, t}};
}

double TableInterpolator::log_shift(std::size_t column, double frequency_hz) const {
  if (table_.row_axis == RowAxis::gamma) {  // the row of every column: Γ = A ω² / g
    const double omega = 2 * std::numbers::pi * frequency_hz;
    return std::log(omega * omega / table_.gravity_m_s2);
  }
  // Same Γ in column c: A_c = A (f / f_c)². Weightless (g = 0): A_c = A.
  const double exponent = table_.gravity_m_s2 > 0 ? 2.0 : 0.0;
  return exponent * std::log(frequency_hz / table_.frequencies_hz[column]);
}

bool TableInterpolator::add_column(std::size_t column, double s, double weight, DamperValues& sum,
                                   bool& unsettled) const {
  const auto& la = log_rows_;
  if (s < la.front() - same_log_amplitude || s > la.back() + same_log_amplitude) return false;
  s = std::clamp(s, la.front(), la.back());
  std::size_t i = static_cast<std::size_t>(std::lower_bound(la.begin(), la.end(), s) - la.begin());
  // A node is met exactly, also through the rounding of a Γ mapped from A and f.
  const bool at_node = la[i] - s <= same_log_amplitude || s - la[i - 1] <= same_log_amplitude;
  if (at_node && la[i] - s > same_log_amplitude) --i;
  const TablePoint& upper = table_.at(i, column);
  if (at_node) {
    add_scaled(sum, upper, weight);
    unsettled = unsettled || !upper.settled;
    return true;
  }
  const TablePoint& lower = table_.at(i - 1, column);
  const double u = (s - la[i - 1]) / (la[i] - la[i - 1]);
  add_scaled(sum, lerp(lower, upper, u), weight);
  unsettled = unsettled || !lower.settled || !upper.settled;
  return true;
}

std::optional<DamperValues> TableInterpolator::at(double amplitude_m, double frequency_hz, bool* unsettled) const {
  const auto columns = columns_at(frequency_hz);
  if (columns.empty() || !(amplitude_m > 0)) return std::nullopt;
  const double s = std::log(amplitude_m);
  DamperValues sum;
  bool any_unsettled = false;
  for (const auto& [column, weight] : columns) {
    if (!add_column(column, s + log_shift(column, frequency_hz), weight, sum, any_unsettled)) return std::nullopt;
  }
  if (unsettled) *unsettled = any_unsettled;
  return sum;
}

AmplitudeProfile TableInterpolator::profile(double frequency_hz) const {
  AmplitudeProfile profile;
  profile.frequency_hz = frequency_hz;
  const auto columns = columns_at(frequency_hz);
  if (columns.empty()) return profile;

  // The amplitudes every column used covers, and the columns' nodes inside them.
  double low = -HUGE_VAL, high = HUGE_VAL;
  for (const auto& c : columns) {
    const double shift = log_shift(c.column, frequency_hz);
    low = std::max(low, log_rows_.front() - shift);
    high = std::min(high, log_rows_.back() - shift);
  }
  if (!(high - low > same_log_amplitude)) return profile;
  std::vector<double> knots{low, high};
  for (const auto& c : columns) {
    const double shift = log_shift(c.column, frequency_hz);
    for (const double s : log_rows_) {
      if (s - shift > low && s - shift < high) knots.push_back(s - shift);
    }
  }
  std::sort(knots.begin(), knots.end());
  for (const double s : knots) {
    if (profile.log_amplitude.empty() || s - profile.log_amplitude.back() > same_log_amplitude) {
      profile.log_amplitude.push_back(s);
    }
  }
  profile.log_amplitude.back() = high;

  // Values at the knots; a segment's midpoint sees both nodes around it in each column.
  auto evaluate = [&](double s, bool& unsettled) {
    DamperValues sum;
    for (const auto& [column, weight] : columns) {
      add_column(column, s + log_shift(column, frequency_hz), weight, sum, unsettled);
    }
    return sum;
  };
  for (const double s : profile.log_amplitude) {
    bool ignored = false;
    profile.values.push_back(evaluate(s, ignored));
  }
  for (std::size_t k = 0; k + 1 < profile.log_amplitude.size(); ++k) {
    bool unsettled = false;
    evaluate(0.5 * (profile.log_amplitude[k] + profile.log_amplitude[k + 1]), unsettled);
    profile.segment_unsettled.push_back(unsettled);
  }
  return profile;
}

}  // namespace pdamp::rom
