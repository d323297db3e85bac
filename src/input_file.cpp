#include "pdamp/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "pdamp/errors.hpp"

namespace pdamp {
namespace {

/// Closes a file descriptor when it goes out of scope.
struct OpenFile {
  int fd;
  ~OpenFile() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

std::string read_input_file(const InputFile& file) {
  const OpenFile in{::open(file.path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC)};
  auto cannot_read = [&](int error) {
    return InputError(file.name + " cannot be read (" +
                      (error == ENOENT   ? "no such file"
                       : error == EACCES ? "permission denied"
                                         : std::strerror(error)) +
                      ")" + file.hint);
  };
  struct stat status {};
  if (in.fd < 0 || ::fstat(in.fd, &status) != 0) throw cannot_read(errno);
  if (!S_ISREG(status.st_mode)) {
    const char* kind = S_ISDIR(status.st_mode)    ? "a directory"
                       : S_ISFIFO(status.st_mode) ? "a FIFO"
                       : S_ISSOCK(status.st_mode) ? "a socket"
                                                  : "a device";
    throw InputError(file.name + " is " + kind + ", not a regular file");
  }
  std::string text;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t got = ::read(in.fd, buffer, sizeof buffer);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw cannot_read(errno);
    if (got == 0) return text;
    text.append(buffer, static_cast<std::size_t>(got));
    if (text.size() > file.max_bytes) {
      throw InputError(file.name + " is larger than " + std::to_string(file.max_bytes) + " bytes, the most " +
                       file.kind + " may have");
    }
  }
}

}  // namespace pdamp
