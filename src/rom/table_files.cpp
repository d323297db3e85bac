#include "pdamp/rom/table_files.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

#include "pdamp/errors.hpp"

namespace pdamp::rom {
FileFormat file_format(const std::filesystem::path& file, const std::string& what) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".csv") return FileFormat::csv;
  if (extension == ".json") return FileFormat::json;
  throw InputError(what + " '" + file.string() + "': name it .csv or .json to choose the format");
}

DamperTable read_damper_table(const std::filesystem::path& file) {
  const FileFormat format = file_format(file, "damper table");
  std::error_code error;
  if (std::filesystem::exists(file, error) && !std::filesystem::is_regular_file(file, error)) {
    throw InputError("damper table '" + file.string() + "' is not a regular file");
  }
  // A characterisation grid holds hundreds of points (tens of kB); a file far larger is no
  // table and is not read into memory.
  constexpr std::uintmax_t most_bytes = 64u << 20;
  const std::uintmax_t bytes = std::filesystem::file_size(file, error);
  if (!error && bytes > most_bytes) {
    throw InputError("damper table '" + file.string() + "' has " + std::to_string(bytes) +
                     " bytes: a table file is at most 64 MiB");
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError("damper table '" + file.string() + "' cannot be read (does it exist?)");
  std::ostringstream text;
  text << in.rdbuf();
  return format == FileFormat::csv ? parse_damper_table_csv(text.str(), file.string())
                                   : parse_damper_table_json(text.str(), file.string());
}

std::string damper_table_text(const DamperTable& table, const std::filesystem::path& file) {
  return file_format(file, "table export") == FileFormat::csv ? damper_table_csv(table) : damper_table_json(table);
}

void write_text_file(const std::filesystem::path& file, const std::string& text) {
  std::filesystem::path temporary = file;
  temporary += ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw RuntimeFailure("cannot write '" + file.string() + "'");
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, file, error);
  if (error) {
    std::filesystem::remove(temporary, error);
    throw RuntimeFailure("cannot write '" + file.string() + "': " + error.message());
  }
}

}  // namespace pdamp::rom
