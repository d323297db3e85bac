/// The damper table as CSV: '#' comment lines (four or five of them `# key = value`
/// metadata), a header row, then one row per grid point, frequency by frequency.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/rom/table_files.hpp"
#include "text_format.hpp"

namespace pdamp::rom {
namespace {

/// The columns in the order they are written. Of `amplitude_m` and `gamma` (A (2πf)² / g;
/// empty for a weightless table) the one that is not the table's rows is derived, optional
/// and checked on reading.
const std::vector<std::string> columns = {"amplitude_m",     "frequency_hz",      "gamma",  "m_app_kg", "c_eq_N_s_m",
                                          "m_app_spread_kg", "c_eq_spread_N_s_m", "settled"};
const std::vector<std::string> metadata_keys = {"format", "source", "bed_mass_kg", "gravity_m_s2"};
/// `rows = gamma` for a table of Γ rows; without it the rows are amplitudes.
const std::string rows_key = "rows";

/// A derived value written and the one recomputed from the rows, f and g may differ in the last digits.
constexpr double derived_tolerance = 1e-9;

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::istringstream in(line);
  for (std::string field; std::getline(in, field, ',');) fields.push_back(trim(field));
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

struct Row {
  std::optional<double> amplitude_m, gamma;
  double frequency_hz;
  TablePoint point;
  int line;
};

class CsvReader {
 public:
  CsvReader(const std::string& where) : where_(where) {}

  DamperTable read(const std::string& text) {
    std::istringstream in(text);
    int line_number = 0;
    for (std::string line; std::getline(in, line);) {
      ++line_number;
      line = trim(line);
      if (line.empty()) continue;
      if (line[0] == '#') {
        read_comment(line, line_number);
      } else if (header_.empty()) {
        read_header(line, line_number);
      } else {
        rows_.push_back(read_row(line, line_number));
      }
    }
    return assemble();
  }

 private:
  [[noreturn]] void fail(int line, const std::string& why) const {
    throw InputError(where_ + ":" + std::to_string(line) + ": " + why);
  }

  double parse_number(const std::string& field, const std::string& column, int line) const {
    double value = 0;
    const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
    if (field.empty() || ec != std::errc() || end != field.data() + field.size() || !std::isfinite(value)) {
      fail(line, column + " = '" + field + "': not a finite number");
    }
    return value;
  }

  void read_comment(const std::string& line, int line_number) {
    const auto equals = line.find('=');
    if (equals == std::string::npos) return;
    const std::string key = trim(line.substr(1, equals - 1));
    if (key != rows_key && std::find(metadata_keys.begin(), metadata_keys.end(), key) == metadata_keys.end()) return;
    if (metadata_.count(key)) fail(line_number, "'" + key + "' is given twice");
    if (key == rows_key && !header_.empty()) fail(line_number, "'# rows = ...' must come before the header row");
    metadata_[key] = {trim(line.substr(equals + 1)), line_number};
  }

  void read_header(const std::string& line, int line_number) {
    header_ = split(line);
    for (const auto& name : header_) {
      if (std::find(columns.begin(), columns.end(), name) == columns.end()) {
        fail(line_number, "unknown column '" + name + "' (the columns are those of docs/rom.md, \"Table files\")");
      }
      if (std::count(header_.begin(), header_.end(), name) > 1) fail(line_number, "column '" + name + "' twice");
    }
    const std::string derived = rows_are_gammas() ? "amplitude_m" : "gamma";
    for (const auto& name : columns) {
      if (name != derived && std::find(header_.begin(), header_.end(), name) == header_.end()) {
        fail(line_number, "column '" + name + "' is missing" +
                              (name == "gamma" ? " (the table's rows are gammas: '# rows = gamma')" : ""));
      }
    }
  }

  Row read_row(const std::string& line, int line_number) const {
    const auto fields = split(line);
    if (fields.size() != header_.size()) {
      fail(line_number, std::to_string(fields.size()) + " fields for " + std::to_string(header_.size()) + " columns");
    }
    Row row{};
    row.line = line_number;
    for (std::size_t c = 0; c < fields.size(); ++c) {
      const std::string& name = header_[c];
      if (name == "settled") {
        if (fields[c] != "0" && fields[c] != "1") fail(line_number, "settled = '" + fields[c] + "': must be 1 or 0");
        row.point.settled = fields[c] == "1";
      } else if (name == "gamma") {
        if (!fields[c].empty()) row.gamma = parse_number(fields[c], name, line_number);
      } else if (name == "amplitude_m") {
        if (!fields[c].empty() || !rows_are_gammas()) row.amplitude_m = parse_number(fields[c], name, line_number);
      } else {
        const double v = parse_number(fields[c], name, line_number);
        if (name == "frequency_hz") row.frequency_hz = v;
        if (name == "m_app_kg") row.point.m_app_kg = v;
        if (name == "c_eq_N_s_m") row.point.c_eq_N_s_m = v;
        if (name == "m_app_spread_kg") row.point.m_app_spread_kg = v;
        if (name == "c_eq_spread_N_s_m") row.point.c_eq_spread_N_s_m = v;
      }
    }
    if (rows_are_gammas() && !row.gamma) fail(line_number, "gamma is empty: the table's rows are gammas");
    if (!(row_value(row) > 0)) {
      fail(line_number,
           (rows_are_gammas() ? "gamma = " : "amplitude_m = ") + text::number(row_value(row)) + ": must be > 0");
    }
    if (!(row.frequency_hz > 0))
      fail(line_number, "frequency_hz = " + text::number(row.frequency_hz) + ": must be > 0");
    return row;
  }

  void read_metadata(DamperTable& table) const {
    for (const auto& key : metadata_keys) {
      if (!metadata_.count(key)) throw InputError(where_ + ": the comment line '# " + key + " = ...' is missing");
    }
    if (metadata_.count(rows_key)) {
      const auto& [rows, line] = metadata_.at(rows_key);
      if (rows != "gamma" && rows != "amplitude") fail(line, "rows = '" + rows + "': must be amplitude or gamma");
    }
    const auto& [format, format_line] = metadata_.at("format");
    if (format != table_csv_format) {
      fail(format_line, "format '" + format + "': this pdamp reads '" + table_csv_format + "'");
    }
    table.source = metadata_.at("source").first;
    table.row_axis = rows_are_gammas() ? RowAxis::gamma : RowAxis::amplitude;
    for (const auto& [key, target] :
         {std::pair{"bed_mass_kg", &table.bed_mass_kg}, {"gravity_m_s2", &table.gravity_m_s2}}) {
      const auto& [value, line] = metadata_.at(key);
      *target = parse_number(value, key, line);
    }
  }

  bool rows_are_gammas() const {
    const auto rows = metadata_.find(rows_key);
    return rows != metadata_.end() && rows->second.first == "gamma";
  }

  double row_value(const Row& r) const { return rows_are_gammas() ? *r.gamma : *r.amplitude_m; }

  /// The grid from the rows: every distinct row value with every distinct frequency, once.
  DamperTable assemble() const {
    DamperTable table;
    read_metadata(table);
    if (header_.empty()) throw InputError(where_ + ": no header row (and no points)");
    for (const Row& r : rows_) {
      table.rows.push_back(row_value(r));
      table.frequencies_hz.push_back(r.frequency_hz);
    }
    for (auto* axis : {&table.rows, &table.frequencies_hz}) {
      std::sort(axis->begin(), axis->end());
      axis->erase(std::unique(axis->begin(), axis->end()), axis->end());
    }
    const std::size_t na = table.rows.size(), nf = table.frequencies_hz.size();
    if (na >= 2 && nf >= 2) place_rows(table);
    validate_damper_table(table, where_);
    return table;
  }

  void place_rows(DamperTable& table) const {
    const auto index = [](const std::vector<double>& axis, double v) {
      return static_cast<std::size_t>(std::lower_bound(axis.begin(), axis.end(), v) - axis.begin());
    };
    const std::size_t na = table.rows.size(), nf = table.frequencies_hz.size();
    std::vector<int> line_of(na * nf, 0);
    table.points.resize(na * nf);
    for (const Row& r : rows_) {
      const std::size_t i = index(table.rows, row_value(r)), j = index(table.frequencies_hz, r.frequency_hz);
      int& seen = line_of[j * na + i];
      if (seen) fail(r.line, "the point " + describe_point(table, i, j) + " is also on line " + std::to_string(seen));
      seen = r.line;
      table.at(i, j) = r.point;
      check_derived(table, r, i, j);
    }
    const auto missing = std::find(line_of.begin(), line_of.end(), 0);
    if (missing != line_of.end()) {
      const auto k = static_cast<std::size_t>(missing - line_of.begin());
      throw InputError(where_ + ": the grid is not rectangular: " + std::to_string(rows_.size()) + " points for " +
                       std::to_string(na) + (rows_are_gammas() ? " gammas x " : " amplitudes x ") + std::to_string(nf) +
                       " frequencies; there is no point at " + describe_point(table, k % na, k / na));
    }
  }

  /// The column that is not the rows, where given, must follow from them.
  void check_derived(const DamperTable& table, const Row& r, std::size_t i, std::size_t j) const {
    const bool gammas = table.row_axis == RowAxis::gamma;
    if (table.gravity_m_s2 == 0) {  // Γ rows without gravity: validate_damper_table names it
      if (r.gamma && !gammas) {
        fail(r.line, "gamma is given but the table is weightless (gravity_m_s2 = 0): leave it empty");
      }
      return;
    }
    const std::optional<double> given = gammas ? r.amplitude_m : r.gamma;
    if (!given) return;
    const double expected = gammas ? table.amplitude_m(i, j) : table.gamma(i, j);
    if (std::abs(*given - expected) > derived_tolerance * expected) {
      fail(r.line, (gammas ? "amplitude_m = " + text::number(*given) + " but gamma g / (2 pi f)^2 = "
                           : "gamma = " + text::number(*given) + " but A (2 pi f)^2 / g = ") +
                       text::number(expected) + " (gravity_m_s2 = " + text::number(table.gravity_m_s2) + ")");
    }
  }

  std::string where_;
  std::map<std::string, std::pair<std::string, int>> metadata_;
  std::vector<std::string> header_;
  std::vector<Row> rows_;
};

}  // namespace

std::string damper_table_csv(const DamperTable& table) {
  std::ostringstream out;
  out << "# format = " << table_csv_format << "\n"
      << "# source = " << table.source << "\n"
      << "# bed_mass_kg = " << text::number(table.bed_mass_kg) << "\n"
      << "# gravity_m_s2 = " << text::number(table.gravity_m_s2) << "\n";
  if (table.row_axis == RowAxis::gamma) out << "# " << rows_key << " = gamma\n";
  out << "# Container motion z = A sin(2 pi f t); the particles' first-harmonic force on it is\n"
      << "# -m_app z'' - c_eq z'. Units: A in m, f in Hz, m_app in kg, c_eq in N s/m; gamma = A (2 pi f)^2 / g;\n"
      << "# spreads: standard deviation over the averaged steady cycles; settled: 1 steady state reached, 0 not.\n";
  for (std::size_t c = 0; c < columns.size(); ++c) out << (c ? "," : "") << columns[c];
  out << "\n";
  for (std::size_t j = 0; j < table.frequencies_hz.size(); ++j) {
    for (std::size_t i = 0; i < table.rows.size(); ++i) {
      const TablePoint& p = table.at(i, j);
      out << text::number(table.amplitude_m(i, j)) << "," << text::number(table.frequencies_hz[j]) << ","
          << (table.gravity_m_s2 > 0 ? text::number(table.gamma(i, j)) : "") << "," << text::number(p.m_app_kg) << ","
          << text::number(p.c_eq_N_s_m) << "," << text::number(p.m_app_spread_kg) << ","
          << text::number(p.c_eq_spread_N_s_m) << "," << (p.settled ? 1 : 0) << "\n";
    }
  }
  return out.str();
}

DamperTable parse_damper_table_csv(const std::string& text, const std::string& where) {
  return CsvReader(where).read(text);
}

}  // namespace pdamp::rom
