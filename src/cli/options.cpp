#include "options.hpp"

#include <unistd.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <sstream>

#include "pdamp/errors.hpp"

namespace po = boost::program_options;

namespace pdamp {

po::options_description db_option() {
  po::options_description o("store");
  o.add_options()("db", po::value<std::string>()->default_value("pdamp.sqlite"), "SQLite run store file");
  return o;
}

CommandLine parse_options(const std::vector<std::string>& args, const po::options_description& options,
                          const po::positional_options_description& positional) {
  CommandLine line;
  try {
    const po::parsed_options parsed =
        po::command_line_parser(args).options(options).positional(positional).style(unabbreviated_style).run();
    po::store(parsed, line.vm);
    po::notify(line.vm);
    line.in_order = parsed.options;
  } catch (const po::unknown_option& e) {
    // "-1" given for RUN_ID looks like an option to the parser: say what is wrong with it.
    const std::string& token = e.get_option_name();
    double number = 0.0;
    const char* end = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(token.data(), end, number);
    const bool negative_number = ec == std::errc() && ptr == end;
    throw InputError(std::string(e.what()) +
                     (negative_number ? ": a negative number, where pdamp takes IDs and counts that are positive "
                                        "whole numbers"
                                      : ""));
  } catch (const po::error& e) {
    throw InputError(std::string(e.what()));
  }
  return line;
}

void check_writable_output(const std::filesystem::path& file, const std::string& option) {
  const auto folder = file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
  const std::string named = option + " '" + file.string() + "'";
  if (!std::filesystem::is_directory(folder)) {
    throw InputError(named + ": folder '" + folder.string() + "' does not exist");
  }
  if (std::filesystem::exists(file) ? access(file.c_str(), W_OK) != 0 : access(folder.c_str(), W_OK | X_OK) != 0) {
    throw InputError(named + ": " + (std::filesystem::exists(file) ? "the file" : "folder '" + folder.string() + "'") +
                     " is not writable by this user");
  }
}

std::string required_option(const po::variables_map& vm, const std::string& name, const std::string& command) {
  // Positional arguments are named in capitals (RUN_ID, STUDY.ini), as the usage shows them.
  const bool positional = std::isupper(static_cast<unsigned char>(name.front())) != 0;
  if (!vm.count(name)) throw InputError("pdamp " + command + ": " + (positional ? "" : "--") + name + " is required");
  return vm[name].as<std::string>();
}

long parse_whole_number(const std::string& text, long min, long max, const std::string& what) {
  long value = 0;
  const char* end = text.data() + text.size();
  if (auto [ptr, ec] = std::from_chars(text.data(), end, value);
      ec != std::errc() || ptr != end || value < min || value > max) {
    throw InputError(what + " '" + text + "': must be a whole number from " + std::to_string(min) + " to " +
                     std::to_string(max));
  }
  return value;
}

po::options_description snapshot_options() {
  po::options_description o("snapshots for ParaView (docs/snapshots.md)");
  o.add_options()("snapshots", po::value<std::string>()->value_name("EVERY_S"),
                  "write the spheres and the cavity as VTK files every EVERY_S s of simulated time, listed in one .pvd "
                  "per run")("snapshot-dir", po::value<std::string>()->value_name("DIR"),
                             "folder of the snapshots, each run's in DIR/run-<id>/ (default: beside the store, "
                             "named after it: pdamp.snapshots for pdamp.sqlite)");
  return o;
}

std::optional<SnapshotSettings> snapshot_request(const po::variables_map& vm) {
  if (!vm.count("snapshots")) {
    if (vm.count("snapshot-dir")) throw InputError("--snapshot-dir needs --snapshots EVERY_S");
    return std::nullopt;
  }
  return parse_snapshot_settings(vm["snapshots"].as<std::string>(),
                                 vm.count("snapshot-dir") ? vm["snapshot-dir"].as<std::string>() : std::string(),
                                 default_snapshot_directory(vm["db"].as<std::string>()));
}

po::options_description checkpoint_option() {
  po::options_description o("checkpoints (docs/checkpoints.md)");
  o.add_options()("checkpoint-every", po::value<std::string>()->value_name("SECONDS")->default_value("60"),
                  "save the run's state in the store every SECONDS of wall time, with the results up to it, so that "
                  "`pdamp resume` (or a study's resume) continues it if it is stopped or killed; 0: no checkpoints");
  return o;
}

std::chrono::milliseconds checkpoint_interval(const po::variables_map& vm) {
  const double seconds = parse_seconds(vm["checkpoint-every"].as<std::string>(), 0.0, true, 1e6, "--checkpoint-every");
  return std::chrono::ceil<std::chrono::milliseconds>(std::chrono::duration<double>(seconds));
}

double parse_seconds(const std::string& text, double min_s, bool min_allowed, double max_s, const std::string& what) {
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  const bool above_min = min_allowed ? value >= min_s : value > min_s;
  if (ec != std::errc() || ptr != end || !std::isfinite(value) || !above_min || value > max_s) {
    std::ostringstream range;
    range << (min_allowed ? "at least " : "above ") << min_s << " s and at most " << max_s << " s";
    throw InputError(what + " '" + text + "': must be a number of seconds " + range.str());
  }
  return value;
}

}  // namespace pdamp
