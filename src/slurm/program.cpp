#include "pdamp/slurm/program.hpp"

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "pdamp/errors.hpp"

extern char** environ;

namespace pdamp::slurm {
namespace {

/// A pipe's two ends, closed when it goes.
struct Pipe {
  int fds[2] = {-1, -1};
  Pipe() {
    if (pipe2(fds, O_CLOEXEC) != 0) throw RuntimeFailure(std::string("cannot create a pipe: ") + std::strerror(errno));
  }
  ~Pipe() {
    for (const int fd : fds) {
      if (fd >= 0) close(fd);
    }
  }
  Pipe(const Pipe&) = delete;
  Pipe& operator=(const Pipe&) = delete;
  void close_end(int end) {
    close(fds[end]);
    fds[end] = -1;
  }
};

pid_t spawn(const std::vector<std::string>& argv, Pipe& out, Pipe& err) {
  std::vector<char*> words;
  words.reserve(argv.size() + 1);
  std::vector<std::string> copy = argv;
  for (auto& word : copy) words.push_back(word.data());
  words.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, out.fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, err.fds[1], STDERR_FILENO);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, words[0], &actions, nullptr, words.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw RuntimeFailure("cannot run '" + argv[0] + "': " + std::strerror(rc));
  out.close_end(1);
  err.close_end(1);
  return pid;
}

/// Reads both pipes until they close or the time is up; false on timeout.
bool read_all(Pipe& out, Pipe& err, std::string& out_text, std::string& err_text,
              std::chrono::steady_clock::time_point deadline) {
  Pipe* pipes[] = {&out, &err};
  std::string* texts[] = {&out_text, &err_text};
  while (out.fds[0] >= 0 || err.fds[0] >= 0) {
    pollfd fds[2];
    nfds_t n = 0;
    int which[2];
    for (int k = 0; k < 2; ++k) {
      if (pipes[k]->fds[0] >= 0) {
        fds[n] = {pipes[k]->fds[0], POLLIN, 0};
        which[n++] = k;
      }
    }
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    if (poll(fds, n, static_cast<int>(left.count())) < 0 && errno != EINTR) return false;
    for (nfds_t i = 0; i < n; ++i) {
      if (!(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      char buffer[4096];
      const ssize_t got = read(fds[i].fd, buffer, sizeof buffer);
      if (got > 0) {
        texts[which[i]]->append(buffer, static_cast<std::size_t>(got));
      } else if (got == 0 || errno != EINTR) {
        pipes[which[i]]->close_end(0);
      }
    }
  }
  return true;
}

}  // namespace

std::optional<std::filesystem::path> find_program(std::string_view name) {
  const char* path = std::getenv("PATH");
  std::istringstream folders(path ? path : "/usr/bin:/bin");
  for (std::string folder; std::getline(folders, folder, ':');) {
    const auto candidate = std::filesystem::path(folder.empty() ? "." : folder) / name;
    if (access(candidate.c_str(), X_OK) == 0 && !std::filesystem::is_directory(candidate)) return candidate;
  }
  return std::nullopt;
}

ProgramResult run_program(const std::vector<std::string>& argv, std::chrono::milliseconds timeout) {
  Pipe out, err;
  const pid_t pid = spawn(argv, out, err);
  ProgramResult result;
  const bool in_time = read_all(out, err, result.out, result.err, std::chrono::steady_clock::now() + timeout);
  if (!in_time) kill(pid, SIGKILL);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!in_time) {
    throw RuntimeFailure("'" + argv[0] + "' did not answer within " +
                         std::to_string(std::chrono::duration_cast<std::chrono::seconds>(timeout).count()) +
                         " s and was stopped");
  }
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

}  // namespace pdamp::slurm
