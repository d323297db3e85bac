#pragma once
/// The damper table's file formats, CSV and JSON (columns and units: docs/rom.md, "Table
/// files"). Both read back to the same bits they were written from. Every reader validates the
/// table and throws InputError naming the file, the line or field and the reason.

#include <cstddef>
#include <filesystem>
#include <string>

#include "pdamp/rom/damper_table.hpp"

namespace pdamp::rom {

/// The format names written into and required from the files.
inline constexpr const char* table_csv_format = "pdamp damper table 1";
inline constexpr const char* table_json_format = "pdamp damper table";
inline constexpr int table_json_version = 1;

std::string damper_table_csv(const DamperTable& table);
std::string damper_table_json(const DamperTable& table);

/// `where` names the text in error messages (a file name).
DamperTable parse_damper_table_csv(const std::string& text, const std::string& where);
DamperTable parse_damper_table_json(const std::string& text, const std::string& where);

enum class FileFormat { csv, json };

/// The format `file`'s extension names (.csv or .json, any case); InputError naming `what` otherwise.
FileFormat file_format(const std::filesystem::path& file, const std::string& what);

/// The most a table file may hold (bytes): a characterisation grid of hundreds of points
/// takes tens of kB.
constexpr std::size_t max_table_file_bytes = 16 << 20;

/// Reads a table file, CSV or JSON by its extension (.csv, .json): a regular file of at most
/// max_table_file_bytes.
DamperTable read_damper_table(const std::filesystem::path& file);

/// The table's text in the format `file`'s extension names (.csv, .json); InputError otherwise.
std::string damper_table_text(const DamperTable& table, const std::filesystem::path& file);

/// Writes `text` to `file` through a temporary file beside it and a rename, so that a reader
/// never sees half a file and a failed write leaves no file; RuntimeFailure if it cannot.
void write_text_file(const std::filesystem::path& file, const std::string& text);

}  // namespace pdamp::rom
