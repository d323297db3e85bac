#pragma once
/// Command-line parsing shared by the CLI's commands (Boost.Program_options).

#include <boost/program_options.hpp>
#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "pdamp/sim/snapshots.hpp"

namespace pdamp {

/// --db FILE, default ./pdamp.sqlite.
boost::program_options::options_description db_option();

/// Boost's default style, but an option must be written whole: `--f` is not `--force`.
inline constexpr int unabbreviated_style = boost::program_options::command_line_style::default_style &
                                           ~boost::program_options::command_line_style::allow_guessing;

/// A command's parsed arguments: the options by name, and each as given, in order.
struct CommandLine {
  boost::program_options::variables_map vm;
  std::vector<boost::program_options::option> in_order;
};

/// Parses `args`; a bad option is an InputError.
CommandLine parse_options(const std::vector<std::string>& args,
                          const boost::program_options::options_description& options,
                          const boost::program_options::positional_options_description& positional = {});

/// An output file's folder exists and this user may write the file there: checked before
/// any work, so that a bad name leaves nothing written. InputError naming `option`.
void check_writable_output(const std::filesystem::path& file, const std::string& option);

/// The option's value; InputError naming the command if it is missing.
std::string required_option(const boost::program_options::variables_map& vm, const std::string& name,
                            const std::string& command);

/// --snapshots EVERY_S and --snapshot-dir DIR (pdamp run, compare, study run and resume).
boost::program_options::options_description snapshot_options();

/// --snapshots and --snapshot-dir, if given (checked against a scenario by plan_run); the
/// directory defaults to one beside the --db store.
std::optional<SnapshotSettings> snapshot_request(const boost::program_options::variables_map& vm);

/// --checkpoint-every SECONDS, default 60 (pdamp run, compare, resume, study run, resume and run-point).
boost::program_options::options_description checkpoint_option();

/// The wall time between checkpoints --checkpoint-every gives (0: none); InputError if it is not a
/// number of seconds from 0 to 10^6.
std::chrono::milliseconds checkpoint_interval(const boost::program_options::variables_map& vm);

/// A whole number from `min` to `max` given for `what`; InputError otherwise.
long parse_whole_number(const std::string& text, long min, long max, const std::string& what);

/// A finite number of seconds given for `what`, at least `min_s` (or above it if not
/// `min_allowed`) and at most `max_s`; InputError naming the range otherwise.
double parse_seconds(const std::string& text, double min_s, bool min_allowed, double max_s, const std::string& what);

}  // namespace pdamp
