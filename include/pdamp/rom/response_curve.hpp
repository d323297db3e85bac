#pragma once
/// The predicted response over a frequency range: the harmonic balance at every frequency, its
/// solutions joined into branches, and the path a stepped-sine sweep up or down would follow
/// (docs/rom.md, "Branches and sweeps").

#include <string>
#include <vector>

#include "pdamp/rom/harmonic_balance.hpp"

namespace pdamp::rom {

enum class Spacing { linear, log };

struct FrequencyRange {
  double start_hz = 0.0;
  double stop_hz = 0.0;
  int count = 0;
  Spacing spacing = Spacing::linear;
};

/// Parses "START:STOP:COUNT" (Hz, Hz, points); InputError naming `option` otherwise.
FrequencyRange parse_frequency_range(const std::string& text, Spacing spacing, const std::string& option);

/// The frequencies, start and stop exactly included. InputError unless 0 < start < stop (finite)
/// and 2 <= count <= 100000.
std::vector<double> frequencies_of(const FrequencyRange& range);

/// A stepped sine's change of branch between two consecutive frequencies.
struct Jump {
  double from_frequency_hz, to_frequency_hz;
  double from_amplitude_m, to_amplitude_m;
  int from_branch, to_branch;
};

struct ResponseCurve {
  std::vector<FrequencyResponse> points;  ///< one per frequency, in the range's order
  std::vector<Jump> jumps_up, jumps_down;
};

/// The response at every frequency. InputError (before any work) if a frequency lies outside
/// the table's frequencies or the host is invalid; a frequency whose response lies outside the
/// characterised amplitudes is flagged, not an error (see covers_something).
ResponseCurve predict_response(const TableInterpolator& table, const HostSdof& host, const Excitation& excitation,
                               const std::vector<double>& frequencies_hz);

/// True if at least one frequency has a solution inside the characterised amplitudes.
bool covers_something(const ResponseCurve& curve);

/// Why nothing is covered, for the error message: where the response lies instead.
std::string coverage_summary(const ResponseCurve& curve);

}  // namespace pdamp::rom
