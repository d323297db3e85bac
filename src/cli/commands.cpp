#include "commands.hpp"

#include <omp.h>

#include <atomic>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "pdamp/compare/comparison.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/sim/engine_factory.hpp"
#include "pdamp/sim/initial_bed.hpp"
#include "pdamp/sim/run.hpp"
#include "pdamp/sim/stored_run.hpp"
#include "pdamp/soft/time_step.hpp"
#include "pdamp/store/run_store.hpp"

namespace pdamp {
namespace {

std::atomic<int> stop_signal{0};
std::atomic<bool> stop_requested{false};

extern "C" void request_stop(int signal_number) {
  stop_signal.store(signal_number);
  stop_requested.store(true);
}

/// SIGINT and SIGTERM end a run cleanly: it keeps what it computed and is marked
/// interrupted. A second signal does the same (the run loop checks often).
void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

void require_existing(const std::filesystem::path& db) {
  if (!std::filesystem::exists(db)) {
    throw InputError("database '" + db.string() + "' does not exist (give the file a run was stored in with --db)");
  }
}

std::string format_optional(const std::optional<double>& value, int precision = 4) {
  if (!value) return "-";
  std::ostringstream out;
  out << std::setprecision(precision) << *value;
  return out.str();
}

void print_summary(RunStore& store, std::int64_t run_id, std::ostream& out) {
  const auto s = store.summary(run_id);
  if (!s) throw InputError("run " + std::to_string(run_id) + " is not in '" + store.database().file().string() + "'");
  out << "run " << s->run_id << ": " << s->model << " model, scenario '" << s->scenario_name << "', " << s->status;
  if (!s->message.empty()) out << " (" << s->message << ")";
  out << "\n  particles               " << s->n_particles << "\n  simulated               " << s->sim_time_s << " s of "
      << s->duration_s << " s\n  wall time               " << format_optional(s->wall_time_s) << " s"
      << "\n  energy balance error    " << format_optional(s->energy_balance_rel_err, 3) << " (max relative)"
      << "\n  dissipated impact       " << format_optional(s->dissipated_impact_J) << " J"
      << "\n  dissipated friction     " << format_optional(s->dissipated_friction_J) << " J"
      << "\n  dissipated viscous      " << format_optional(s->dissipated_viscous_J) << " J"
      << "\n  samples, cycles         " << s->n_samples << ", " << s->n_cycles << "\n";
  for (const auto& [name, value] : store.statistics(run_id)) {
    out << "  " << std::left << std::setw(28) << name << std::right << value << "\n";
  }
  if (s->n_cycles == 0) return;
  sqlite::Statement cycles(store.database(),
                           "SELECT (SELECT freq_hz FROM cycles WHERE run_id = ?1 ORDER BY cycle LIMIT 1), "
                           "(SELECT freq_hz FROM cycles WHERE run_id = ?1 ORDER BY cycle DESC LIMIT 1), "
                           "psi, gamma, cycle FROM cycles WHERE run_id = ?1 ORDER BY psi DESC LIMIT 1");
  cycles.bind(1, run_id);
  if (cycles.step()) {
    out << "  frequency               " << format_optional(cycles.column_double(0)) << " Hz (first cycle), "
        << format_optional(cycles.column_double(1)) << " Hz (last)\n  psi peak                " << std::setprecision(4)
        << cycles.column_double(2) << " in cycle " << cycles.column_int(4) << " (Gamma "
        << format_optional(cycles.column_optional_double(3)) << ")\n";
  }
}

InitialBed prepare_bed(const Scenario& scenario, RunStore& store, bool show_progress) {
  std::function<void(double, double)> progress;
  if (show_progress) {
    progress = [](double t, double kinetic) {
      std::fprintf(stderr, "\r  settling the bed: t = %.3f s, kinetic energy %.3g J   ", t, kinetic);
      std::fflush(stderr);
    };
  }
  InitialBed bed = prepare_initial_bed(scenario, store, &stop_requested, progress);
  if (show_progress && !bed.reused && scenario.particles.count > 0) std::fputs("\n", stderr);
  if (bed.state_id) {
    std::cerr << "pdamp: " << (bed.reused ? "starting from stored" : "settled and stored") << " bed " << *bed.state_id
              << " (" << scenario.particles.count << " spheres at rest after " << bed.settle_time_s
              << " s of settling)\n";
  }
  return bed;
}

RunControl run_control(const Scenario& scenario, bool show_progress) {
  RunControl control;
  control.stop = &stop_requested;
  if (show_progress) {
    control.progress = [duration = scenario.run.duration_s](double t) {
      std::fprintf(stderr, "\r  t = %.4f of %.4f s", t, duration);
      std::fflush(stderr);
    };
  }
  return control;
}

int exit_code(const StoredRun& run) {
  switch (run.outcome.status) {
    case RunStatus::completed:
      return 0;
    case RunStatus::interrupted:
      return 128 + stop_signal.load();
    default:
      break;
  }
  std::cerr << "pdamp: run " << run.run_id << " failed: " << run.outcome.message << "\n";
  return 1;
}

}  // namespace

int run_command(const ScenarioRequest& request, const std::string& model_name, const std::filesystem::path& db,
                bool show_progress) {
  // Everything that can be wrong with the input is found before the store is touched.
  const Model model = parse_model(model_name);
  const Scenario scenario = load_scenario(request.file, request.overrides);
  check_model_can_run(model, scenario);

  RunStore store(db);
  install_stop_handlers();
  const InitialBed bed = prepare_bed(scenario, store, show_progress);
  const StoredRun run =
      run_and_store(store, model, scenario, bed, run_control(scenario, show_progress),
                    [](const std::string& warning) { std::cerr << "pdamp: warning: " << warning << "\n"; });
  if (show_progress) std::fputs("\n", stderr);
  print_summary(store, run.run_id, std::cout);
  return exit_code(run);
}

namespace {

std::string cell(const std::optional<double>& value, int precision = 4) { return format_optional(value, precision); }

void print_comparison(RunStore& store, std::int64_t id, const ComparisonRecord& c, std::ostream& out) {
  auto psi_peak = [&](std::int64_t run) {
    sqlite::Statement q(store.database(), "SELECT psi, gamma FROM cycles WHERE run_id = ? ORDER BY psi DESC LIMIT 1");
    q.bind(1, run);
    return q.step() ? format_optional(q.column_double(0), 3) + " (Gamma " +
                          format_optional(q.column_optional_double(1), 3) + ")"
                    : std::string("-");
  };
  auto row = [&](const std::string& name, const std::string& soft, const std::string& hard,
                 const std::string& note = "") {
    out << "  " << std::left << std::setw(32) << name << std::setw(20) << soft << std::setw(20) << hard << note << "\n";
  };
  const auto energy_end = c.energy.end() - 2;  // the last time: soft then hard
  out << "comparison " << id << ": scenario '" << c.scenario_name << "', soft run " << c.soft_run_id << ", hard run "
      << c.hard_run_id << ", hard restitution " << c.hard_restitution << "\n";
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

int compare_command(const ScenarioRequest& request, const std::filesystem::path& db, bool show_progress) {
  const Scenario scenario = load_scenario(request.file, request.overrides);
  check_model_can_run(Model::soft, scenario);
  check_model_can_run(Model::hard, scenario);

  RunStore store(db);
  install_stop_handlers();
  const InitialBed bed = prepare_bed(scenario, store, show_progress);
  auto warn = [](const std::string& warning) { std::cerr << "pdamp: warning: " << warning << "\n"; };
  const RunControl control = run_control(scenario, show_progress);
  std::int64_t run_ids[2] = {0, 0};
  for (const Model model : {Model::soft, Model::hard}) {
    if (show_progress) std::cerr << "pdamp: " << to_string(model) << " model\n";
    const StoredRun run = run_and_store(store, model, scenario, bed, control, warn);
    if (show_progress) std::fputs("\n", stderr);
    run_ids[model == Model::hard] = run.run_id;
    if (run.outcome.status != RunStatus::completed) {
      print_summary(store, run.run_id, std::cout);
      return exit_code(run);
    }
  }
  ComparisonRecord comparison = compare_stored_runs(store, run_ids[0], run_ids[1]);
  comparison.scenario_name = scenario.name;
  comparison.initial_state_id = bed.state_id;
  comparison.hard_restitution = scenario.hard_restitution == HardRestitution::calibrated ? "calibrated" : "constant";
  const std::int64_t id = store.save_comparison(comparison);
  print_comparison(store, id, comparison, std::cout);
  return 0;
}

int stop_signal_received() { return stop_signal.load(); }

void set_thread_count(const std::string& text) {
  int threads = 0;
  const char* end = text.data() + text.size();
  if (auto [ptr, ec] = std::from_chars(text.data(), end, threads);
      ec != std::errc() || ptr != end || threads < 1 || threads > 1024) {
    throw InputError("--threads '" + text + "': must be a whole number from 1 to 1024");
  }
  omp_set_num_threads(threads);
}

int list_runs_command(const std::filesystem::path& db) {
  require_existing(db);
  RunStore store(db);
  std::cout << std::left << std::setw(7) << "run_id" << std::setw(6) << "model" << std::setw(24) << "scenario"
            << std::setw(12) << "status" << std::right << std::setw(10) << "particles" << std::setw(11) << "sim_s"
            << std::setw(11) << "wall_s" << std::setw(11) << "balance" << std::setw(8) << "cycles"
            << "\n";
  for (const auto& s : store.list_runs()) {
    std::cout << std::left << std::setw(7) << s.run_id << std::setw(6) << s.model << std::setw(24) << s.scenario_name
              << std::setw(12) << s.status << std::right << std::setw(10) << s.n_particles << std::setw(11)
              << std::setprecision(4) << s.sim_time_s << std::setw(11) << format_optional(s.wall_time_s)
              << std::setw(11) << format_optional(s.energy_balance_rel_err, 2) << std::setw(8) << s.n_cycles << "\n";
  }
  return 0;
}

int show_run_command(const std::string& run_id_text, const std::filesystem::path& db) {
  std::int64_t run_id = 0;
  const char* end = run_id_text.data() + run_id_text.size();
  if (auto [ptr, ec] = std::from_chars(run_id_text.data(), end, run_id);
      ec != std::errc() || ptr != end || run_id < 1) {
    throw InputError("RUN_ID '" + run_id_text + "' must be a positive whole number (see 'pdamp runs')");
  }
  require_existing(db);
  RunStore store(db);
  print_summary(store, run_id, std::cout);
  return 0;
}

int check_command(const ScenarioRequest& request) {
  const Scenario scenario = load_scenario(request.file, request.overrides);
  std::cout << "# scenario '" << scenario.name << "' is valid; every key with its resolved value:\n"
            << scenario.canonical_text << "\n";
  if (scenario.particles.count > 0) {
    const double dt = soft::choose_time_step_s(scenario);
    std::cout << "# soft engine time step: " << dt << " s (" << (scenario.run.dt_s ? "given" : "automatic")
              << "); shortest Hertz contact " << soft::shortest_contact_time_s(scenario) << " s at the fastest impact, "
              << soft::max_impact_speed_m_s(scenario) << " m/s; tangential spring period "
              << soft::shortest_tangential_period_s(scenario) << " s\n";
  }
  return 0;
}

}  // namespace pdamp
