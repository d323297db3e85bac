#pragma once
/// The damper table: what a characterisation of the isolated damper hands to the reduced-order
/// model and to structural codes (docs/rom.md, "The damper table").
///
/// The container is driven with z = A sin(2πft); the first harmonic of the particles' force on
/// it, F_p,1 = −m_app z̈₁ − c_eq ż₁, gives the apparent mass m_app and the equivalent damping
/// c_eq at each (A, f) of a rectangular grid.

#include <cstddef>
#include <string>
#include <vector>

namespace pdamp::rom {

/// The damper at one (A, f): the first harmonic of the particles' force on the container.
struct DamperValues {
  double m_app_kg = 0.0;    ///< apparent mass: force in phase with −z̈, over ω² A
  double c_eq_N_s_m = 0.0;  ///< equivalent damping: force in phase with −ż, over ω A
  /// Steady-state spread: the standard deviation of the per-cycle values over the cycles that
  /// were averaged (same units as the values).
  double m_app_spread_kg = 0.0;
  double c_eq_spread_N_s_m = 0.0;

  bool operator==(const DamperValues&) const = default;
};

/// One characterised point of the grid.
struct TablePoint : DamperValues {
  /// The characterisation reached a steady state there. An unsettled point is still
  /// interpolated through, but every prediction that uses it carries the flag `unsettled`.
  bool settled = true;

  bool operator==(const TablePoint&) const = default;
};

struct DamperTable {
  /// Where the table came from (free text: a study, a file, "synthetic ...").
  std::string source;
  double bed_mass_kg = 0.0;            ///< m_p, the mass of the particles (≥ 0)
  double gravity_m_s2 = 9.81;          ///< |g| during the characterisation (0: weightless), for Γ = A(2πf)²/g
  std::vector<double> amplitudes_m;    ///< container displacement amplitudes A, increasing, > 0
  std::vector<double> frequencies_hz;  ///< frequencies f, increasing, > 0
  /// points[j * amplitudes_m.size() + i] is the point at amplitudes_m[i], frequencies_hz[j].
  std::vector<TablePoint> points;

  const TablePoint& at(std::size_t amplitude_index, std::size_t frequency_index) const {
    return points[frequency_index * amplitudes_m.size() + amplitude_index];
  }
  TablePoint& at(std::size_t amplitude_index, std::size_t frequency_index) {
    return points[frequency_index * amplitudes_m.size() + amplitude_index];
  }
  /// Γ = A (2πf)² / g at a grid point (infinite when g = 0).
  double gamma(std::size_t amplitude_index, std::size_t frequency_index) const;

  /// Every field and value equal (a file read back to the table it was written from).
  bool operator==(const DamperTable&) const = default;
};

/// Throws InputError naming the first problem, prefixed by `where` (a file name): fewer than
/// two values on an axis, axes not strictly increasing or not positive, a point count that is
/// not amplitudes × frequencies, non-finite values, negative spreads, a negative bed mass or
/// gravity.
void validate_damper_table(const DamperTable& table, const std::string& where);

}  // namespace pdamp::rom
