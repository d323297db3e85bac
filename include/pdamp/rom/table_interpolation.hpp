#pragma once
/// Interpolation of the damper table over (A, f) (docs/rom.md, "Interpolation").
///
/// Between two frequency columns f_j < f < f_j+1 the table is interpolated at constant
/// Γ = A ω² / g: the query amplitude A maps to A_c = A (f / f_c)² in column c, each column is
/// interpolated linearly in log A_c between its nodes, and the two columns are blended linearly
/// in f. In a weightless table (g = 0) the columns are read at A itself; in a table of Γ rows
/// every column is read at the query's Γ = A (2πf)² / g. Every interpolated
/// value is a convex combination of at most four nodes, so it never leaves their range, and it
/// is exact on the nodes. A query outside the characterised grid is never extrapolated.

#include <cstddef>
#include <optional>
#include <vector>

#include "pdamp/rom/damper_table.hpp"

namespace pdamp::rom {

/// The table along the amplitude axis at one frequency: exactly piecewise linear in s = ln A
/// between `log_amplitude` knots (the nodes of the columns used, mapped to this frequency).
struct AmplitudeProfile {
  double frequency_hz = 0.0;
  std::vector<double> log_amplitude;    ///< knots s_k = ln A_k (A in m), increasing; empty if nothing is covered
  std::vector<DamperValues> values;     ///< at each knot
  std::vector<bool> segment_unsettled;  ///< per segment [s_k, s_k+1]: an unsettled node has weight in it

  bool covers_anything() const { return log_amplitude.size() >= 2; }
  double lowest_amplitude_m() const;
  double highest_amplitude_m() const;
  std::size_t segment_count() const { return log_amplitude.empty() ? 0 : log_amplitude.size() - 1; }
  /// Values at s inside segment k, linear between its knots.
  DamperValues in_segment(std::size_t k, double s) const;
};

class TableInterpolator {
 public:
  /// Validates the table (InputError, see validate_damper_table).
  explicit TableInterpolator(DamperTable table, const std::string& where = "damper table");

  const DamperTable& table() const { return table_; }
  double lowest_frequency_hz() const { return table_.frequencies_hz.front(); }
  double highest_frequency_hz() const { return table_.frequencies_hz.back(); }

  /// The profile at frequency f, which must lie within the table's frequencies.
  AmplitudeProfile profile(double frequency_hz) const;

  /// The interpolated values at (A, f); empty outside the characterised grid. `unsettled`,
  /// if given, is set when an unsettled node has weight in the result.
  std::optional<DamperValues> at(double amplitude_m, double frequency_hz, bool* unsettled = nullptr) const;

 private:
  struct ColumnWeight {
    std::size_t column;
    double weight;
  };
  /// The one or two frequency columns that f blends, with their weights (summing to 1).
  std::vector<ColumnWeight> columns_at(double frequency_hz) const;
  /// ln of the factor that maps an amplitude at `frequency_hz` to column c's row at the same Γ.
  double log_shift(std::size_t column, double frequency_hz) const;
  /// Adds weight × column c's value at row ln r = s into `sum`; false if s is outside the column.
  bool add_column(std::size_t column, double s, double weight, DamperValues& sum, bool& unsettled) const;

  DamperTable table_;
  std::vector<double> log_rows_;  ///< ln of the rows
};

}  // namespace pdamp::rom
