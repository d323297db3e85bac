#include "pdamp/rom/prediction_files.hpp"

#include <cmath>
#include <functional>
#include <numbers>
#include <sstream>
#include <type_traits>
#include <variant>

#include "pdamp/rom/table_files.hpp"
#include "text_format.hpp"

namespace pdamp::rom {
namespace {

constexpr const char* prediction_format = "pdamp rom prediction";
constexpr int prediction_version = 1;

using Cell = std::variant<std::monostate, double, int, bool, std::string>;

struct Column {
  const char* name;
  std::function<Cell(const PredictionRow&)> value;
};

/// A solution's value, empty on a flag row.
template <class Get>
std::function<Cell(const PredictionRow&)> of_solution(Get get) {
  return [get](const PredictionRow& r) -> Cell {
    if (!r.solution) return std::monostate{};
    return get(r);
  };
}

const std::vector<Column>& columns() {
  static const std::vector<Column> all = {
      {"frequency_hz", [](const PredictionRow& r) -> Cell { return r.frequency_hz; }},
      {"branch", of_solution([](const PredictionRow& r) -> Cell { return r.solution->branch; })},
      {"stability", of_solution([](const PredictionRow& r) -> Cell { return to_string(r.solution->stability); })},
      {"amplitude_m", of_solution([](const PredictionRow& r) -> Cell { return r.solution->amplitude_m; })},
      {"response_ratio", of_solution([](const PredictionRow& r) -> Cell { return r.amplitude_ratio; })},
      {"phase_deg", of_solution([](const PredictionRow& r) -> Cell { return r.phase_deg; })},
      {"gamma", of_solution([](const PredictionRow& r) -> Cell {
         if (!r.gamma) return std::monostate{};
         return *r.gamma;
       })},
      {"m_app_kg", of_solution([](const PredictionRow& r) -> Cell { return r.solution->damper.m_app_kg; })},
      {"c_eq_N_s_m", of_solution([](const PredictionRow& r) -> Cell { return r.solution->damper.c_eq_N_s_m; })},
      {"m_app_spread_kg",
       of_solution([](const PredictionRow& r) -> Cell { return r.solution->damper.m_app_spread_kg; })},
      {"c_eq_spread_N_s_m",
       of_solution([](const PredictionRow& r) -> Cell { return r.solution->damper.c_eq_spread_N_s_m; })},
      {"loss_factor", of_solution([](const PredictionRow& r) -> Cell { return r.loss_factor; })},
      {"loss_factor_bed", of_solution([](const PredictionRow& r) -> Cell { return r.loss_factor_bed; })},
      {"sweep_up", of_solution([](const PredictionRow& r) -> Cell { return r.solution->on_sweep_up; })},
      {"sweep_down", of_solution([](const PredictionRow& r) -> Cell { return r.solution->on_sweep_down; })},
  };
  return all;
}

/// A cell as CSV (empty if missing, booleans 1/0) or as JSON (null, true/false, quoted text).
std::string cell_text(const Cell& cell, bool json) {
  return std::visit(
      [json](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, std::monostate>) {
          return json ? "null" : "";
        } else if constexpr (std::is_same_v<T, double>) {
          return json ? text::json_number(x) : text::number(x);
        } else if constexpr (std::is_same_v<T, int>) {
          return std::to_string(x);
        } else if constexpr (std::is_same_v<T, bool>) {
          return json ? (x ? "true" : "false") : (x ? "1" : "0");
        } else {
          return json ? text::json_string(x) : x;
        }
      },
      cell);
}

std::vector<std::string> solution_flags(const Solution& s) {
  std::vector<std::string> flags;
  if (s.unsettled) flags.emplace_back("unsettled");
  if (s.saddle) flags.emplace_back("saddle");
  if (s.slow_flow_growth) flags.emplace_back("slow_flow_growth");
  if (s.stability == Stability::unknown) flags.emplace_back("effective_mass_nonpositive");
  return flags;
}

PredictionRow solution_row(const PredictionSetup& setup, double frequency_hz, const Solution& s) {
  PredictionRow row;
  row.frequency_hz = frequency_hz;
  row.solution = s;
  const double omega = 2 * std::numbers::pi * frequency_hz;
  row.amplitude_ratio = std::abs(s.ratio);
  row.phase_deg = std::arg(s.ratio) * 180 / std::numbers::pi;
  if (setup.table->gravity_m_s2 > 0) row.gamma = s.amplitude_m * omega * omega / setup.table->gravity_m_s2;
  row.loss_factor = omega * (setup.host.damping_N_s_m + s.damper.c_eq_N_s_m) / setup.host.stiffness_N_m;
  row.loss_factor_bed = omega * s.damper.c_eq_N_s_m / setup.host.stiffness_N_m;
  row.flags = solution_flags(s);
  return row;
}

PredictionRow flag_row(double frequency_hz, const char* flag) {
  PredictionRow row;
  row.frequency_hz = frequency_hz;
  row.flags = {flag};
  return row;
}

void json_jumps(std::ostream& out, const char* key, const std::vector<Jump>& jumps) {
  out << "    " << text::json_string(key) << ": [";
  for (std::size_t i = 0; i < jumps.size(); ++i) {
    const Jump& j = jumps[i];
    out << (i ? ",\n      " : "\n      ") << "{\"from_frequency_hz\": " << text::json_number(j.from_frequency_hz)
        << ", \"to_frequency_hz\": " << text::json_number(j.to_frequency_hz)
        << ", \"from_amplitude_m\": " << text::json_number(j.from_amplitude_m)
        << ", \"to_amplitude_m\": " << text::json_number(j.to_amplitude_m) << ", \"from_branch\": " << j.from_branch
        << ", \"to_branch\": " << j.to_branch << "}";
  }
  out << (jumps.empty() ? "]" : "\n    ]");
}

}  // namespace

std::string excitation_text(const Excitation& e) {
  return e.kind == ExcitationKind::force ? "force F0 = " + text::number(e.amplitude) + " N"
                                         : "base motion Y = " + text::number(e.amplitude) + " m";
}

std::string range_text(const FrequencyRange& r) {
  return std::to_string(r.count) + " frequencies " + text::number(r.start_hz) + " to " + text::number(r.stop_hz) +
         " Hz (" + (r.spacing == Spacing::linear ? "linear" : "log") + ")";
}

std::string flags_text(const PredictionRow& row) {
  std::string out;
  for (const auto& flag : row.flags) out += (out.empty() ? "" : ";") + flag;
  return out;
}

std::vector<PredictionRow> prediction_rows(const PredictionSetup& setup, const ResponseCurve& curve) {
  std::vector<PredictionRow> rows;
  for (const FrequencyResponse& p : curve.points) {
    if (p.not_covered) rows.push_back(flag_row(p.frequency_hz, "not_covered"));
    if (p.solution_below) rows.push_back(flag_row(p.frequency_hz, "solution_below_grid"));
    for (const Solution& s : p.solutions) rows.push_back(solution_row(setup, p.frequency_hz, s));
    if (p.solution_above) rows.push_back(flag_row(p.frequency_hz, "solution_above_grid"));
  }
  return rows;
}

std::string prediction_csv(const PredictionSetup& setup, const ResponseCurve& curve) {
  std::ostringstream out;
  const HostSdof& h = setup.host;
  out << "# format = " << prediction_format << " " << prediction_version << "\n"
      << "# table = " << setup.table_name << " (source: " << setup.table->source << ")\n"
      << "# host = M " << text::number(h.mass_kg) << " kg, K " << text::number(h.stiffness_N_m) << " N/m, C "
      << text::number(h.damping_N_s_m) << " N s/m\n"
      << "# excitation = " << excitation_text(setup.excitation) << "\n"
      << "# frequencies = " << range_text(setup.range) << "\n"
      << "# response_ratio = |X|/(F0/K) (force) or |X|/Y (base); phase_deg = arg(X/F0) or arg(X/Y);\n"
      << "# loss_factor = omega (C + c_eq) / K, loss_factor_bed = omega c_eq / K; flags separated by ';'\n";
  for (const Column& c : columns()) out << c.name << ",";
  out << "flags\n";
  for (const PredictionRow& row : prediction_rows(setup, curve)) {
    for (const Column& c : columns()) out << cell_text(c.value(row), false) << ",";
    out << flags_text(row) << "\n";
  }
  return out.str();
}

std::string prediction_json(const PredictionSetup& setup, const ResponseCurve& curve) {
  std::ostringstream out;
  const HostSdof& h = setup.host;
  const bool force = setup.excitation.kind == ExcitationKind::force;
  out << "{\n  \"format\": " << text::json_string(prediction_format)
      << ",\n  \"format_version\": " << prediction_version
      << ",\n  \"table\": {\"file\": " << text::json_string(setup.table_name)
      << ", \"source\": " << text::json_string(setup.table->source)
      << ", \"bed_mass_kg\": " << text::json_number(setup.table->bed_mass_kg)
      << "},\n  \"host\": {\"mass_kg\": " << text::json_number(h.mass_kg)
      << ", \"stiffness_N_m\": " << text::json_number(h.stiffness_N_m)
      << ", \"damping_N_s_m\": " << text::json_number(h.damping_N_s_m)
      << "},\n  \"excitation\": {\"kind\": " << (force ? "\"force\", \"amplitude_N\": " : "\"base\", \"amplitude_m\": ")
      << text::json_number(setup.excitation.amplitude)
      << "},\n  \"frequencies\": {\"start_hz\": " << text::json_number(setup.range.start_hz)
      << ", \"stop_hz\": " << text::json_number(setup.range.stop_hz) << ", \"count\": " << setup.range.count
      << ", \"spacing\": \"" << (setup.range.spacing == Spacing::linear ? "linear" : "log") << "\"},\n  \"points\": [";
  const auto rows = prediction_rows(setup, curve);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    out << (i ? ",\n    {" : "\n    {");
    for (const Column& c : columns())
      out << text::json_string(c.name) << ": " << cell_text(c.value(rows[i]), true) << ", ";
    out << "\"flags\": [";
    for (std::size_t f = 0; f < rows[i].flags.size(); ++f)
      out << (f ? ", " : "") << text::json_string(rows[i].flags[f]);
    out << "]}";
  }
  out << "\n  ],\n  \"jumps\": {\n";
  json_jumps(out, "sweep_up", curve.jumps_up);
  out << ",\n";
  json_jumps(out, "sweep_down", curve.jumps_down);
  out << "\n  }\n}\n";
  return out.str();
}

std::string prediction_text(const PredictionSetup& setup, const ResponseCurve& curve,
                            const std::filesystem::path& file) {
  return file_format(file, "prediction output") == FileFormat::csv ? prediction_csv(setup, curve)
                                                                   : prediction_json(setup, curve);
}

}  // namespace pdamp::rom
