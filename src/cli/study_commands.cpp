#include "study_commands.hpp"

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <numbers>
#include <sstream>

#include "commands.hpp"
#include "options.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/store/process_lease.hpp"
#include "pdamp/store/study_store.hpp"
#include "pdamp/study/point_runner.hpp"
#include "pdamp/study/study_runner.hpp"
#include "slurm_commands.hpp"
#include "study_progress.hpp"
#include "subcommand.hpp"
#include "text_table.hpp"

namespace po = boost::program_options;

namespace pdamp {
namespace {

using namespace study;

constexpr const char* study_usage =
    "usage: pdamp study <command> [options]\n"
    "\n"
    "commands:\n"
    "  run STUDY.ini [--jobs N] [--threads N] [--snapshots EVERY_S [--snapshot-dir DIR]] [--checkpoint-every S]\n"
    "          [--take-over HOST] [--force] [--db FILE]\n"
    "          validate every point, store the study, run its points N at a time; running an\n"
    "          unchanged study again resumes it (completed points are kept)\n"
    "  resume STUDY_ID [--jobs N] [--threads N] [--snapshots EVERY_S [--snapshot-dir DIR]] [--checkpoint-every S]\n"
    "          [--take-over HOST] [--db FILE]\n"
    "          run the points of a stored study that are not completed; --take-over HOST also\n"
    "          those left running by processes on another host HOST that runs them no more\n"
    "  list [--db FILE]                  the stored studies\n"
    "  show STUDY_ID [--db FILE]         every point of a study: values, status, metrics\n"
    "  plot STUDY_ID [--metric M] [--x KEY] [--out FILE.png] [--db FILE]\n"
    "          draw a metric against a swept key, one curve per model (python3-matplotlib); an\n"
    "          [frf] study: amplitude and phase against frequency, m_app and c_eq against Gamma;\n"
    "          a [characterise] study: m_app/m_p and c_eq/(m_p w) against Gamma, a curve per frequency\n"
    "  run-point STUDY_ID POINT [--threads N] [--db FILE]\n"
    "          run one point of a stored study in this process (what each worker runs)\n"
    "  submit STUDY.ini --slurm [--partition P] [--account A] [--time T] [--max-parallel K]\n"
    "         [--threads N] [--scratch DIR] [--force] [--dry-run] [--db FILE]\n"
    "  submit --resume STUDY_ID --slurm [options]\n"
    "          run the study's points on a Slurm cluster: a job array, one task per point, each\n"
    "          writing a shard store of its own; --resume submits the points missing or failed\n"
    "  collect STUDY_ID [--db FILE]      merge the finished shard stores into the store\n"
    "  status STUDY_ID [--db FILE]       each point as the store, the shards and Slurm tell\n"
    "  task SHARD_FOLDER --job J --task T [--threads N] [--scratch DIR]\n"
    "          run one task of a job array into its shard store (what the job script runs)\n"
    "\n"
    "A study file names a base scenario, the model(s) and [sweep] sections of scenario keys and\n"
    "their values (data/studies/table4.ini), [frf] sections of stepped-sine frequency\n"
    "responses (data/studies/table1_frf.ini), or [characterise] sections driving the damper's\n"
    "container over a grid of amplitude and frequency (data/studies/table1_characterise.ini).\n";

/// The point's message and, if its process is gone, how to run it again.
void point_messages(const StudyPointState& p, std::int64_t id, std::vector<std::string>& messages) {
  if (!p.message.empty()) messages.push_back("point " + std::to_string(p.point) + ": " + p.message);
  if (!p.lease) return;
  const std::string process = std::to_string(p.lease->pid) + " on " + p.lease->host;
  const std::string resume = "'pdamp study resume " + std::to_string(id);
  if (!lease_is_alive(*p.lease)) {
    messages.push_back("point " + std::to_string(p.point) + ": its process (" + process + ") is gone; " + resume +
                       "' runs it again");
  } else if (p.lease->host != this_host_name()) {
    messages.push_back("point " + std::to_string(p.point) + ": its process (" + process +
                       ") cannot be checked from here; if it runs there no more, " + resume + " --take-over " +
                       p.lease->host + "' runs it again");
  }
}

/// A frequency-response study's points: one line each, on its curve, with its metrics (and
/// its curve's grid values, where the study has a grid).
void print_frf_points(StudyStore& studies, std::int64_t id, std::ostream& out) {
  const auto rows = studies.frf_points(id);
  const bool grid = std::any_of(rows.begin(), rows.end(), [](const auto& f) { return !f.place.grid.empty(); });
  std::vector<TextTable::Column> columns{
      {"point", true},     {"curve", true},      {"model"},           {"dir"},
      {"level", true},     {"f_Hz", true},       {"status"},          {"settled"},
      {"cycles", true},    {"X_norm", true},     {"phase_rad", true}, {"Gamma", true},
      {"m_app/m_p", true}, {"c_eq_N_s_m", true}, {"eta", true},       {"wall_s", true}};
  if (grid) columns.push_back({"grid"});
  TextTable table(columns);
  std::vector<std::string> messages;
  const auto states = studies.points(id);
  for (const auto& f : rows) {
    std::vector<std::string> row{std::to_string(f.point),
                                 std::to_string(f.place.curve),
                                 f.place.model + (f.place.host_alone ? " alone" : ""),
                                 f.place.direction,
                                 format_number(f.place.level),
                                 format_number(f.place.frequency_hz),
                                 f.status};
    if (const auto& r = f.result) {
      const ResponseMetrics& m = r->metrics;
      const std::optional<double> ratio =
          r->particle_mass_kg > 0 ? std::optional(m.apparent_mass_kg / r->particle_mass_kg) : std::nullopt;
      row.insert(row.end(),
                 {m.settled ? "yes" : "no", std::to_string(r->cycles_run), format_number(m.normalised_amplitude),
                  format_number(m.phase_rad, 3), format_optional(m.gamma, 3), format_optional(ratio, 3),
                  format_number(m.equivalent_damping_N_s_m, 3), format_number(m.loss_factor, 3),
                  format_number(r->wall_time_s, 3)});
    } else {
      row.resize(16, "-");
    }
    if (grid) row.push_back(f.place.grid);
    table.add_row(row);
    point_messages(states.at(static_cast<std::size_t>(f.point - 1)), id, messages);
  }
  table.print(out);
  for (const auto& message : messages) out << printable(message) << "\n";
}

/// A characterisation's points: one line each, on its curve, with its metrics.
void print_characterise_points(StudyStore& studies, std::int64_t id, std::ostream& out) {
  TextTable table({{"point", true},
                   {"curve", true},
                   {"model"},
                   {"A_m", true},
                   {"f_Hz", true},
                   {"status"},
                   {"settled"},
                   {"cycles", true},
                   {"Gamma", true},
                   {"A/L", true},
                   {"m_app/m_p", true},
                   {"c_eq/(m_p w)", true},
                   {"eta", true},
                   {"floor", true},
                   {"lid", true},
                   {"wall_s", true}});
  std::vector<std::string> messages;
  const auto states = studies.points(id);
  for (const auto& c : studies.characterise_points(id)) {
    std::vector<std::string> row{std::to_string(c.point),
                                 std::to_string(c.place.curve),
                                 c.place.model + (c.place.empty ? " empty" : ""),
                                 format_number(c.place.amplitude_m),
                                 format_number(c.place.frequency_hz),
                                 c.status};
    if (const auto& r = c.result) {
      const CharacterisationMetrics& m = r->metrics;
      const double m_p = r->particle_mass_kg;
      const double omega_rad_s = 2.0 * std::numbers::pi * c.place.frequency_hz;
      auto ratio = [&](double x, double by) { return m_p > 0 ? std::optional(x / by) : std::nullopt; };
      row.insert(row.end(), {m.settled ? "yes" : "no", std::to_string(r->cycles_run), format_optional(m.gamma, 3),
                             format_number(m.amplitude_m / r->free_height_m, 3),
                             format_optional(ratio(m.apparent_mass_kg, m_p), 3),
                             format_optional(ratio(m.equivalent_damping_N_s_m, m_p * omega_rad_s), 3),
                             format_number(m.loss_factor, 3), format_number(m.floor_contact_fraction, 2),
                             format_number(m.lid_contact_fraction, 2), format_number(r->wall_time_s, 3)});
    } else {
      row.resize(16, "-");
    }
    table.add_row(row);
    point_messages(states.at(static_cast<std::size_t>(c.point - 1)), id, messages);
  }
  table.print(out);
  for (const auto& message : messages) out << printable(message) << "\n";
}

/// How the files a stored study was read from stand now: "" while they still describe it,
/// else why what is shown (the stored definition, which its points run) is not theirs.
std::string files_note(const Study& stored) {
  const auto& source = stored.source;
  if (!std::filesystem::exists(source.study_path) || !std::filesystem::exists(source.scenario_path)) {
    return " (gone; the study is shown as stored)";
  }
  try {
    const auto differences = study_differences(stored, make_study(read_study_source(source.study_path), true));
    if (differences.empty()) return "";
    return " (now another study: " + differences.front() + (differences.size() > 1 ? "; ..." : "") +
           "; the study is shown as stored)";
  } catch (const InputError&) {
    return " (unreadable now; the study is shown as stored)";
  }
}

void print_study(StudyStore& studies, std::int64_t id, const Study& study, std::ostream& out) {
  const auto summary = studies.summary(id);
  out << "study " << id << " '" << printable(study.file.name) << "': models " << to_string(study.file.models) << ", "
      << summary->n_points << " points (" << summary->completed << " completed, " << summary->failed << " failed, "
      << summary->interrupted << " interrupted, " << summary->running << " running, " << summary->pending
      << " pending)\n  study file     " << printable(study.source.study_path.string() + files_note(study))
      << "\n  base scenario  " << printable(study.source.scenario_path.string()) << "\n";
  if (!study.file.frfs.empty()) {
    print_frf_points(studies, id, out);
    return;
  }
  if (!study.file.characterisations.empty()) {
    print_characterise_points(studies, id, out);
    return;
  }
  std::map<int, std::vector<PointMetrics>> metrics;
  for (auto& m : studies.metrics(id)) metrics[m.point].push_back(std::move(m));
  TextTable table({{"point", true},
                   {"section"},
                   {"status"},
                   {"model"},
                   {"run", true},
                   {"psi_peak", true},
                   {"at_Gamma", true},
                   {"dissipated_J", true},
                   {"final_A_m", true},
                   {"balance", true},
                   {"wall_s", true},
                   {"hard/soft", true},
                   {"values"}});
  std::vector<std::string> messages;
  for (const auto& p : studies.points(id)) {
    const StudyPoint& point = study.points.at(static_cast<std::size_t>(p.point - 1));
    const std::vector<std::string> head{std::to_string(p.point), point.section, std::string(to_string(p.status))};
    if (p.status != PointStatus::completed) {
      auto row = head;
      row.resize(12, "-");
      row.push_back(describe_values(point));
      table.add_row(row);
      point_messages(p, id, messages);
      continue;
    }
    for (const auto& m : metrics[p.point]) {
      // models = both: the hard model's dissipated energy over the soft model's.
      const std::optional<double> ratio =
          m.model == "hard" && m.dissipated_rel_diff ? std::optional(1.0 + *m.dissipated_rel_diff) : std::nullopt;
      auto row = head;
      row.insert(row.end(), {m.model, std::to_string(m.run_id), format_optional(m.psi_peak, 3),
                             format_optional(m.psi_peak_gamma, 3),
                             format_number(m.dissipated_impact_J + m.dissipated_friction_J + m.dissipated_viscous_J),
                             format_optional(m.final_amplitude_m, 3), format_number(m.energy_balance_rel_err, 2),
                             format_number(m.wall_time_s, 3), format_optional(ratio, 3), describe_values(point)});
      table.add_row(row);
    }
  }
  table.print(out);
  for (const auto& message : messages) out << printable(message) << "\n";
}

/// Soft-engine threads per worker: the cores (or OMP_NUM_THREADS) shared among the jobs.
int threads_per_worker(const po::variables_map& vm, int jobs) {
  if (vm.count("threads")) {
    return static_cast<int>(parse_whole_number(vm["threads"].as<std::string>(), 1, 1024, "--threads"));
  }
  return std::max(1, omp_get_max_threads() / jobs);
}

/// The options of the commands that run a study's points.
void add_run_options(Subcommand& command) {
  command.add_options()("jobs,j", po::value<std::string>()->default_value("1"),
                        "points run at once, each in its own process")(
      "threads", po::value<std::string>(),
      "soft-engine threads per point (default: the cores shared among the jobs); results are the same bits for any "
      "number")("take-over", po::value<std::string>(),
                "HOST: points left running by processes on another host HOST (which cannot be checked from here) are "
                "run again; say it only when no process there runs the study any more");
  command.add(snapshot_options());
  command.add(checkpoint_option());
}

/// The runner's options from the command line, checked before the store is touched.
StudyRunOptions runner_options(const po::variables_map& vm) {
  StudyRunOptions options;
  options.jobs = static_cast<int>(parse_whole_number(vm["jobs"].as<std::string>(), 1, 256, "--jobs"));
  options.threads_per_worker = threads_per_worker(vm, options.jobs);
  options.db = vm["db"].as<std::string>();
  checkpoint_interval(vm);  // checked here, before the store is touched
  options.worker = {"/proc/self/exe",
                    {"study", "run-point", "--checkpoint-every", vm["checkpoint-every"].as<std::string>()}};
  if (const auto snapshots = snapshot_request(vm)) {
    // Each worker writes its runs' snapshots where this process would have.
    options.worker.arguments.insert(options.worker.arguments.end(),
                                    {"--snapshots", vm["snapshots"].as<std::string>(), "--snapshot-dir",
                                     std::filesystem::absolute(snapshots->directory).string()});
  }
  options.stop = stop_flag();
  if (vm.count("take-over")) {
    options.take_over_host = vm["take-over"].as<std::string>();
    if (options.take_over_host.empty()) {
      throw InputError("--take-over '': give the host whose processes ran the points (as 'pdamp study show' names it)");
    }
    if (options.take_over_host == this_host_name()) {
      throw InputError("--take-over " + printable(options.take_over_host) +
                       ": that is this host, whose processes are checked: its points whose process is gone are run "
                       "again without it, and a live one's are not taken over");
    }
  }
  return options;
}

/// The runner's events shown as the study's progress.
StudyEvents events_to(StudyProgress& progress) {
  return {
      [&progress](int point) { progress.started(point); },
      [&progress](int point, double fraction, std::string_view phase) { progress.progressed(point, fraction, phase); },
      [&progress](int point, bool completed) { progress.ended(point, completed); },
      [&progress](const std::string& line) { progress.message(line); },
      [&progress](int queued) { progress.update(queued); }};
}

int run_and_report(RunStore& store, std::int64_t id, const Study& study, StudyRunOptions options) {
  install_stop_handlers();
  StudyStore studies(store);
  const int completed = studies.summary(id)->completed, points = static_cast<int>(study.points.size());
  std::cerr << "pdamp: study " << id << " '" << printable(study.file.name) << "': " << points << " points, "
            << completed << " completed before"
            << (completed == points ? "; nothing to run" : "; up to " + std::to_string(options.jobs) + " at a time")
            << "\n";
  StudyProgress progress(std::cerr, isatty(STDERR_FILENO) != 0, printable(study.file.name), points, completed,
                         options.jobs);
  options.events = events_to(progress);
  const StudyRunReport report = run_study(store, id, options);
  progress.finish();
  print_study(studies, id, study, std::cout);
  for (const auto& problem : report.problems) std::cerr << "pdamp: " << printable(problem) << "\n";
  if (report.stopped) {
    std::cerr << "pdamp: stopped; 'pdamp study resume " << id << "' runs the "
              << report.not_started + report.interrupted << " points left\n";
    return 128 + stop_signal_received();
  }
  return report.completed == points ? 0 : 1;
}

int study_run(const std::vector<std::string>& args) {
  Subcommand command("pdamp study run STUDY.ini [options]", {"STUDY.ini"});
  add_run_options(command);
  const std::string force_help = "run a study of more than " + std::to_string(max_points_without_force) + " points";
  command.add_options()("force", force_help.c_str());
  if (!command.parse(args)) return 0;
  const auto& vm = command.vm();
  // Everything that can be wrong with the study is found before the store is touched.
  const StudyRunOptions runner = runner_options(vm);
  Study study = make_study(read_study_source(required_option(vm, "STUDY.ini", "study run")), vm.count("force") > 0);
  validate_study(study, snapshot_request(vm));
  RunStore store(vm["db"].as<std::string>());
  const std::int64_t id = find_or_create_study(store, study);
  // Reported as stored, which is what the points run: a study found by its name may have
  // been read from another path, or with equal values written otherwise.
  return run_and_report(store, id, stored_study(*StudyStore(store).study(id)), runner);
}

int study_resume(const std::vector<std::string>& args) {
  Subcommand command("pdamp study resume STUDY_ID [options]", {"STUDY_ID"});
  add_run_options(command);
  if (!command.parse(args)) return 0;
  const StudyRunOptions runner = runner_options(command.vm());
  OpenStudy open(command.vm(), "study resume", StoreAccess::modify);
  check_study_files(open);
  if (const auto snapshots = snapshot_request(command.vm())) validate_study(open.study, snapshots);
  return run_and_report(open.store, open.id, open.study, runner);
}

int study_run_point(const std::vector<std::string>& args) {
  Subcommand command("pdamp study run-point STUDY_ID POINT [options]", {"STUDY_ID", "POINT"});
  command.add_options()("threads", po::value<std::string>(), "soft-engine threads")(
      "report-progress", "progress lines on stdout for the study runner");
  command.add(snapshot_options());
  command.add(checkpoint_option());
  if (!command.parse(args)) return 0;
  const auto& vm = command.vm();
  const auto point =
      static_cast<int>(parse_whole_number(required_option(vm, "POINT", "study run-point"), 1, 1'000'000, "POINT"));
  if (vm.count("threads")) set_thread_count(vm["threads"].as<std::string>());
  OpenStudy open(vm, "study run-point", StoreAccess::modify);

  install_stop_handlers();
  PointRunControl control;
  control.stop = stop_flag();
  control.warn = [](const std::string& warning) { std::cerr << "pdamp: warning: " << warning << "\n"; };
  control.snapshots = snapshot_request(vm);
  control.checkpoint_interval = checkpoint_interval(vm);
  if (vm.count("report-progress")) {
    std::signal(SIGPIPE, SIG_IGN);  // a runner that is gone must not kill the point before it is stored
    control.progress = [](double fraction, std::string_view phase) {
      std::fputs(progress_line(fraction, phase).c_str(), stdout);
      std::fflush(stdout);
    };
  }
  const PointResult result = run_study_point(open.store, open.id, open.study, point, control);
  switch (result.status) {
    case PointStatus::completed:
      if (!vm.count("report-progress")) std::cout << "study " << open.id << " point " << point << ": completed\n";
      return 0;
    case PointStatus::pending:
      std::cerr << "pdamp: " << result.message << "; not run here\n";
      return exit_point_not_claimed;
    case PointStatus::interrupted:
      std::cerr << "pdamp: point " << point << " interrupted: " << result.message << "\n";
      return 128 + stop_signal_received();
    default:
      std::cerr << "pdamp: point " << point << " failed: " << result.message << "\n";
      return 1;
  }
}

int study_list(const std::vector<std::string>& args) {
  Subcommand command("pdamp study list [--db FILE]", {});
  if (!command.parse(args)) return 0;
  RunStore store(command.vm()["db"].as<std::string>(), StoreAccess::read);
  TextTable table({{"study", true},
                   {"name", false, 40},
                   {"models"},
                   {"points", true},
                   {"completed", true},
                   {"failed", true},
                   {"interrupted", true},
                   {"running", true},
                   {"pending", true},
                   {"created"}});
  for (const auto& s : StudyStore(store).list_studies()) {
    table.add_row({std::to_string(s.study_id), s.name, s.models, std::to_string(s.n_points),
                   std::to_string(s.completed), std::to_string(s.failed), std::to_string(s.interrupted),
                   std::to_string(s.running), std::to_string(s.pending), s.created_at});
  }
  table.print(std::cout);
  return 0;
}

int study_show(const std::vector<std::string>& args) {
  Subcommand command("pdamp study show STUDY_ID [--db FILE]", {"STUDY_ID"});
  if (!command.parse(args)) return 0;
  OpenStudy open(command.vm(), "study show", StoreAccess::read);
  print_study(open.studies, open.id, open.study, std::cout);
  return 0;
}

int study_plot(const std::vector<std::string>& args) {
  Subcommand command("pdamp study plot STUDY_ID [options]", {"STUDY_ID"});
  command.add_options()("metric", po::value<std::string>()->default_value("psi_peak"),
                        "a column of the study_results view: psi_peak, psi_peak_gamma, dissipated_total_J, "
                        "dissipated_impact_J, dissipated_friction_J, dissipated_viscous_J, final_amplitude_m, cycles, "
                        "energy_balance_rel_err, wall_time_s")(
      "x", po::value<std::string>(), "the swept key on the x axis (default: the one with the most values)")(
      "out", po::value<std::string>(), "the picture (default: study-ID.png)");
  if (!command.parse(args)) return 0;
  const auto& vm = command.vm();
  if (vm.count("out")) {
    const std::filesystem::path out = vm["out"].as<std::string>();
    const std::string extension = out.extension().string();
    if (extension != ".png" && extension != ".svg" && extension != ".pdf") {
      throw InputError("--out '" + out.string() + "': name the picture .png, .svg or .pdf");
    }
    check_writable_output(out, "--out");
  }
  const OpenStudy open(vm, "study plot", StoreAccess::read);
  const std::int64_t id = open.id;
  const bool frf = !open.study.file.frfs.empty();
  const bool characterisation = !open.study.file.characterisations.empty();
  if ((frf || characterisation) && (!vm["metric"].defaulted() || vm.count("x"))) {
    throw InputError("--metric and --x are for [sweep] studies; study " + std::to_string(id) +
                     (frf ? " is a frequency response, drawn as its amplitude, phase, m_app and c_eq"
                          : " is a characterisation, drawn as m_app/m_p and c_eq/(m_p w) against Gamma"));
  }
  const std::string db = vm["db"].as<std::string>();
  const std::filesystem::path script =
      std::filesystem::path(PDAMP_TOOLS_DIR) / (frf                ? "plot_frf.py"
                                                : characterisation ? "plot_characterisation.py"
                                                                   : "plot_study.py");
  if (!std::filesystem::exists(script)) {
    throw RuntimeFailure("the plotting script '" + script.string() + "' is missing (it comes with pdamp's sources)");
  }
  std::vector<std::string> python{"/usr/bin/python3", script.string(), "--db", db, "--study", std::to_string(id)};
  if (!frf && !characterisation) python.insert(python.end(), {"--metric", vm["metric"].as<std::string>()});
  if (vm.count("x")) python.insert(python.end(), {"--x", vm["x"].as<std::string>()});
  if (vm.count("out")) python.insert(python.end(), {"--out", vm["out"].as<std::string>()});
  std::vector<char*> argv;
  argv.reserve(python.size() + 1);
  for (auto& a : python) argv.push_back(a.data());
  argv.push_back(nullptr);
  execv(argv[0], argv.data());
  throw RuntimeFailure(
      "cannot run /usr/bin/python3 for the plot; install Debian's python3-matplotlib "
      "(tools/setup.sh python3-matplotlib)");
}

}  // namespace

void check_study_files(OpenStudy& open) {
  const auto& source = open.study.source;
  if (std::filesystem::exists(source.study_path) && std::filesystem::exists(source.scenario_path)) {
    // Compared with this study only: what the file holds now is never stored from here.
    check_same_study(open.study, make_study(read_study_source(source.study_path), true),
                     "study " + std::to_string(open.id) + " ('" + open.study.file.name + "' in '" +
                         open.store.file().string() + "'): its study file '" + source.study_path.string() +
                         "' now describes another study:",
                     "restore the file to resume the study, or move it away to resume from the definition stored "
                     "with the study; 'pdamp study run' stores the file's study as a study of its own");
  } else {
    std::cerr << "pdamp: the study's files are gone; resuming from the definition stored with it\n";
  }
}

int study_command(const std::vector<std::string>& args) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::cout << study_usage;
    return args.empty() ? 2 : 0;
  }
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (args[0] == "run") return study_run(rest);
  if (args[0] == "resume") return study_resume(rest);
  if (args[0] == "run-point") return study_run_point(rest);
  if (args[0] == "list") return study_list(rest);
  if (args[0] == "show") return study_show(rest);
  if (args[0] == "plot") return study_plot(rest);
  if (args[0] == "submit") return study_submit(rest);
  if (args[0] == "collect") return study_collect(rest);
  if (args[0] == "status") return study_status(rest);
  if (args[0] == "task") return study_task(rest);
  throw InputError("unknown study command '" + args[0] + "'\n\n" + study_usage);
}

}  // namespace pdamp
