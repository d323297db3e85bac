#include "store_file.hpp"

#include <algorithm>
#include <array>
#include <fstream>
#include <set>
#include <string_view>
#include <utility>
#include <vector>

#include "schema.hpp"

namespace pdamp::store_file {
namespace {

using Kind = Examined::Kind;

/// The tables that grow with the runs' results; the others grow with the number of runs.
constexpr std::array<std::string_view, 3> bulk_tables{"samples", "cycles", "initial_particles"};

std::string named(const std::filesystem::path& file) { return "'" + file.string() + "'"; }

bool has_sqlite_header(const std::filesystem::path& file) {
  static constexpr std::string_view magic("SQLite format 3\0", 16);
  std::array<char, magic.size()> header{};
  std::ifstream in(file, std::ios::binary);
  in.read(header.data(), header.size());
  return in && std::string_view(header.data(), header.size()) == magic;
}

/// A read-only connection. A WAL store needs its -shm file beside it; where that cannot
/// be created (a directory the user cannot write) and no -wal file holds writes not yet
/// in the file, nobody can be writing it, and the file is read as it is.
std::unique_ptr<sqlite::Database> open_reader(const std::filesystem::path& file, const StoreOptions& options) {
  try {
    auto db = std::make_unique<sqlite::Database>(file, sqlite::Access::read_only, options.busy_limit);
    db->exec("SELECT count(*) FROM sqlite_schema");
    return db;
  } catch (const sqlite::NotWritable& e) {
    std::error_code error;
    if (std::filesystem::file_size(file.string() + "-wal", error) > 0 && !error) {
      throw InputError("the store " + named(file) +
                       " cannot be read: SQLite needs to create its -shm file beside it (" + e.what() +
                       ") to read the writes its -wal file holds");
    }
  }
  return std::make_unique<sqlite::Database>(file, sqlite::Access::snapshot, options.busy_limit);
}

std::int64_t integer(sqlite::Database& db, const std::string& sql) {
  sqlite::Statement query(db, sql);
  query.step();
  return query.column_int(0);
}

std::vector<std::string> table_names(sqlite::Database& db) {
  sqlite::Statement query(db, "SELECT name FROM sqlite_schema WHERE type = 'table' ORDER BY name");
  std::vector<std::string> names;
  while (query.step()) names.push_back(query.column_text(0));
  return names;
}

/// What PRAGMA quick_check reports wrong, of the whole file or of one table: at most 3 lines.
std::vector<std::string> quick_check(sqlite::Database& db, const std::string& table) {
  std::string quoted = "\"";
  for (const char c : table) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  sqlite::Statement check(db, table.empty() ? "PRAGMA quick_check(3)" : "PRAGMA quick_check(" + quoted + "\")");
  std::vector<std::string> problems;
  while (check.step() && problems.size() < 3) {
    if (const std::string line = check.column_text(0); line != "ok") problems.push_back(line);
  }
  return problems;
}

void check_integrity(sqlite::Database& db, const std::filesystem::path& file, const StoreOptions& options,
                     const std::vector<std::string>& tables) {
  std::vector<std::string> problems;
  if (std::filesystem::file_size(file) <= options.full_check_limit_bytes) {
    problems = quick_check(db, "");
  } else {
    for (const auto& table : tables) {
      if (std::find(bulk_tables.begin(), bulk_tables.end(), table) != bulk_tables.end()) continue;
      for (auto& problem : quick_check(db, table)) problems.push_back(std::move(problem));
    }
  }
  if (problems.empty()) return;
  std::string message = "the store " + named(file) + " is damaged (SQLite's quick_check: ";
  for (std::size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
  throw InputError(message + "); pdamp neither reads nor writes it. Recover what is readable with: sqlite3 " +
                   named(file) + " .recover | sqlite3 recovered.sqlite");
}

std::string not_a_store(const std::filesystem::path& file, std::int64_t application_id,
                        const std::vector<std::string>& tables) {
  std::string message = "'" + file.string() + "' is not a pdamp run store: it is another program's SQLite database (";
  if (application_id != 0) message += "application_id " + std::to_string(application_id) + ", ";
  message += "tables ";
  for (std::size_t i = 0; i < tables.size() && i < 5; ++i) message += (i ? ", " : "") + tables[i];
  if (tables.size() > 5) message += " ...";
  return message + "); give another --db";
}

/// The (type, name) of every schema object but SQLite's own.
std::set<std::pair<std::string, std::string>> schema_objects(sqlite::Database& db) {
  sqlite::Statement query(db, "SELECT type, name FROM sqlite_schema WHERE substr(name, 1, 7) != 'sqlite_'");
  std::set<std::pair<std::string, std::string>> objects;
  while (query.step()) objects.emplace(query.column_text(0), query.column_text(1));
  return objects;
}

}  // namespace

void check_schema(sqlite::Database& db) {
  static const auto expected = [] {
    sqlite::Database scratch(":memory:");
    for (const std::string_view migration : schema::migrations()) scratch.exec(migration);
    return schema_objects(scratch);
  }();
  const auto present = schema_objects(db);
  std::string missing;
  for (const auto& [type, name] : expected) {
    if (!present.contains({type, name})) missing += (missing.empty() ? "" : ", ") + type + " " + name;
  }
  if (missing.empty()) return;
  throw InputError("the store " + named(db.file()) + " is damaged: its schema lacks " + missing +
                   ", which pdamp created (the file was changed by hand or by another program); pdamp neither reads "
                   "nor writes it. Restore the file from a copy, or give another --db");
}

void refuse_newer(const std::filesystem::path& file, int version, int latest_version) {
  throw InputError("database " + named(file) + " has schema version " + std::to_string(version) +
                   ", newer than this pdamp's " + std::to_string(latest_version) +
                   "; use a newer pdamp or another --db");
}

Examined examine(const std::filesystem::path& file, const StoreOptions& options, int latest_version) {
  // Names SQLite takes for something else than a file: runs stored there would be lost
  // (a temporary or in-memory database) or land in another file (a URI's path).
  const std::string name = file.string();
  if (name.empty() || name == ":memory:" || name.starts_with("file:")) {
    const std::string what = name.empty()         ? "a temporary database, deleted when pdamp ends"
                             : name == ":memory:" ? "a database in memory, gone when pdamp ends"
                                                  : "a URI, whose path is another file's";
    throw InputError("database '" + name + "': SQLite takes this name for " + what +
                     "; give a run store file's path with --db" +
                     (name.empty() ? "" : " (for a file of that name, './" + name + "')"));
  }
  std::error_code error;
  const auto status = std::filesystem::status(file, error);
  if (!std::filesystem::exists(status)) return {};
  if (!std::filesystem::is_regular_file(status)) {
    throw InputError("database " + named(file) + " is not a file (give a run store file with --db)");
  }
  if (std::filesystem::file_size(file) == 0) return {Kind::empty, 0, nullptr};
  if (!has_sqlite_header(file)) {
    throw InputError("'" + file.string() +
                     "' is not a pdamp run store: it is not an SQLite database; give another --db");
  }
  Examined examined{Kind::store, 0, nullptr};
  try {
    examined.reader = open_reader(file, options);
    sqlite::Database& db = *examined.reader;
    const std::int64_t application_id = integer(db, "PRAGMA application_id");
    examined.version = static_cast<int>(integer(db, "PRAGMA user_version"));
    const std::vector<std::string> tables = table_names(db);
    if (application_id == 0 && examined.version == 0 && tables.empty()) return {Kind::empty, 0, nullptr};
    // Stores made before migration 6 have no application_id: they have a runs table.
    const bool pdamp_store = application_id == pdamp_application_id ||
                             (application_id == 0 && examined.version >= 1 && examined.version < 6 &&
                              std::find(tables.begin(), tables.end(), "runs") != tables.end());
    if (!pdamp_store) throw InputError(not_a_store(file, application_id, tables));
    if (examined.version > latest_version) refuse_newer(file, examined.version, latest_version);
    check_integrity(db, file, options, tables);
    if (examined.version == latest_version) check_schema(db);
  } catch (const sqlite::Damaged& e) {
    throw InputError(e.what());
  }
  return examined;
}

}  // namespace pdamp::store_file
