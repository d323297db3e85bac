/// The damper table as JSON: the axes as arrays, each quantity as an array of rows, one row per
/// frequency, one value per amplitude (or Γ). Read with SQLite's JSON functions (strict RFC 8259
/// syntax in SQLite 3.40), so no JSON library is needed.

#include <algorithm>
#include <sstream>
#include <unordered_map>

#include "pdamp/errors.hpp"
#include "pdamp/rom/table_files.hpp"
#include "pdamp/store/sqlite.hpp"
#include "text_format.hpp"

namespace pdamp::rom {
namespace {

/// The per-point quantities, by member.
struct Quantity {
  const char* key;
  double TablePoint::*member;
};
constexpr Quantity quantities[] = {{"m_app_kg", &TablePoint::m_app_kg},
                                   {"c_eq_N_s_m", &TablePoint::c_eq_N_s_m},
                                   {"m_app_spread_kg", &TablePoint::m_app_spread_kg},
                                   {"c_eq_spread_N_s_m", &TablePoint::c_eq_spread_N_s_m}};

const std::vector<std::string> keys = {"format",          "format_version",    "source",   "bed_mass_kg",
                                       "gravity_m_s2",    "frequencies_hz",    "m_app_kg", "c_eq_N_s_m",
                                       "m_app_spread_kg", "c_eq_spread_N_s_m", "settled"};
/// The rows' axis, exactly one of them.
constexpr const char* amplitude_rows = "amplitudes_m";
constexpr const char* gamma_rows = "gammas";
const char* rows_key(RowAxis axis) { return axis == RowAxis::gamma ? gamma_rows : amplitude_rows; }

/// The document's every node by its path ($.key[j][i]), from one pass of SQLite's json_tree.
class JsonReader {
 public:
  JsonReader(const std::string& text, const std::string& where) : where_(where) {
    sqlite::Database db(":memory:");
    sqlite::Statement valid(db, "SELECT json_valid(?1)");
    valid.bind(1, text);
    if (!valid.step() || valid.column_int(0) != 1) fail("not valid JSON (RFC 8259)");
    sqlite::Statement tree(db,
                           "SELECT fullkey, type, atom, CASE type WHEN 'array' THEN json_array_length(value) END, "
                           "path, key FROM json_tree(?1)");
    tree.bind(1, text);
    while (tree.step()) {
      // SQLite quotes some keys in fullkey ($."bed_mass_kg"); the table's keys hold no quotes.
      std::string path = tree.column_text(0);
      path.erase(std::remove(path.begin(), path.end(), '"'), path.end());
      if (nodes_.count(path)) fail("member " + path + " is given twice");
      nodes_[path] = {tree.column_text(1), tree.column_double(2), tree.column_text(2),
                      static_cast<std::size_t>(tree.column_int(3))};
      if (tree.column_text(4) == "$" && !tree.is_null(5)) members_.push_back(tree.column_text(5));
    }
  }

  DamperTable read() const {
    check_members();
    DamperTable table;
    const std::string format = string_at("$.format");
    const double version = number_at("$.format_version");
    if (format != table_json_format || version != table_json_version) {
      fail("format '" + format + "' version " + text::number(version) + ": this pdamp reads '" + table_json_format +
           "' version " + std::to_string(table_json_version));
    }
    table.source = string_at("$.source");
    table.bed_mass_kg = number_at("$.bed_mass_kg");
    table.gravity_m_s2 = number_at("$.gravity_m_s2");
    table.row_axis = nodes_.count(std::string("$.") + gamma_rows) ? RowAxis::gamma : RowAxis::amplitude;
    table.rows = numbers_at(std::string("$.") + rows_key(table.row_axis));
    table.frequencies_hz = numbers_at("$.frequencies_hz");
    const std::size_t na = table.rows.size(), nf = table.frequencies_hz.size();
    table.points.resize(na * nf);
    for (const Quantity& q : quantities) {
      read_grid(q.key, na, nf, [&](std::size_t i, std::size_t j, const std::string& path) {
        table.at(i, j).*q.member = number_at(path);
      });
    }
    read_grid("settled", na, nf, [&](std::size_t i, std::size_t j, const std::string& path) {
      const std::string type = type_at(path);
      if (type != "true" && type != "false") fail(path + " is " + type + ": must be true or false");
      table.at(i, j).settled = type == "true";
    });
    validate_damper_table(table, where_);
    return table;
  }

 private:
  struct Node {
    std::string type;  ///< SQLite's json_type: object, array, text, integer, real, true, false, null
    double number;
    std::string text;
    std::size_t length;  ///< of an array
  };

  [[noreturn]] void fail(const std::string& why) const { throw InputError(where_ + ": " + why); }

  void check_members() const {
    if (type_at("$") != "object") fail("the document must be a JSON object");
    for (const auto& member : members_) {
      if (member != amplitude_rows && member != gamma_rows &&
          std::find(keys.begin(), keys.end(), member) == keys.end()) {
        fail("unknown member \"" + member + "\" (the members are those of docs/rom.md, \"Table files\")");
      }
    }
    for (const auto& key : keys) {
      if (!nodes_.count("$." + key)) fail("member \"" + key + "\" is missing");
    }
    if (nodes_.count(std::string("$.") + amplitude_rows) == nodes_.count(std::string("$.") + gamma_rows)) {
      fail(std::string("give exactly one of the members \"") + amplitude_rows + "\" (rows of amplitudes, m) and \"" +
           gamma_rows + "\" (rows of Gamma)");
    }
  }

  std::string type_at(const std::string& path) const {
    const auto node = nodes_.find(path);
    return node == nodes_.end() ? "missing" : node->second.type;
  }

  double number_at(const std::string& path) const {
    const std::string type = type_at(path);
    if (type != "integer" && type != "real") fail(path + " is " + type + ": must be a number");
    return nodes_.at(path).number;
  }

  std::string string_at(const std::string& path) const {
    const std::string type = type_at(path);
    if (type != "text") fail(path + " is " + type + ": must be a string");
    return nodes_.at(path).text;
  }

  std::size_t array_length(const std::string& path) const {
    const std::string type = type_at(path);
    if (type != "array") fail(path + " is " + type + ": must be an array");
    return nodes_.at(path).length;
  }

  std::vector<double> numbers_at(const std::string& path) const {
    std::vector<double> values(array_length(path));
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = number_at(path + "[" + std::to_string(i) + "]");
    return values;
  }

  /// Visits key[j][i] for every frequency j and amplitude i, after checking the shape.
  template <class Visit>
  void read_grid(const std::string& key, std::size_t na, std::size_t nf, Visit visit) const {
    const std::string rows = nodes_.count(std::string("$.") + gamma_rows) ? " gammas" : " amplitudes";
    const std::string path = "$." + key;
    if (array_length(path) != nf) {
      fail(path + " has " + std::to_string(array_length(path)) + " rows for " + std::to_string(nf) +
           " frequencies: the grid must be rectangular (one row per frequency)");
    }
    for (std::size_t j = 0; j < nf; ++j) {
      const std::string row = path + "[" + std::to_string(j) + "]";
      if (array_length(row) != na) {
        fail(row + " has " + std::to_string(array_length(row)) + " values for " + std::to_string(na) + rows +
             ": the grid must be rectangular (one value per row)");
      }
      for (std::size_t i = 0; i < na; ++i) visit(i, j, row + "[" + std::to_string(i) + "]");
    }
  }

  std::string where_;
  std::unordered_map<std::string, Node> nodes_;
  std::vector<std::string> members_;  ///< the top-level object's keys
};

template <class Value>
void write_grid(std::ostream& out, const DamperTable& table, const char* key, Value value) {
  out << ",\n  " << text::json_string(key) << ": [";
  for (std::size_t j = 0; j < table.frequencies_hz.size(); ++j) {
    out << (j ? ",\n    [" : "\n    [");
    for (std::size_t i = 0; i < table.rows.size(); ++i) out << (i ? ", " : "") << value(table.at(i, j));
    out << "]";
  }
  out << "\n  ]";
}

void write_axis(std::ostream& out, const char* key, const std::vector<double>& axis) {
  out << ",\n  " << text::json_string(key) << ": [";
  for (std::size_t i = 0; i < axis.size(); ++i) out << (i ? ", " : "") << text::json_number(axis[i]);
  out << "]";
}

}  // namespace

std::string damper_table_json(const DamperTable& table) {
  std::ostringstream out;
  out << "{\n  \"format\": " << text::json_string(table_json_format)
      << ",\n  \"format_version\": " << table_json_version << ",\n  \"source\": " << text::json_string(table.source)
      << ",\n  \"bed_mass_kg\": " << text::json_number(table.bed_mass_kg)
      << ",\n  \"gravity_m_s2\": " << text::json_number(table.gravity_m_s2);
  write_axis(out, rows_key(table.row_axis), table.rows);
  write_axis(out, "frequencies_hz", table.frequencies_hz);
  for (const Quantity& q : quantities) {
    write_grid(out, table, q.key, [&](const TablePoint& p) { return text::json_number(p.*q.member); });
  }
  write_grid(out, table, "settled", [](const TablePoint& p) { return p.settled ? "true" : "false"; });
  out << "\n}\n";
  return out.str();
}

DamperTable parse_damper_table_json(const std::string& text, const std::string& where) {
  return JsonReader(text, where).read();
}

}  // namespace pdamp::rom
