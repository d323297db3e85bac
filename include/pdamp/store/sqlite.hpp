#pragma once
/// A thin RAII layer over the SQLite C API: a connection, prepared statements and
/// transactions. Errors become RuntimeFailure carrying SQLite's message; a store locked
/// by others beyond the wait limit becomes Busy, a damaged one Damaged.
///
/// A connection belongs to one thread at a time (SQLite's multi-thread mode): threads
/// writing one store each open their own.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "pdamp/errors.hpp"

struct sqlite3;
struct sqlite3_stmt;

namespace pdamp::sqlite {

/// How long a connection waits for other connections' locks before giving up.
inline constexpr std::chrono::milliseconds default_busy_limit{60'000};

enum class Access {
  read_write,  ///< creates the file if needed
  read_only,   ///< never writes the file (reading a WAL file may create its -shm beside it)
  snapshot,    ///< read-only, without locks or the WAL: for a file nobody can be writing
};

/// The file stayed locked by other connections beyond the wait limit.
class Busy : public RuntimeFailure {
 public:
  using RuntimeFailure::RuntimeFailure;
};

/// The file is not an SQLite database, or SQLite found a damaged page in it.
class Damaged : public RuntimeFailure {
 public:
  using RuntimeFailure::RuntimeFailure;
};

/// The file, or the files SQLite keeps beside it (-wal, -shm), cannot be written.
class NotWritable : public RuntimeFailure {
 public:
  using RuntimeFailure::RuntimeFailure;
};

class Database {
 public:
  /// Opens a database file with foreign keys on. A lock held by another connection is
  /// waited for, retrying with randomised exponential back-off up to `busy_limit`.
  explicit Database(const std::filesystem::path& file, Access access = Access::read_write,
                    std::chrono::milliseconds busy_limit = default_busy_limit);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  /// Runs one or more statements without results.
  void exec(std::string_view sql);
  std::int64_t last_insert_rowid() const;
  /// Rows changed by the last INSERT, UPDATE or DELETE.
  std::int64_t changes() const;
  sqlite3* handle() const { return db_; }
  /// Whether SQLite opened the file for reading only (opened to write a file that this
  /// user may not write, it falls back to that).
  bool read_only() const;
  const std::filesystem::path& file() const { return file_; }
  std::chrono::milliseconds busy_limit() const { return busy_limit_; }

  /// Sleeps before retry number `attempt` (from 0): 1, 2, 4 ... 64, then 100 ms, each
  /// scaled by a random factor from 0.5 to 1.5 so that waiting writers do not retry in step.
  void back_off(int attempt);
  /// Throws the exception that SQLite's result code `rc` calls for; `sql` names the
  /// statement when the error is the program's rather than the file's.
  [[noreturn]] void fail(int rc, std::string_view sql) const;

 private:
  static int on_busy(void* self, int attempt);

  sqlite3* db_ = nullptr;
  std::filesystem::path file_;
  std::chrono::milliseconds busy_limit_;
  std::chrono::steady_clock::time_point wait_started_;
  std::minstd_rand jitter_;
};

class Statement {
 public:
  Statement(Database& db, std::string_view sql);
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  // Parameters are numbered from 1, as in SQLite.
  Statement& bind(int index, double value);
  Statement& bind(int index, std::int64_t value);
  Statement& bind(int index, int value) { return bind(index, static_cast<std::int64_t>(value)); }
  Statement& bind(int index, std::string_view value);
  Statement& bind(int index, std::optional<double> value);
  Statement& bind(int index, std::optional<std::int64_t> value);
  Statement& bind(int index, std::span<const std::byte> blob);
  Statement& bind_null(int index);
  /// Binds the value in `column` of another statement's current row as it is: its type and
  /// bits (a row copied between stores).
  Statement& bind_column(int index, const Statement& row, int column);

  /// Steps once: true if a row is available, false when done.
  bool step();
  /// Steps to completion (for statements without results) and resets.
  void run();
  void reset();

  // Columns are numbered from 0, as in SQLite.
  bool is_null(int column) const;
  double column_double(int column) const;
  std::int64_t column_int(int column) const;
  std::string column_text(int column) const;
  std::optional<double> column_optional_double(int column) const;
  std::optional<std::int64_t> column_optional_int(int column) const;
  std::vector<std::byte> column_blob(int column) const;
  int column_count() const;
  /// Whether `column` holds the same type and bits as `other_column` of another statement's
  /// row (a REAL compared bit for bit: -0.0 differs from 0.0).
  bool same_value(int column, const Statement& other, int other_column) const;

 private:
  void check_bind(int rc);

  Database* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

/// BEGIN IMMEDIATE ... COMMIT; rolls back if destroyed uncommitted.
class Transaction {
 public:
  explicit Transaction(Database& db);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit();

 private:
  Database* db_;
  bool open_ = true;
};

/// Runs `action`, and again, with back-off, while another connection's lock gets in its
/// way (also the busy errors SQLite's own wait cannot absorb, such as a stale WAL
/// snapshot), until the database's busy limit. Returns what `action` returns.
template <class Action>
auto retry_while_busy(Database& db, Action&& action) -> std::invoke_result_t<Action&> {
  const auto deadline = std::chrono::steady_clock::now() + db.busy_limit();
  for (int attempt = 0;; ++attempt) {
    try {
      return action();
    } catch (const Busy&) {
      if (std::chrono::steady_clock::now() >= deadline) throw;
    }
    db.back_off(attempt);
  }
}

/// Runs `write` inside a write transaction and commits it, retried from the start while
/// busy (retry_while_busy): `write` must keep its effects inside the transaction.
template <class Write>
auto write_transaction(Database& db, Write&& write) -> std::invoke_result_t<Write&> {
  return retry_while_busy(db, [&] {
    Transaction transaction(db);
    if constexpr (std::is_void_v<std::invoke_result_t<Write&>>) {
      write();
      transaction.commit();
    } else {
      auto result = write();
      transaction.commit();
      return result;
    }
  });
}

}  // namespace pdamp::sqlite
