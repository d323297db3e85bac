#pragma once
/// The damper table: what a characterisation of the isolated damper hands to the reduced-order
/// model and to structural codes (docs/rom.md, "The damper table").
///
/// The container is driven with z = A sin(2πft); the first harmonic of the particles' force on
/// it, F_p,1 = −m_app z̈₁ − c_eq ż₁, gives the apparent mass m_app and the equivalent damping
/// c_eq at each point of a rectangular grid: amplitude × frequency, or Γ × frequency (each
/// column then at the amplitudes A = Γ g / (2πf)², as a `gammas` characterisation runs).

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

/// What the rows of the grid are.
enum class RowAxis {
  amplitude,  ///< container displacement amplitudes A (m), the same in every column
  gamma,      ///< peak accelerations over g, Γ = A (2πf)² / g: A differs from column to column
};

struct DamperTable {
  /// Where the table came from (free text: a study, a file, "synthetic ...").
  std::string source;
  double bed_mass_kg = 0.0;    ///< m_p, the mass of the particles (≥ 0)
  double gravity_m_s2 = 9.81;  ///< |g| during the characterisation (0: weightless), for Γ = A(2πf)²/g
  RowAxis row_axis = RowAxis::amplitude;
  /// The rows: amplitudes A in m, or Γ (dimensionless, needs g > 0); increasing, > 0.
  std::vector<double> rows;
  std::vector<double> frequencies_hz;  ///< frequencies f, increasing, > 0
  /// points[j * rows.size() + i] is the point at rows[i], frequencies_hz[j].
  std::vector<TablePoint> points;

  const TablePoint& at(std::size_t row_index, std::size_t frequency_index) const {
    return points[frequency_index * rows.size() + row_index];
  }
  TablePoint& at(std::size_t row_index, std::size_t frequency_index) {
    return points[frequency_index * rows.size() + row_index];
  }
  /// The container amplitude A (m) at a grid point.
  double amplitude_m(std::size_t row_index, std::size_t frequency_index) const;
  /// Γ = A (2πf)² / g at a grid point (infinite when g = 0).
  double gamma(std::size_t row_index, std::size_t frequency_index) const;

  /// Every field and value equal (a file read back to the table it was written from).
  bool operator==(const DamperTable&) const = default;
};

/// "A = 0.001 m, f = 20 Hz" or "Gamma = 2, f = 20 Hz": a grid point for messages.
std::string describe_point(const DamperTable& table, std::size_t row_index, std::size_t frequency_index);

/// Throws InputError naming the first problem, prefixed by `where` (a file name): fewer than
/// two values on an axis, axes not strictly increasing or not positive, a point count that is
/// not rows × frequencies, non-finite values, negative spreads, a negative bed mass or
/// gravity, Γ rows in a weightless table.
void validate_damper_table(const DamperTable& table, const std::string& where);

}  // namespace pdamp::rom
