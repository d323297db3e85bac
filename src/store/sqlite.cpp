#include "pdamp/store/sqlite.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>
#include <thread>

namespace pdamp::sqlite {
namespace {

/// `file:` URI of a path, for the `immutable` parameter (RFC 3986 escapes where SQLite needs them).
std::string file_uri(const std::filesystem::path& file) {
  std::string uri = "file:";
  for (const char c : std::filesystem::absolute(file).string()) {
    if (c == '%' || c == '?' || c == '#') {
      static constexpr char hex[] = "0123456789ABCDEF";
      const auto byte = static_cast<unsigned char>(c);
      uri += '%';
      uri += hex[byte >> 4];
      uri += hex[byte & 15];
    } else {
      uri += c;
    }
  }
  return uri + "?immutable=1";
}

std::string seconds(std::chrono::milliseconds duration) {
  std::ostringstream text;
  text << std::chrono::duration<double>(duration).count() << " s";
  return text.str();
}

int open_flags(Access access) {
  switch (access) {
    case Access::read_write:
      return SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE;
    case Access::read_only:
      return SQLITE_OPEN_READONLY;
    case Access::snapshot:
      break;
  }
  return SQLITE_OPEN_READONLY | SQLITE_OPEN_URI;
}

}  // namespace

Database::Database(const std::filesystem::path& file, Access access, std::chrono::milliseconds busy_limit)
    : file_(file), busy_limit_(busy_limit), jitter_(std::random_device{}()) {
  const std::string name = access == Access::snapshot ? file_uri(file) : file.string();
  if (sqlite3_open_v2(name.c_str(), &db_, open_flags(access) | SQLITE_OPEN_NOMUTEX, nullptr) != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw InputError("database '" + file.string() + "' cannot be opened: " + message);
  }
  sqlite3_extended_result_codes(db_, 1);
  // Several pdamp processes and threads may use one file: wait for each other's locks.
  sqlite3_busy_handler(db_, &Database::on_busy, this);
  exec("PRAGMA foreign_keys = ON");
}

Database::~Database() { sqlite3_close(db_); }

bool Database::read_only() const { return sqlite3_db_readonly(db_, "main") == 1; }

int Database::on_busy(void* self, int attempt) {
  auto& db = *static_cast<Database*>(self);
  const auto now = std::chrono::steady_clock::now();
  if (attempt == 0) db.wait_started_ = now;
  if (now - db.wait_started_ >= db.busy_limit_) return 0;
  db.back_off(attempt);
  return 1;
}

void Database::back_off(int attempt) {
  const double base_ms = std::min(100.0, std::ldexp(1.0, std::min(attempt, 7)));
  std::uniform_real_distribution<double> factor(0.5, 1.5);
  std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(base_ms * factor(jitter_)));
}

void Database::fail(int rc, std::string_view sql) const {
  const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
  const std::string store = "the store '" + file_.string() + "'";
  switch (rc & 0xff) {
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
      throw Busy(store + " stayed locked by another connection for longer than the " + seconds(busy_limit_) +
                 " pdamp waits (SQLite: " + message + "); another program may be holding a transaction open on it");
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB:
      throw Damaged(store + " is damaged (SQLite: " + message + "); recover what is readable with: sqlite3 '" +
                    file_.string() + "' .recover | sqlite3 recovered.sqlite");
    case SQLITE_READONLY:
    case SQLITE_CANTOPEN:
    case SQLITE_PERM:
      throw NotWritable(store + ": " + message);
    case SQLITE_FULL:
    case SQLITE_IOERR:
    case SQLITE_NOMEM:
    case SQLITE_NOLFS:
      throw RuntimeFailure(store + ": " + message);
    default:
      break;
  }
  // The program's own error (a constraint, a mistake in SQL): the statement helps.
  throw RuntimeFailure("SQLite: " + message + " in: " + std::string(sql.substr(0, 120)));
}

void Database::exec(std::string_view sql) {
  const std::string text(sql);
  if (const int rc = sqlite3_exec(db_, text.c_str(), nullptr, nullptr, nullptr); rc != SQLITE_OK) fail(rc, text);
}

std::int64_t Database::last_insert_rowid() const { return sqlite3_last_insert_rowid(db_); }
std::int64_t Database::changes() const { return sqlite3_changes64(db_); }

Statement::Statement(Database& db, std::string_view sql) : db_(&db) {
  if (const int rc = sqlite3_prepare_v3(db.handle(), sql.data(), static_cast<int>(sql.size()),
                                        SQLITE_PREPARE_PERSISTENT, &stmt_, nullptr);
      rc != SQLITE_OK) {
    db.fail(rc, sql);
  }
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

void Statement::check_bind(int rc) {
  if (rc != SQLITE_OK) db_->fail(rc, sqlite3_sql(stmt_));
}

Statement& Statement::bind(int index, double value) {
  check_bind(sqlite3_bind_double(stmt_, index, value));
  return *this;
}

Statement& Statement::bind(int index, std::int64_t value) {
  check_bind(sqlite3_bind_int64(stmt_, index, value));
  return *this;
}

Statement& Statement::bind(int index, std::string_view value) {
  check_bind(sqlite3_bind_text(stmt_, index, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT));
  return *this;
}

Statement& Statement::bind(int index, std::span<const std::byte> blob) {
  check_bind(sqlite3_bind_blob64(stmt_, index, blob.data(), blob.size(), SQLITE_TRANSIENT));
  return *this;
}

Statement& Statement::bind(int index, std::optional<double> value) {
  return value ? bind(index, *value) : bind_null(index);
}

Statement& Statement::bind(int index, std::optional<std::int64_t> value) {
  return value ? bind(index, *value) : bind_null(index);
}

Statement& Statement::bind_null(int index) {
  check_bind(sqlite3_bind_null(stmt_, index));
  return *this;
}

Statement& Statement::bind_column(int index, const Statement& row, int column) {
  check_bind(sqlite3_bind_value(stmt_, index, sqlite3_column_value(row.stmt_, column)));
  return *this;
}

bool Statement::step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  const std::string sql = sqlite3_sql(stmt_) ? sqlite3_sql(stmt_) : "";
  try {
    db_->fail(rc, sql);
  } catch (...) {
    sqlite3_reset(stmt_);
    throw;
  }
}

void Statement::run() {
  while (step()) {
  }
  reset();
}

void Statement::reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

bool Statement::is_null(int column) const { return sqlite3_column_type(stmt_, column) == SQLITE_NULL; }
double Statement::column_double(int column) const { return sqlite3_column_double(stmt_, column); }
std::int64_t Statement::column_int(int column) const { return sqlite3_column_int64(stmt_, column); }

std::string Statement::column_text(int column) const {
  const auto* text = sqlite3_column_text(stmt_, column);
  return text ? std::string(reinterpret_cast<const char*>(text),
                            static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column)))
              : std::string();
}

std::vector<std::byte> Statement::column_blob(int column) const {
  const auto* first = static_cast<const std::byte*>(sqlite3_column_blob(stmt_, column));
  return first ? std::vector<std::byte>(first, first + sqlite3_column_bytes(stmt_, column)) : std::vector<std::byte>();
}

std::optional<double> Statement::column_optional_double(int column) const {
  if (is_null(column)) return std::nullopt;
  return column_double(column);
}

std::optional<std::int64_t> Statement::column_optional_int(int column) const {
  if (is_null(column)) return std::nullopt;
  return column_int(column);
}

int Statement::column_count() const { return sqlite3_column_count(stmt_); }

bool Statement::same_value(int column, const Statement& other, int other_column) const {
  const int type = sqlite3_column_type(stmt_, column);
  if (type != sqlite3_column_type(other.stmt_, other_column)) return false;
  switch (type) {
    case SQLITE_NULL:
      return true;
    case SQLITE_INTEGER:
      return column_int(column) == other.column_int(other_column);
    case SQLITE_FLOAT:
      return std::bit_cast<std::uint64_t>(column_double(column)) ==
             std::bit_cast<std::uint64_t>(other.column_double(other_column));
    default:  // text and blobs: their bytes
      break;
  }
  const auto* a = static_cast<const char*>(sqlite3_column_blob(stmt_, column));
  const int size = sqlite3_column_bytes(stmt_, column);
  const auto* b = static_cast<const char*>(sqlite3_column_blob(other.stmt_, other_column));
  return size == sqlite3_column_bytes(other.stmt_, other_column) &&
         (size == 0 ||
          std::string_view(a, static_cast<std::size_t>(size)) == std::string_view(b, static_cast<std::size_t>(size)));
}

Transaction::Transaction(Database& db) : db_(&db) { db.exec("BEGIN IMMEDIATE"); }

Transaction::~Transaction() {
  if (open_) sqlite3_exec(db_->handle(), "ROLLBACK", nullptr, nullptr, nullptr);
}

void Transaction::commit() {
  db_->exec("COMMIT");
  open_ = false;
}

}  // namespace pdamp::sqlite
