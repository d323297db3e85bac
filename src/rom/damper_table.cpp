#include "pdamp/rom/damper_table.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pdamp/errors.hpp"
#include "text_format.hpp"

namespace pdamp::rom {
namespace {

using text::number;

void check_axis(const std::vector<double>& axis, const std::string& name, const std::string& plural,
                const std::string& unit, const std::string& where) {  // unit: " m", or "" for Γ
  if (axis.size() < 2) {
    throw InputError(where + ": " + std::to_string(axis.size()) + " " + (axis.size() == 1 ? name : plural) +
                     ": the table needs at least two on each axis to interpolate");
  }
  for (std::size_t i = 0; i < axis.size(); ++i) {
    if (!std::isfinite(axis[i]) || axis[i] <= 0) {
      throw InputError(where + ": " + name + " " + number(axis[i]) + unit + ": must be a finite number > 0");
    }
    if (i > 0 && axis[i] <= axis[i - 1]) {
      throw InputError(where + ": " + plural + " " + number(axis[i - 1]) + " and " + number(axis[i]) + unit +
                       ": the axis must be strictly increasing (each value once)");
    }
  }
}

void check_point(const DamperTable& table, std::size_t i, std::size_t j, const std::string& where) {
  const TablePoint& p = table.at(i, j);
  const std::string at = where + ": at " + describe_point(table, i, j) + ": ";
  const struct {
    const char* name;
    double value;
    bool spread;
  } fields[] = {{"m_app_kg", p.m_app_kg, false},
                {"c_eq_N_s_m", p.c_eq_N_s_m, false},
                {"m_app_spread_kg", p.m_app_spread_kg, true},
                {"c_eq_spread_N_s_m", p.c_eq_spread_N_s_m, true}};
  for (const auto& f : fields) {
    if (!std::isfinite(f.value)) throw InputError(at + f.name + " = " + number(f.value) + ": must be a finite number");
    if (f.spread && f.value < 0) {
      throw InputError(at + f.name + " = " + number(f.value) + ": a spread (standard deviation) must be >= 0");
    }
  }
}

}  // namespace

std::string describe_point(const DamperTable& table, std::size_t i, std::size_t j) {
  return (table.row_axis == RowAxis::gamma ? "Gamma = " + number(table.rows[i])
                                           : "A = " + number(table.rows[i]) + " m") +
         ", f = " + number(table.frequencies_hz[j]) + " Hz";
}

double DamperTable::amplitude_m(std::size_t row_index, std::size_t frequency_index) const {
  if (row_axis == RowAxis::amplitude) return rows[row_index];
  const double omega = 2 * std::numbers::pi * frequencies_hz[frequency_index];
  return rows[row_index] * gravity_m_s2 / (omega * omega);
}

double DamperTable::gamma(std::size_t row_index, std::size_t frequency_index) const {
  if (row_axis == RowAxis::gamma) return rows[row_index];
  const double omega = 2 * std::numbers::pi * frequencies_hz[frequency_index];
  return rows[row_index] * omega * omega / gravity_m_s2;
}

void validate_damper_table(const DamperTable& table, const std::string& where) {
  const auto control = std::find_if(table.source.begin(), table.source.end(),
                                    [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; });
  if (control != table.source.end()) {
    throw InputError(where + ": the source description must be one line of text, without control characters (" +
                     std::to_string(static_cast<unsigned char>(*control)) + " at character " +
                     std::to_string(control - table.source.begin() + 1) + ")");
  }
  if (!std::isfinite(table.bed_mass_kg) || table.bed_mass_kg < 0) {
    throw InputError(where + ": bed_mass_kg = " + number(table.bed_mass_kg) + ": must be a finite number >= 0");
  }
  if (!std::isfinite(table.gravity_m_s2) || table.gravity_m_s2 < 0) {
    throw InputError(where + ": gravity_m_s2 = " + number(table.gravity_m_s2) +
                     ": must be a finite number >= 0 (0 for a weightless characterisation)");
  }
  const bool gammas = table.row_axis == RowAxis::gamma;
  if (gammas && !(table.gravity_m_s2 > 0)) {
    throw InputError(where + ": the rows are gammas but gravity_m_s2 = " + number(table.gravity_m_s2) +
                     ": a weightless table has no Gamma, its rows are amplitudes (m)");
  }
  check_axis(table.rows, gammas ? "gamma" : "amplitude", gammas ? "gammas" : "amplitudes", gammas ? "" : " m", where);
  check_axis(table.frequencies_hz, "frequency", "frequencies", " Hz", where);
  const std::size_t expected = table.rows.size() * table.frequencies_hz.size();
  if (table.points.size() != expected) {
    throw InputError(where + ": " + std::to_string(table.points.size()) + " points for " +
                     std::to_string(table.rows.size()) + (gammas ? " gammas x " : " amplitudes x ") +
                     std::to_string(table.frequencies_hz.size()) + " frequencies: the grid must be rectangular (" +
                     std::to_string(expected) + " points)");
  }
  for (std::size_t j = 0; j < table.frequencies_hz.size(); ++j) {
    for (std::size_t i = 0; i < table.rows.size(); ++i) check_point(table, i, j, where);
  }
}

}  // namespace pdamp::rom
