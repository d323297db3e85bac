#pragma once
/// What a file given as a run store holds, found without writing to it, and whether
/// SQLite finds it whole.

#include <cstdint>
#include <filesystem>
#include <memory>

#include "pdamp/store/run_store.hpp"

namespace pdamp::store_file {

/// application_id of a pdamp store ('pdam'), set by the schema's migration 6.
inline constexpr std::int64_t pdamp_application_id = 1885626733;

struct Examined {
  enum class Kind {
    missing,  ///< no file
    empty,    ///< an empty file, or an SQLite database without tables
    store,    ///< a pdamp store, checked whole (see StoreOptions)
  } kind = Kind::missing;
  int version = 0;  ///< its schema version
  /// A read-only connection to the store (Kind::store only).
  std::unique_ptr<sqlite::Database> reader;
};

/// Examines `file` read-only. Throws InputError for anything but a missing or empty file
/// or a pdamp store of a version this pdamp reads (at most `latest_version`), and for a
/// damaged store.
Examined examine(const std::filesystem::path& file, const StoreOptions& options, int latest_version);

/// Throws InputError for a store of the current schema version that lacks a table, view,
/// index or trigger the migrations create (one changed by hand or by another program):
/// found at open, before any work whose results could then not be stored. Objects added
/// beside pdamp's (a user's own views) are left alone.
void check_schema(sqlite::Database& db);

/// Throws the InputError for a store of a newer schema than this pdamp's.
[[noreturn]] void refuse_newer(const std::filesystem::path& file, int version, int latest_version);

}  // namespace pdamp::store_file
