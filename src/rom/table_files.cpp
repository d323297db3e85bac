#include "pdamp/rom/table_files.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <fstream>

#include "pdamp/errors.hpp"
#include "pdamp/input_file.hpp"

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
  const std::string name = "damper table '" + file.string() + "'";
  const std::string text = read_input_file({file, name, "a damper table file", max_table_file_bytes});
  return format == FileFormat::csv ? parse_damper_table_csv(text, file.string())
                                   : parse_damper_table_json(text, file.string());
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
