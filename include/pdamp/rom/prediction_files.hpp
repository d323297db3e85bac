#pragma once
/// The predicted response as rows (one per solution, and one per side where a solution lies
/// outside the characterised amplitudes), written as CSV or JSON (columns and units:
/// docs/rom.md, "Prediction output").

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "pdamp/rom/response_curve.hpp"

namespace pdamp::rom {

/// What was predicted, for the files' headers.
struct PredictionSetup {
  std::string table_name;  ///< the table's file (or, later, its study)
  const DamperTable* table = nullptr;
  HostSdof host;
  Excitation excitation;
  FrequencyRange range;
};

struct PredictionRow {
  double frequency_hz = 0.0;
  std::optional<Solution> solution;  ///< empty on a row that only carries flags
  double amplitude_ratio = 0.0;      ///< |X| / (F0/K) (force) or |X| / Y (base)
  double phase_deg = 0.0;            ///< arg(X / F0) or arg(X / Y), in (−180, 180]
  std::optional<double> gamma;       ///< A ω² / g of the host's motion (empty if the table is weightless)
  double loss_factor = 0.0;          ///< ω (C + c_eq) / K
  double loss_factor_bed = 0.0;      ///< ω c_eq / K
  std::vector<std::string> flags;
};

std::vector<PredictionRow> prediction_rows(const PredictionSetup& setup, const ResponseCurve& curve);

std::string prediction_csv(const PredictionSetup& setup, const ResponseCurve& curve);
std::string prediction_json(const PredictionSetup& setup, const ResponseCurve& curve);

/// "force F0 = 0.05 N", "base motion Y = 1e-04 m": the excitation in the files' headers.
std::string excitation_text(const Excitation& excitation);
/// "201 frequencies 14 to 22 Hz (linear)".
std::string range_text(const FrequencyRange& range);
/// The row's flags separated by ';', as in the CSV.
std::string flags_text(const PredictionRow& row);

/// The prediction's text in the format `file`'s extension names (.csv, .json); InputError otherwise.
std::string prediction_text(const PredictionSetup& setup, const ResponseCurve& curve,
                            const std::filesystem::path& file);

}  // namespace pdamp::rom
