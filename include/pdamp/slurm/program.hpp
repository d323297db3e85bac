#pragma once
/// Running Slurm's programs (sbatch, squeue, sacct, scontrol) without a shell.

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pdamp::slurm {

/// The program's path if `name` is an executable in one of PATH's folders.
std::optional<std::filesystem::path> find_program(std::string_view name);

struct ProgramResult {
  int exit_code = 0;  ///< 128 + the signal if it was killed
  std::string out, err;
};

/// Runs `argv[0]` (looked up in PATH) with the other words as its arguments, no shell
/// between, and captures its output. Throws RuntimeFailure if it cannot be started, or
/// runs longer than `timeout` (it is then killed).
ProgramResult run_program(const std::vector<std::string>& argv,
                          std::chrono::milliseconds timeout = std::chrono::seconds(60));

}  // namespace pdamp::slurm
