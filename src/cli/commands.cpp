#include "commands.hpp"

#include <omp.h>

#include <atomic>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "options.hpp"
#include "pdamp/compare/comparison.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/sim/engine_factory.hpp"
#include "pdamp/sim/initial_bed.hpp"
#include "pdamp/sim/run.hpp"
#include "pdamp/sim/stored_run.hpp"
#include "pdamp/store/run_store.hpp"
#include "pdamp/store/study_store.hpp"
#include "progress.hpp"
#include "text_table.hpp"

namespace pdamp {
namespace {

std::atomic<int> stop_signal{0};
std::atomic<bool> stop_requested{false};

extern "C" void request_stop(int signal_number) {
  stop_signal.store(signal_number);
  stop_requested.store(true);
}

/// A run's status, with the host of a run running on another one (whose process cannot
/// be checked from here).
std::string status_text(const RunSummary& s) {
  if (s.status == "running" && s.lease && s.lease->host != this_host_name()) return "running on " + s.lease->host;
  return s.status;
}

void print_summary(RunStore& store, std::int64_t run_id, std::ostream& out) {
  const auto s = store.summary(run_id);
  if (!s) throw InputError("run " + std::to_string(run_id) + " is not in '" + store.file().string() + "'");
  out << "run " << s->run_id << ": " << s->model << " model, scenario '" << printable(s->scenario_name) << "', "
      << status_text(*s);
  if (!s->message.empty()) out << " (" << printable(s->message) << ")";
  out << "\n  particles               " << s->n_particles << "\n  simulated               " << s->sim_time_s << " s of "
      << s->duration_s << " s\n  wall time               " << format_optional(s->wall_time_s) << " s"
      << "\n  energy balance error    " << format_optional(s->energy_balance_rel_err, 3) << " (max relative)"
      << "\n  dissipated impact       " << format_optional(s->dissipated_impact_J) << " J"
      << "\n  dissipated friction     " << format_optional(s->dissipated_friction_J) << " J"
      << "\n  dissipated viscous      " << format_optional(s->dissipated_viscous_J) << " J"
      << "\n  samples, cycles         " << s->n_samples << ", " << s->n_cycles << "\n";
  if (const auto snapshots = store.snapshots(run_id)) {
    out << "  snapshots               " << snapshots->frames << " frames every " << snapshots->interval_s
        << " s: " << printable(snapshots->collection) << "\n";
  }
  for (const auto& [name, value] : store.statistics(run_id)) {
    out << "  " << std::left << std::setw(28) << name << std::right << value << "\n";
  }
  if (const auto cycles = store.cycle_overview(run_id)) {
    out << "  frequency               " << format_number(cycles->first_freq_hz) << " Hz (first cycle), "
        << format_number(cycles->last_freq_hz) << " Hz (last)\n  psi peak                "
        << format_number(cycles->psi_peak) << " in cycle " << cycles->psi_peak_cycle << " (Gamma "
        << format_optional(cycles->psi_peak_gamma) << ")\n";
  }
}

/// The bed of a command's runs: settled (or taken from the store) by the first run that
/// needs it, the others start from the same.
class CommandBed {
 public:
  CommandBed(const Scenario& scenario, RunStore& store, Progress& progress)
      : scenario_(scenario), store_(store), progress_(progress) {}
  BedSource source() {
    return [this]() -> const InitialBed& {
      if (!bed_) bed_ = prepare();
      return *bed_;
    };
  }

 private:
  InitialBed prepare() {
    progress_.begin("settling the bed");
    InitialBed bed = prepare_initial_bed(scenario_, store_, &stop_requested, [this](double t, double kinetic) {
      progress_.update(t, "kinetic energy " + format_number(kinetic, 3) + " J");
    });
    progress_.end();
    if (bed.state_id) {
      std::ostringstream note;
      note << "pdamp: " << (bed.reused ? "starting from stored" : "settled and stored") << " bed " << *bed.state_id
           << " (" << scenario_.particles.count << " spheres at rest after " << bed.settle_time_s << " s of settling)";
      progress_.message(note.str());
    }
    return bed;
  }

  const Scenario& scenario_;
  RunStore& store_;
  Progress& progress_;
  std::optional<InitialBed> bed_;
};

/// Stops on SIGINT and SIGTERM; reports progress as the phase `label` of the scenario's
/// duration; checkpoints at `checkpoint_interval`.
RunControl run_control(const Scenario& scenario, Progress& progress, const std::string& label,
                       std::chrono::milliseconds checkpoint_interval) {
  RunControl control;
  control.stop = &stop_requested;
  control.checkpoint_interval = checkpoint_interval;
  control.progress = [&progress, label, duration = scenario.run.duration_s, begun = false](double t) mutable {
    if (!begun) progress.begin(label, duration);
    begun = true;
    progress.update(t);
  };
  return control;
}

std::function<void(const std::string&)> warnings_to(Progress& progress) {
  return [&progress](const std::string& warning) { progress.message("pdamp: warning: " + warning); };
}

std::int64_t parse_run_id(const std::string& text) {
  std::int64_t run_id = 0;
  const char* end = text.data() + text.size();
  if (auto [ptr, ec] = std::from_chars(text.data(), end, run_id); ec != std::errc() || ptr != end || run_id < 1) {
    throw InputError("RUN_ID '" + printable(text) + "' must be a positive whole number (see 'pdamp runs')");
  }
  return run_id;
}

int exit_code(RunStore& store, const StoredRun& run) {
  switch (run.outcome.status) {
    case RunStatus::completed:
      return 0;
    case RunStatus::interrupted: {
      const std::string id = std::to_string(run.run_id);
      const auto checkpoint = store.checkpoint(run.run_id);
      std::cerr << "pdamp: run " << id << " stopped by a signal at t = " << format_number(run.outcome.sim_time_s, 6)
                << " s; "
                << (checkpoint ? "'pdamp resume " + id + "' continues it from its checkpoint at t = " +
                                     format_number(checkpoint->checkpoint.t_s, 6) + " s"
                               : std::string("it has no checkpoint to resume from"))
                << "\n";
      return 128 + stop_signal.load();
    }
    default:
      break;
  }
  std::cerr << "pdamp: run " << run.run_id << " failed: " << run.outcome.message << "\n";
  return 1;
}

}  // namespace

int run_command(const ScenarioRequest& request, const std::string& model_name, const std::filesystem::path& db,
                const std::optional<SnapshotSettings>& snapshots, bool terminal,
                std::chrono::milliseconds checkpoint_interval, bool diagnose_events) {
  // Everything that can be wrong with the input is found before the store is touched.
  const Model model = parse_model(model_name);
  if (diagnose_events && model != Model::hard) {
    throw InputError("--diagnose-events counts the event-driven engine's collisions: it needs --model hard, not '" +
                     model_name + "'");
  }
  const Scenario scenario = load_scenario(request.file, request.overrides);
  const RunPlan plan = plan_run(model, scenario, snapshots, diagnose_events);

  RunStore store(db);
  install_stop_handlers();
  Progress progress(std::cerr, terminal);
  CommandBed bed(scenario, store, progress);
  const StoredRun run =
      run_and_store(store, plan, bed.source(),
                    run_control(scenario, progress, std::string(to_string(model)) + " model", checkpoint_interval),
                    warnings_to(progress));
  progress.end();
  print_summary(store, run.run_id, std::cout);
  return exit_code(store, run);
}

int resume_command(const std::string& run_id_text, std::optional<double> until_s, const std::filesystem::path& db,
                   bool terminal, std::chrono::milliseconds checkpoint_interval) {
  const std::int64_t run_id = parse_run_id(run_id_text);
  RunStore store(db, StoreAccess::modify);
  if (const auto point = StudyStore(store).curve_point_of_run(run_id)) {
    const std::string study = std::to_string(point->study_id);
    throw InputError("run " + std::to_string(run_id) + " is the run of [" + point->section + "] point " +
                     std::to_string(point->point) + " of study " + study +
                     ", which runs cycle by cycle to its steady state: such a run is continued with its point, "
                     "from its checkpoint, by 'pdamp study resume " +
                     study + "'");
  }
  if (const auto comparison = store.comparison_runs(run_id)) {
    if (until_s) {
      throw InputError("run " + std::to_string(run_id) +
                       " is a run of a comparison under way (pdamp compare, soft run " +
                       std::to_string(comparison->soft_run_id) +
                       "): resuming it completes the comparison, to the runs' duration; --until is for a run of "
                       "its own");
    }
    return complete_comparison(store, *comparison, terminal, checkpoint_interval);
  }
  // Where the run will end, for its percentage and time left (a missing run is refused by
  // resume_and_store).
  std::optional<double> end_s = until_s;
  if (const auto summary = store.summary(run_id); summary && !end_s) end_s = summary->duration_s;
  install_stop_handlers();
  Progress progress(std::cerr, terminal);
  RunControl control;
  control.stop = &stop_requested;
  control.checkpoint_interval = checkpoint_interval;
  control.progress = [&progress, end_s, begun = false](double t) mutable {
    if (!begun) progress.begin("resumed run", end_s);
    begun = true;
    progress.update(t);
  };
  const StoredRun run = resume_and_store(store, run_id, until_s, control, warnings_to(progress));
  progress.end();
  print_summary(store, run.run_id, std::cout);
  return exit_code(store, run);
}

namespace {

std::string cell(const std::optional<double>& value, int precision = 4) { return format_optional(value, precision); }

void print_comparison(RunStore& store, std::int64_t id, const ComparisonRecord& c, std::ostream& out) {
  auto psi_peak = [&](std::int64_t run) {
    const auto cycles = store.cycle_overview(run);
    return cycles ? format_number(cycles->psi_peak, 3) + " (Gamma " + format_optional(cycles->psi_peak_gamma, 3) + ")"
                  : std::string("-");
  };
  auto row = [&](const std::string& name, const std::string& soft, const std::string& hard,
                 const std::string& note = "") {
    out << "  " << std::left << std::setw(32) << name << std::setw(20) << soft << std::setw(20) << hard << note << "\n";
  };
  const auto energy_end = c.energy.end() - 2;  // the last time: soft then hard
  out << "comparison " << id << ": scenario '" << printable(c.scenario_name) << "', soft run " << c.soft_run_id
      << ", hard run " << c.hard_run_id << ", hard restitution " << c.hard_restitution << "\n";
  row("", "soft", "hard");
  row("wall time (s)", cell(c.wall_time_soft_s), cell(c.wall_time_hard_s), "soft/hard " + cell(c.wall_time_ratio, 3));
  row("time steps / collisions", std::to_string(c.soft_steps), std::to_string(c.hard_events));
  row("dissipated at t = " + cell(energy_end->t_s) + " s (J)", "", "");
  row("  impact", cell(energy_end->impact_J), cell((energy_end + 1)->impact_J));
  row("  friction", cell(energy_end->friction_J), cell((energy_end + 1)->friction_J));
  row("  viscous", cell(energy_end->viscous_J), cell((energy_end + 1)->viscous_J));
  row("  total", cell(c.dissipated_soft_J), cell(c.dissipated_hard_J),
      "hard vs soft " + cell(c.dissipated_rel_diff, 3));
  row("psi peak (at Gamma)", psi_peak(c.soft_run_id), psi_peak(c.hard_run_id));
  row("frequency once Gamma < 1 (Hz)", cell(c.small_amplitude_freq_soft_hz), cell(c.small_amplitude_freq_hard_hz));
  row("Gamma < 1 from (s)", cell(c.gamma_below_1_soft_s), cell(c.gamma_below_1_hard_s));
  out << "  envelope difference (of the first amplitude): max " << cell(c.envelope_max_rel_diff, 3) << ", rms "
      << cell(c.envelope_rms_rel_diff, 3)
      << "\n  psi(Gamma) mean |difference| over Gamma bins: " << cell(c.psi_mean_abs_diff, 3) << "\n";
}

}  // namespace

namespace {

/// The end of one of a comparison's runs: its snapshots named; the exit code if it did not
/// complete (then the comparison stops there, to be completed by pdamp resume).
std::optional<int> comparison_run_ended(RunStore& store, const StoredRun& run, Progress& progress) {
  progress.end();
  if (const auto written = store.snapshots(run.run_id)) {
    progress.message("pdamp: " + std::to_string(written->frames) + " snapshots of run " + std::to_string(run.run_id) +
                     ": " + printable(written->collection));
  }
  if (run.outcome.status == RunStatus::completed) return std::nullopt;
  print_summary(store, run.run_id, std::cout);
  return exit_code(store, run);
}

int store_and_print_comparison(RunStore& store, const Scenario& scenario, std::optional<std::int64_t> bed_state_id,
                               const std::int64_t (&run_ids)[2]) {
  const auto [id, comparison] = store_comparison(store, scenario, bed_state_id, run_ids[0], run_ids[1]);
  print_comparison(store, id, comparison, std::cout);
  return 0;
}

}  // namespace

int compare_command(const ScenarioRequest& request, const std::filesystem::path& db,
                    const std::optional<SnapshotSettings>& snapshots, bool terminal,
                    std::chrono::milliseconds checkpoint_interval) {
  const Scenario scenario = load_scenario(request.file, request.overrides);
  const RunPlan plans[2] = {plan_run(Model::soft, scenario, snapshots), plan_run(Model::hard, scenario, snapshots)};

  RunStore store(db);
  install_stop_handlers();
  Progress progress(std::cerr, terminal);
  CommandBed bed(scenario, store, progress);
  std::int64_t run_ids[2] = {0, 0};
  for (const RunPlan& plan : plans) {
    const std::string label = std::string(to_string(plan.engine.model)) + " model";
    progress.message("pdamp: " + label);
    const bool hard = plan.engine.model == Model::hard;
    // Recorded as they begin, so that pdamp resume can complete the comparison.
    const auto begun = [&](std::int64_t run_id) {
      run_ids[hard] = run_id;
      store.save_comparison_runs(run_ids[0], hard ? std::optional(run_id) : std::nullopt);
    };
    const StoredRun run =
        run_and_store(store, plan, bed.source(), run_control(scenario, progress, label, checkpoint_interval),
                      warnings_to(progress), begun);
    if (const auto code = comparison_run_ended(store, run, progress)) return *code;
  }
  return store_and_print_comparison(store, scenario, bed.source()().state_id, run_ids);
}

int complete_comparison(RunStore& store, const ComparisonRuns& runs, bool terminal,
                        std::chrono::milliseconds checkpoint_interval) {
  const Scenario scenario =
      parse_scenario(runs.scenario_text, runs.scenario_name, "run " + std::to_string(runs.soft_run_id) + "'s scenario");
  std::int64_t run_ids[2] = {runs.soft_run_id, runs.hard_run_id.value_or(0)};
  // Every refusal before anything changes: each run not completed must be resumable.
  auto completed = [&](std::int64_t run_id) { return store.summary(run_id)->status == "completed"; };
  for (const std::int64_t run_id : run_ids) {
    if (run_id != 0 && !completed(run_id)) store.resumable_run(run_id, std::nullopt);
  }
  // A hard run not begun starts from the soft run's bed, with its snapshot settings.
  std::optional<RunPlan> hard_plan;
  if (!runs.hard_run_id) {
    std::optional<SnapshotSettings> snapshots;
    if (const auto taken = store.snapshots(runs.soft_run_id)) {
      snapshots = SnapshotSettings{taken->interval_s, std::filesystem::path(taken->folder).parent_path()};
    }
    hard_plan = plan_run(Model::hard, scenario, snapshots);
  }
  const InitialBed bed{runs.initial_state_id ? store.load_initial_particles(*runs.initial_state_id) : Particles(0),
                       runs.initial_state_id, true, 0.0};

  install_stop_handlers();
  Progress progress(std::cerr, terminal);
  for (const Model model : {Model::soft, Model::hard}) {
    std::int64_t& run_id = run_ids[model == Model::hard];
    if (run_id != 0 && completed(run_id)) continue;
    const std::string label = std::string(to_string(model)) + " model";
    progress.message("pdamp: " + label + (run_id != 0 ? ", run " + std::to_string(run_id) + " resumed" : ""));
    const RunControl control = run_control(scenario, progress, label, checkpoint_interval);
    const StoredRun run =
        run_id != 0 ? resume_and_store(store, run_id, std::nullopt, control, warnings_to(progress))
                    : run_and_store(
                          store, *hard_plan, [&]() -> const InitialBed& { return bed; }, control, warnings_to(progress),
                          [&](std::int64_t begun) {
                            run_id = begun;
                            store.save_comparison_runs(runs.soft_run_id, begun);
                          });
    if (const auto code = comparison_run_ended(store, run, progress)) return *code;
  }
  return store_and_print_comparison(store, scenario, runs.initial_state_id, run_ids);
}

int stop_signal_received() { return stop_signal.load(); }

const std::atomic<bool>* stop_flag() { return &stop_requested; }

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

void set_thread_count(const std::string& text) {
  omp_set_num_threads(static_cast<int>(parse_whole_number(text, 1, 1024, "--threads")));
}

int list_runs_command(const std::filesystem::path& db) {
  RunStore store(db, StoreAccess::read);
  TextTable table({{"run_id", true},
                   {"model"},
                   {"scenario", false, 40},
                   {"status"},
                   {"particles", true},
                   {"sim_s", true},
                   {"wall_s", true},
                   {"balance", true},
                   {"cycles", true}});
  for (const auto& s : store.list_runs()) {
    table.add_row({std::to_string(s.run_id), s.model, s.scenario_name, status_text(s), std::to_string(s.n_particles),
                   format_number(s.sim_time_s), format_optional(s.wall_time_s),
                   format_optional(s.energy_balance_rel_err, 2), std::to_string(s.n_cycles)});
  }
  table.print(std::cout);
  return 0;
}

int show_run_command(const std::string& run_id_text, const std::filesystem::path& db) {
  const std::int64_t run_id = parse_run_id(run_id_text);
  RunStore store(db, StoreAccess::read);
  print_summary(store, run_id, std::cout);
  return 0;
}

int delete_runs_command(const std::vector<std::string>& run_id_texts, const std::filesystem::path& db, bool force) {
  std::vector<std::int64_t> run_ids;
  run_ids.reserve(run_id_texts.size());
  for (const auto& text : run_id_texts) run_ids.push_back(parse_run_id(text));
  RunStore store(db, StoreAccess::modify);
  for (const DeletedRun& d : store.delete_runs(run_ids, force)) {
    std::cout << "deleted run " << d.run.run_id << ": " << d.run.model << " model, scenario '"
              << printable(d.run.scenario_name) << "', " << d.run.status << " (" << d.run.n_samples << " samples, "
              << d.run.n_cycles << " cycles, " << d.comparisons << (d.comparisons == 1 ? " comparison" : " comparisons")
              << ")\n";
  }
  return 0;
}

int check_command(const ScenarioRequest& request) {
  const Scenario scenario = load_scenario(request.file, request.overrides);
  // What any run needs (samples, observations, settling); the soft model's own steps below.
  check_model_can_run(Model::hard, scenario);
  std::cout << "# scenario '" << scenario.name << "' is valid; every key with its resolved value:\n"
            << scenario.canonical_text << "\n";
  if (scenario.particles.count > 0) {
    for (const EngineKind& kind : engine_kinds()) {
      std::cout << "# " << kind.name << " engine: " << kind.describe(scenario) << "\n";
      try {
        check_model_can_run(kind.model, scenario);
      } catch (const InputError& e) {
        std::cout << "# the " << kind.name << " model cannot run it: " << e.what() << "\n";
      }
    }
  }
  return 0;
}

}  // namespace pdamp
