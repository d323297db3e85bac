#pragma once
/// Reading a file the user names as input (a scenario, a damper table): what is not a
/// regular file of bounded size is refused before it can hang the reader or fill the memory.

#include <cstddef>
#include <filesystem>
#include <string>

namespace pdamp {

struct InputFile {
  std::filesystem::path path;
  std::string name;       ///< how messages name it: "scenario file 'x.ini'"
  std::string kind;       ///< what it is, for the size limit: "a scenario file"
  std::size_t max_bytes;  ///< the most it may hold
  std::string hint{};     ///< ends the message when it cannot be read
};

/// The whole of `file`. It is opened without blocking, so that a FIFO cannot hang the
/// reader, and checked as opened, so that nothing can be swapped in between. InputError
/// naming it when it cannot be read, is not a regular file or holds more than max_bytes.
std::string read_input_file(const InputFile& file);

}  // namespace pdamp
