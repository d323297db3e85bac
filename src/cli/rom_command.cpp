#include "rom_command.hpp"

#include <boost/program_options.hpp>
#include <chrono>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "options.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/rom/prediction_files.hpp"
#include "pdamp/rom/table_files.hpp"
#include "pdamp/store/study_store.hpp"
#include "subcommand.hpp"
#include "text_table.hpp"

namespace po = boost::program_options;

namespace pdamp {
namespace {

using Clock = std::chrono::steady_clock;

double milliseconds_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

po::options_description rom_options() {
  po::options_description table("damper table");
  table.add_options()("table", po::value<std::string>(), "damper table file, .csv or .json (docs/rom.md, Table files)")(
      "study", po::value<std::string>(), "or the table of a completed [characterise] study in the store")(
      "model", po::value<std::string>(), "the study's model, soft or hard (needed if it ran both)")(
      "section", po::value<std::string>(),
      "the study's [characterise.NAME] section, one bed (needed if it has several)")(
      "db", po::value<std::string>()->default_value("pdamp.sqlite"), "the store of --study")(
      "export-table", po::value<std::vector<std::string>>()->composing(),
      "write the table as FILE.csv or FILE.json (repeatable)");
  po::options_description host("host (single degree of freedom) and excitation");
  host.add_options()("mass", po::value<double>(), "host mass M without the particles (container included), kg (> 0)")(
      "stiffness", po::value<double>(), "host stiffness K, N/m (> 0)")(
      "damping", po::value<double>()->default_value(0.0), "host damping C, N s/m (>= 0)")(
      "force", po::value<double>(), "force excitation amplitude F0 on the host, N")(
      "base", po::value<double>(), "base excitation: amplitude Y of the base's motion, m")(
      "freq", po::value<std::string>(), "frequencies START:STOP:COUNT in Hz, within the table's frequencies")(
      "spacing", po::value<std::string>()->default_value("linear"), "linear or log spacing of the frequencies");
  po::options_description output("output");
  output.add_options()("out", po::value<std::vector<std::string>>()->composing(),
                       "write the prediction as FILE.csv or FILE.json (repeatable)")("quiet", "no table on stdout")(
      "time", "print the time the prediction took on stderr")("help,h", "show this help");
  po::options_description all(
      "pdamp rom --table FILE|--study ID [--mass M --stiffness K [--damping C] --force F0|--base Y "
      "--freq START:STOP:COUNT] [options]");
  all.add(table).add(host).add(output);
  return all;
}

std::vector<std::string> files(const po::variables_map& vm, const std::string& option) {
  return vm.count(option) ? vm[option].as<std::vector<std::string>>() : std::vector<std::string>{};
}

/// Checked before any work so that a bad name leaves nothing written.
void check_output(const std::filesystem::path& file, const std::string& what) {
  rom::file_format(file, what);
  check_writable_output(file, what);
}

/// The damper table of a completed characterisation: one model and one section (one bed), on
/// its grid of amplitudes and frequencies. Throws InputError naming why a study cannot give one.
rom::DamperTable characterisation_table(const po::variables_map& vm) {
  OpenStudy open(vm["study"].as<std::string>(), vm["db"].as<std::string>(), StoreAccess::read);
  const std::string where = "pdamp rom: study " + std::to_string(open.id) + " '" + open.record.name + "'";
  const auto& sections = open.study.file.characterisations;
  if (sections.empty()) {
    throw InputError(where +
                     " is not a characterisation (it has no [characterise] section); a damper table "
                     "comes from one (docs/characterisation.md)");
  }
  std::set<std::string> models, names;
  for (const auto& p : open.study.points) {
    models.insert(std::string(to_string(p.characterise->model)));
    names.insert(p.section);
  }
  auto list = [](const std::set<std::string>& values) {
    std::string text;
    for (const auto& v : values) text += (text.empty() ? "" : ", ") + v;
    return text;
  };
  auto given = [&](const char* option, const std::set<std::string>& present,
                   const std::string& what) -> std::optional<std::string> {
    if (!vm.count(option)) return std::nullopt;
    const std::string value = vm[option].as<std::string>();
    if (!present.contains(value)) {
      throw InputError(where + ": --" + option + " " + value + ": the study's " + what + " are " + list(present));
    }
    return value;
  };
  const std::optional<std::string> model_given = given("model", models, "models");
  const std::optional<std::string> section_given = given("section", names, "sections");
  // Each section runs its own models: those of the section chosen, the sections of the model.
  auto with = [&](const std::optional<std::string>& model, const std::optional<std::string>& section,
                  bool of_sections) {
    std::set<std::string> values;
    for (const auto& p : open.study.points) {
      const std::string m(to_string(p.characterise->model));
      if ((!model || m == *model) && (!section || p.section == *section)) values.insert(of_sections ? p.section : m);
    }
    return values;
  };
  if (model_given && section_given && with(model_given, section_given, true).empty()) {
    throw InputError(where + ": --section " + *section_given + " and --model " + *model_given + ": [" + *section_given +
                     "] ran no " + *model_given + " points, only " + list(with(std::nullopt, section_given, false)) +
                     " (the sections with " + *model_given + " points are " +
                     list(with(model_given, std::nullopt, true)) + ")");
  }
  auto only = [&](const char* option, const std::set<std::string>& choices, const std::string& what) {
    if (choices.size() > 1) {
      throw InputError(where + " has " + what + " " + list(choices) + ": choose one with --" + option +
                       (std::string(option) == "section" ? " (each section characterises its own bed)" : ""));
    }
    return *choices.begin();
  };
  const std::string model =
      model_given ? *model_given : only("model", with(std::nullopt, section_given, false), "models");
  const std::string section =
      section_given ? *section_given : only("section", with(model, std::nullopt, true), "sections");
  const auto& definition =
      *std::find_if(sections.begin(), sections.end(), [&](const auto& c) { return c.section == section; });
  const bool gammas = definition.axis == study::AmplitudeAxis::gamma;
  rom::DamperTable table;
  table.row_axis = gammas ? rom::RowAxis::gamma : rom::RowAxis::amplitude;
  table.source =
      "study " + std::to_string(open.id) + " '" + open.record.name + "', [" + section + "], " + model + " model";
  std::map<std::pair<double, double>, rom::TablePoint> grid;  // by (frequency, row: A or Γ)
  std::set<double> rows, frequencies;
  int not_completed = 0;
  for (const auto& c : open.studies.characterise_points(open.id)) {
    if (c.place.model != model || open.study.points.at(static_cast<std::size_t>(c.point - 1)).section != section) {
      continue;
    }
    if (!c.result) {
      ++not_completed;
      continue;
    }
    const CharacterisationMetrics& m = c.result->metrics;
    table.bed_mass_kg = c.result->particle_mass_kg;
    table.gravity_m_s2 = c.result->gravity_m_s2;
    const double row = gammas ? c.place.gamma_given.value() : c.place.amplitude_m;
    rows.insert(row);
    frequencies.insert(c.place.frequency_hz);
    grid[{c.place.frequency_hz, row}] = {
        {m.apparent_mass_kg, m.equivalent_damping_N_s_m, m.apparent_mass_spread_kg, m.equivalent_damping_spread_N_s_m},
        m.settled};
  }
  if (not_completed > 0) {
    throw InputError(where + ": " + std::to_string(not_completed) + " of its " + model + " points in [" + section +
                     "] are not completed; run 'pdamp study resume " + std::to_string(open.id) + "' first");
  }
  table.rows.assign(rows.begin(), rows.end());
  table.frequencies_hz.assign(frequencies.begin(), frequencies.end());
  for (const double f : table.frequencies_hz) {
    for (const double row : table.rows) table.points.push_back(grid.at({f, row}));
  }
  rom::validate_damper_table(table, where);
  return table;
}

/// The table the command works on, and its name for messages and file headers: a table file
/// or a stored characterisation.
std::pair<rom::DamperTable, std::string> table_source(const po::variables_map& vm) {
  if (vm.count("table") == vm.count("study")) {
    throw InputError("pdamp rom: give exactly one of --table FILE (.csv or .json) and --study ID (a characterisation)");
  }
  for (const char* option : {"model", "section"}) {
    if (vm.count(option) && !vm.count("study"))
      throw InputError(std::string("pdamp rom: --") + option + " is for --study");
  }
  if (vm.count("study")) {
    return {characterisation_table(vm), vm["db"].as<std::string>() + ", study " + vm["study"].as<std::string>()};
  }
  const std::string file = vm["table"].as<std::string>();
  return {rom::read_damper_table(file), file};
}

bool wants_prediction(const po::variables_map& vm) {
  for (const char* option : {"mass", "stiffness", "force", "base", "freq"}) {
    if (vm.count(option)) return true;
  }
  return false;
}

rom::PredictionSetup prediction_setup(const po::variables_map& vm) {
  for (const char* option : {"mass", "stiffness", "freq"}) {
    if (!vm.count(option)) throw InputError(std::string("pdamp rom: --") + option + " is required to predict");
  }
  if (vm.count("force") == vm.count("base")) {
    throw InputError("pdamp rom: give exactly one of --force F0 (N) and --base Y (m)");
  }
  const std::string spacing = vm["spacing"].as<std::string>();
  if (spacing != "linear" && spacing != "log") {
    throw InputError("pdamp rom: --spacing '" + spacing + "': must be linear or log");
  }
  rom::PredictionSetup setup;
  setup.host = {vm["mass"].as<double>(), vm["stiffness"].as<double>(), vm["damping"].as<double>()};
  const bool force = vm.count("force") > 0;
  setup.excitation = {force ? rom::ExcitationKind::force : rom::ExcitationKind::base,
                      vm[force ? "force" : "base"].as<double>()};
  setup.range = rom::parse_frequency_range(vm["freq"].as<std::string>(),
                                           spacing == "log" ? rom::Spacing::log : rom::Spacing::linear, "--freq");
  rom::validate_host(setup.host, setup.excitation);
  return setup;
}

/// `value` with `digits` significant digits, or `fixed` digits after the point.
std::string digits(double value, int digits, bool fixed = false) {
  std::ostringstream out;
  if (fixed) out << std::fixed;
  out << std::setprecision(digits) << value;
  return out.str();
}

void print_setup(std::ostream& out, const rom::PredictionSetup& setup) {
  const rom::DamperTable& t = *setup.table;
  out << printable("table " + setup.table_name + " (" + t.source + ")") << ": bed mass " << t.bed_mass_kg << " kg, "
      << t.rows.size() << (t.row_axis == rom::RowAxis::gamma ? " gammas " : " amplitudes ") << t.rows.front() << " to "
      << t.rows.back() << (t.row_axis == rom::RowAxis::gamma ? " x " : " m x ") << t.frequencies_hz.size()
      << " frequencies " << t.frequencies_hz.front() << " to " << t.frequencies_hz.back()
      << " Hz\nhost M = " << setup.host.mass_kg << " kg, K = " << setup.host.stiffness_N_m
      << " N/m, C = " << setup.host.damping_N_s_m << " N s/m; " << rom::excitation_text(setup.excitation) << "; "
      << rom::range_text(setup.range) << "\n";
}

/// One row per solution or flagged side; a flagged side has only its frequency and flags.
void print_rows(std::ostream& out, const rom::PredictionSetup& setup, const rom::ResponseCurve& curve) {
  const char* ratio = setup.excitation.kind == rom::ExcitationKind::force ? "|X|K/F0" : "|X|/Y";
  std::vector<TextTable::Column> columns;
  for (const char* header :
       {"f_Hz", "branch", "stability", "|X|_m", ratio, "phase_deg", "Gamma", "m_app_kg", "c_eq_Ns/m", "eta", "sweep"}) {
    columns.push_back({header, true});
  }
  columns.push_back({"flags"});
  TextTable table(columns);
  for (const rom::PredictionRow& row : rom::prediction_rows(setup, curve)) {
    std::vector<std::string> cells = {digits(row.frequency_hz, 5)};
    if (row.solution) {
      const rom::Solution& s = *row.solution;
      const std::string sweep = std::string(s.on_sweep_up ? "u" : "") + (s.on_sweep_down ? "d" : "");
      cells.insert(cells.end(),
                   {std::to_string(s.branch), rom::to_string(s.stability), digits(s.amplitude_m, 4),
                    digits(row.amplitude_ratio, 4), digits(row.phase_deg, 2, true),
                    row.gamma ? digits(*row.gamma, 4) : "-", digits(s.damper.m_app_kg, 4),
                    digits(s.damper.c_eq_N_s_m, 4), digits(row.loss_factor, 4), sweep.empty() ? "-" : sweep});
    }
    cells.resize(columns.size() - 1);
    cells.push_back(rom::flags_text(row));
    table.add_row(cells);
  }
  table.print(out);
}

void print_jumps(std::ostream& out, const char* direction, const std::vector<rom::Jump>& jumps) {
  out << "sweep " << direction << ": " << (jumps.empty() ? "no jump" : std::to_string(jumps.size()) + " jump(s)")
      << "\n";
  for (const rom::Jump& j : jumps) {
    out << "  between " << j.from_frequency_hz << " and " << j.to_frequency_hz << " Hz: |X| "
        << digits(j.from_amplitude_m, 4) << " m (branch " << j.from_branch << ") -> " << digits(j.to_amplitude_m, 4)
        << " m (branch " << j.to_branch << ")\n";
  }
}

/// The prediction for the terminal: what was predicted, the rows, the sweeps' jumps.
void print_prediction(std::ostream& out, const rom::PredictionSetup& setup, const rom::ResponseCurve& curve) {
  print_setup(out, setup);
  print_rows(out, setup, curve);
  print_jumps(out, "up", curve.jumps_up);
  print_jumps(out, "down", curve.jumps_down);
}

}  // namespace

int rom_command(const std::vector<std::string>& args) {
  const po::options_description options = rom_options();
  po::variables_map vm;
  try {
    po::store(po::command_line_parser(args).options(options).style(unabbreviated_style).run(), vm);
  } catch (const po::error& e) {
    throw InputError("pdamp rom: " + std::string(e.what()));
  }
  if (vm.count("help")) {
    std::cout << options << "\nColumns, units and the model: docs/rom.md\n";
    return 0;
  }
  const auto exports = files(vm, "export-table"), outputs = files(vm, "out");
  for (const auto& f : exports) check_output(f, "--export-table");
  for (const auto& f : outputs) check_output(f, "--out");
  const bool predict = wants_prediction(vm);
  if (!predict && exports.empty()) {
    throw InputError(
        "pdamp rom: nothing to do: give a host and an excitation (--mass, --stiffness, --force or --base, --freq) to "
        "predict, or --export-table FILE");
  }
  if (!predict && !outputs.empty()) throw InputError("pdamp rom: --out needs a prediction (a host and --freq)");

  const auto [table, table_name] = table_source(vm);
  const rom::TableInterpolator interpolator(table, table_name);
  std::optional<rom::PredictionSetup> setup;
  rom::ResponseCurve curve;
  if (predict) {
    setup = prediction_setup(vm);
    setup->table_name = table_name;
    setup->table = &interpolator.table();
    const auto frequencies = rom::frequencies_of(setup->range);
    const auto start = Clock::now();
    curve = rom::predict_response(interpolator, setup->host, setup->excitation, frequencies);
    const double elapsed_ms = milliseconds_since(start);
    if (!rom::covers_something(curve)) {
      throw InputError("pdamp rom: the table cannot cover this host and excitation: " + rom::coverage_summary(curve));
    }
    if (vm.count("time")) {
      std::cerr << "pdamp rom: " << frequencies.size() << " frequencies predicted in " << elapsed_ms << " ms\n";
    }
  }

  for (const auto& f : exports) rom::write_text_file(f, rom::damper_table_text(interpolator.table(), f));
  if (setup) {
    for (const auto& f : outputs) rom::write_text_file(f, rom::prediction_text(*setup, curve, f));
    if (!vm.count("quiet")) print_prediction(std::cout, *setup, curve);
  }
  return 0;
}

}  // namespace pdamp
