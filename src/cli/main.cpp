/// pdamp command line: run a scenario on either engine, list and show stored runs.
/// Exit codes: 0 success; 1 runtime failure (the run is stored as failed, unless the store
/// itself failed); 2 usage or input error (nothing is stored); 128 + signal when a run was
/// interrupted (stored as interrupted with what it computed).

#include <unistd.h>

#include <boost/program_options.hpp>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "options.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/sim/engine_factory.hpp"
#include "pdamp/sim/snapshots.hpp"
#include "pdamp/version.hpp"
#include "rom_command.hpp"
#include "study_commands.hpp"
#include "text_table.hpp"

namespace po = boost::program_options;
using namespace pdamp;

namespace {

constexpr const char* usage =
    "usage: pdamp <command> [options]\n"
    "\n"
    "commands:\n"
    "  run     --scenario FILE --model soft|hard [--set k=v ...] [--db FILE] [--duration S]\n"
    "          [--snapshots EVERY_S [--snapshot-dir DIR]]\n"
    "          simulate a scenario and store the run (and snapshots for ParaView)\n"
    "  resume  RUN_ID [--until T] [--db FILE]\n"
    "          continue an interrupted or killed run from its checkpoint (or extend a completed one to T),\n"
    "          with its snapshots if it takes any; a killed comparison's run completes the comparison\n"
    "  runs    [--db FILE]            list the stored runs\n"
    "  show    RUN_ID [--db FILE]     summary of one run\n"
    "  delete  RUN_ID... [--db FILE] [--force]\n"
    "          delete runs with their samples, cycles, statistics and comparisons\n"
    "  compare --scenario FILE [--set k=v ...] [--db FILE] [--duration S] [--snapshots EVERY_S ...]\n"
    "          settle one bed, run both models from it, store both and their comparison\n"
    "  check   --scenario FILE [--set k=v ...]\n"
    "          validate a scenario and print every key with its resolved value\n"
    "  keys    list every scenario key with its unit, default and meaning\n"
    "  rom     --table FILE [--mass M --stiffness K --force F0|--base Y --freq A:B:N] [--out FILE]\n"
    "          a characterised damper's table on any single-degree-of-freedom host (harmonic balance)\n"
    "  study   run|resume|list|show|plot|run-point ...\n"
    "          parameter studies: many points of a base scenario, run in parallel and resumable\n"
    "\n"
    "  pdamp <command> --help   options of a command\n"
    "  pdamp --version\n"
    "\n"
    "The default database is ./pdamp.sqlite (an embedded SQLite file).\n";

po::options_description scenario_options() {
  po::options_description o("scenario");
  o.add_options()("scenario", po::value<std::string>(), "scenario file (INI syntax; see data/scenarios/)")(
      "set", po::value<std::vector<std::string>>()->composing(),
      "override a scenario key: --set section.key=value (repeatable; for a key given twice the last wins)");
  return o;
}

/// --duration S: --set run.duration_s=S, in its place among the --set options. One value:
/// Boost refuses the option given twice, as every single-valued one.
po::options_description duration_option() {
  po::options_description o("run");
  o.add_options()("duration", po::value<std::string>(), "simulated time in s (same as --set run.duration_s=S)");
  return o;
}

/// --threads and --simd: how the engines compute, which leaves the results' bits as they are,
/// so a resumed run may be given other values than its start.
po::options_description execution_options() {
  po::options_description o("execution (the same bits for any)");
  o.add_options()("threads", po::value<std::string>(), "threads for the soft engine (default: one per core)")(
      "simd", po::value<std::string>(),
      "both engines' instruction set, sse2, avx2 or avx512 (default: the widest this CPU runs)");
  return o;
}

void apply_execution_options(const po::variables_map& vm) {
  if (vm.count("threads")) set_thread_count(vm["threads"].as<std::string>());
  if (vm.count("simd")) set_instruction_set(vm["simd"].as<std::string>(), "--simd");
}

/// The scenario file with --set and --duration, in the order given (the last of a key wins).
ScenarioRequest scenario_request(const CommandLine& line, const std::string& command) {
  ScenarioRequest request{required_option(line.vm, "scenario", command), {}};
  for (const po::option& o : line.in_order) {
    for (const std::string& value : o.value) {
      if (o.string_key == "set") request.overrides.push_back(value);
      if (o.string_key == "duration") request.overrides.push_back("run.duration_s=" + value);
    }
  }
  return request;
}

int dispatch(const std::string& command, const std::vector<std::string>& args) {
  po::options_description help("general");
  help.add_options()("help,h", "show this help");

  if (command == "run") {
    po::options_description options("pdamp run --scenario FILE --model soft|hard [options]");
    options.add(help).add(scenario_options()).add(duration_option()).add(db_option()).add(snapshot_options());
    options.add(checkpoint_option()).add(execution_options());
    options.add_options()("model", po::value<std::string>(), "soft (Hertz DEM) or hard (event-driven)")(
        "diagnose-events",
        "hard model: count where the collisions come from (the time between a sphere's collisions against the soft "
        "law's contact time, the approach speeds) into the run's statistics, diagnosis_* (docs/hard-engine.md); the "
        "results are the same bits");
    const CommandLine line = parse_options(args, options);
    const po::variables_map& vm = line.vm;
    if (vm.count("help")) {
      std::cout << options << "\n";
      describe_scenario_keys(std::cout);
      return 0;
    }
    const ScenarioRequest request = scenario_request(line, command);
    apply_execution_options(vm);
    return run_command(request, required_option(vm, "model", command), vm["db"].as<std::string>(), snapshot_request(vm),
                       isatty(STDERR_FILENO) != 0, checkpoint_interval(vm), vm.count("diagnose-events") > 0);
  }
  if (command == "compare") {
    po::options_description options("pdamp compare --scenario FILE [options]");
    options.add(help).add(scenario_options()).add(duration_option()).add(db_option()).add(snapshot_options());
    options.add(checkpoint_option()).add(execution_options());
    const CommandLine line = parse_options(args, options);
    const po::variables_map& vm = line.vm;
    if (vm.count("help")) {
      std::cout << options << "\n";
      return 0;
    }
    const ScenarioRequest request = scenario_request(line, command);
    apply_execution_options(vm);
    return compare_command(request, vm["db"].as<std::string>(), snapshot_request(vm), isatty(STDERR_FILENO) != 0,
                           checkpoint_interval(vm));
  }
  if (command == "runs") {
    po::options_description options("pdamp runs [--db FILE]");
    options.add(help).add(db_option());
    const po::variables_map vm = parse_options(args, options).vm;
    if (vm.count("help")) {
      std::cout << options << "\n";
      return 0;
    }
    return list_runs_command(vm["db"].as<std::string>());
  }
  if (command == "resume") {
    po::options_description options("pdamp resume RUN_ID [--until T] [--db FILE]");
    options.add(help).add(db_option()).add(checkpoint_option()).add(execution_options());
    options.add_options()("RUN_ID", po::value<std::string>(), "run to continue")(
        "until", po::value<std::string>()->value_name("T"),
        "simulated time to run to (s), beyond the run's end: extends a completed run; the result is the same bits "
        "as a run of that duration");
    po::positional_options_description positional;
    positional.add("RUN_ID", 1);
    po::options_description accepted;  // the snapshot options only to refuse them with the reason
    accepted.add(options).add(snapshot_options());
    const po::variables_map vm = parse_options(args, accepted, positional).vm;
    if (vm.count("help")) {
      std::cout << options << "\n";
      return 0;
    }
    if (vm.count("snapshots") || vm.count("snapshot-dir")) {
      throw InputError(std::string("pdamp resume takes no --") +
                       (vm.count("snapshots") ? "snapshots" : "snapshot-dir") +
                       ": a resumed run continues the snapshots it was started with, at their interval and in their "
                       "folder (where the frames up to its checkpoint are, which its .pvd lists), and a run started "
                       "without takes none (docs/checkpoints.md)");
    }
    const std::string run_id = required_option(vm, "RUN_ID", command);
    const std::optional<double> until =
        vm.count("until") ? std::optional(parse_seconds(vm["until"].as<std::string>(), 0.0, false, 1e9, "--until"))
                          : std::nullopt;
    apply_execution_options(vm);
    return resume_command(run_id, until, vm["db"].as<std::string>(), isatty(STDERR_FILENO) != 0,
                          checkpoint_interval(vm));
  }
  if (command == "show") {
    po::options_description options("pdamp show RUN_ID [--db FILE]");
    options.add(help).add(db_option());
    options.add_options()("RUN_ID", po::value<std::string>(), "run to show");
    po::positional_options_description positional;
    positional.add("RUN_ID", 1);
    const po::variables_map vm = parse_options(args, options, positional).vm;
    if (vm.count("help")) {
      std::cout << options << "\n";
      return 0;
    }
    return show_run_command(required_option(vm, "RUN_ID", command), vm["db"].as<std::string>());
  }
  if (command == "delete") {
    po::options_description options("pdamp delete RUN_ID... [--db FILE] [--force]");
    options.add(help).add(db_option());
    options.add_options()("RUN_ID", po::value<std::vector<std::string>>(), "runs to delete")(
        "force", "also delete runs marked running (killed runs stay so; a run still going then fails)");
    po::positional_options_description positional;
    positional.add("RUN_ID", -1);
    const po::variables_map vm = parse_options(args, options, positional).vm;
    if (vm.count("help")) {
      std::cout << options << "\n";
      return 0;
    }
    if (!vm.count("RUN_ID")) throw InputError("pdamp delete: give the RUN_IDs to delete (see 'pdamp runs')");
    return delete_runs_command(vm["RUN_ID"].as<std::vector<std::string>>(), vm["db"].as<std::string>(),
                               vm.count("force") > 0);
  }
  if (command == "check") {
    po::options_description options("pdamp check --scenario FILE [--set k=v ...]");
    options.add(help).add(scenario_options());
    const CommandLine line = parse_options(args, options);
    if (line.vm.count("help")) {
      std::cout << options << "\n";
      return 0;
    }
    return check_command(scenario_request(line, command));
  }
  if (command == "rom") return rom_command(args);
  if (command == "study") return study_command(args);
  if (command == "keys") {
    if (!args.empty()) throw InputError("pdamp keys takes no arguments, not '" + printable(args[0]) + "'");
    describe_scenario_keys(std::cout);
    return 0;
  }
  throw InputError("unknown command '" + command + "'\n\n" + usage);
}

/// The command's exit code, or 1 if its results could not all be written to stdout (a
/// full disk behind `> file`): a truncated output must not pass for a complete one.
int with_output_written(int code) {
  std::cout.flush();
  if (std::cout) return code;
  std::cerr << "pdamp: error: the output could not be written to stdout: " << std::strerror(errno) << "\n";
  return code == 0 ? 1 : code;
}

int run_command_line(const std::vector<std::string>& all) {
  if (all.empty() || all[0] == "--help" || all[0] == "-h" || all[0] == "help") {
    std::cout << usage;
    return all.empty() ? 2 : 0;
  }
  if (all[0] == "--version") {
    if (all.size() > 1) throw InputError("--version takes no arguments, not '" + printable(all[1]) + "'");
    std::cout << "pdamp " << version_string << "\n";
    return 0;
  }
  return dispatch(all[0], {all.begin() + 1, all.end()});
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return with_output_written(run_command_line({argv + 1, argv + argc}));
  } catch (const InputError& e) {
    std::cerr << "pdamp: " << e.what() << "\n";
    return 2;
  } catch (const Interrupted& e) {
    std::cerr << "pdamp: " << e.what() << "\n";
    return 128 + stop_signal_received();
  } catch (const std::exception& e) {
    std::cerr << "pdamp: error: " << e.what() << "\n";
    return 1;
  }
}
