/// End-to-end tests of `pdamp rom` through the executable: predictions and table exports
/// written only when the input is good, exit code 2 with the reason and nothing written
/// otherwise, and the plot script.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

#include "pdamp/rom/prediction_files.hpp"
#include "pdamp/rom/table_files.hpp"
#include "test_process.hpp"
#include "test_support.hpp"

using namespace pdamp;

namespace {

using Args = std::vector<std::string>;

struct Outcome {
  int code;
  std::string out, err;
};

/// Runs `executable ARGS...`; its stdout and stderr are captured in `capture`, apart from the
/// folder the command writes to.
Outcome run(const std::string& executable, const std::vector<std::string>& args, const test::TempDir& capture) {
  test::Process p(executable, args, capture);
  const int code = p.wait();
  return {code, p.out(), p.err()};
}

Outcome pdamp_rom(std::vector<std::string> args, const test::TempDir& capture) {
  args.insert(args.begin(), "rom");
  return run(PDAMP_EXECUTABLE, args, capture);
}

std::vector<std::string> operator+(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

std::string slurp(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string liftoff() { return (test::source_dir() / "data" / "rom" / "synthetic_liftoff.csv").string(); }

/// The Table 1 host with the experiment's damping.
const std::vector<std::string> host = {"--mass", "0.0376", "--stiffness", "470", "--damping", "0.01"};

int files_in(const test::TempDir& dir) {
  const auto entries = std::filesystem::directory_iterator(dir.path());
  return static_cast<int>(std::distance(begin(entries), end(entries)));
}

/// A prediction CSV's rows as columns by name (the '#' lines skipped).
std::map<std::string, std::vector<std::string>> csv_columns(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> header;
  std::map<std::string, std::vector<std::string>> columns;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::istringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
    if (line.back() == ',') cells.emplace_back();
    if (header.empty()) {
      header = cells;
      continue;
    }
    REQUIRE(cells.size() == header.size());
    for (std::size_t c = 0; c < cells.size(); ++c) columns[header[c]].push_back(cells[c]);
  }
  return columns;
}

}  // namespace

TEST_CASE("pdamp rom on a constant table predicts the linear SDOF closed form through the executable") {
  test::TempDir dir("rom-linear"), capture("rom-linear-io");
  rom::DamperTable table;
  table.source = "constant";
  table.bed_mass_kg = 0.004;
  table.rows = {1e-9, 1e-6, 1e-3, 1.0};
  table.frequencies_hz = {2, 10, 30, 60};
  const double m = 0.004, c = 0.03;
  table.points.assign(16, rom::TablePoint{m, c, 0, 0, true});
  const auto file = dir / "constant.json";
  rom::write_text_file(file, rom::damper_table_json(table));
  const auto out = dir / "p.csv";
  const Outcome r = pdamp_rom(
      Args{"--table", file.string(), "--force", "0.05", "--freq", "2:60:300", "--out", out.string()} + host, capture);
  INFO(r.err);
  REQUIRE(r.code == 0);
  auto columns = csv_columns(slurp(out));
  REQUIRE(columns["frequency_hz"].size() == 300);
  for (std::size_t i = 0; i < 300; ++i) {
    const double f = std::stod(columns["frequency_hz"][i]), omega = 2 * std::numbers::pi * f;
    CAPTURE(f);
    const std::complex<double> x = 0.05 / std::complex<double>(470 - omega * omega * (0.0376 + m), omega * (0.01 + c));
    CHECK(std::abs(std::stod(columns["amplitude_m"][i]) - std::abs(x)) <= 1e-12 * std::abs(x));
    CHECK(std::abs(std::stod(columns["phase_deg"][i]) - std::arg(x) * 180 / std::numbers::pi) <= 1e-9);
    CHECK(columns["stability"][i] == "stable");
    CHECK(columns["flags"][i].empty());
  }
}

TEST_CASE("pdamp rom writes the library's prediction of the lift-off table as CSV, JSON and a terminal table") {
  test::TempDir dir("rom-predict"), capture("rom-predict-io");
  const Outcome r = pdamp_rom(Args{"--table", liftoff(), "--force", "0.05", "--freq", "14:22:201", "--out",
                                   (dir / "p.csv").string(), "--out", (dir / "p.json").string(), "--time"} +
                                  host,
                              capture);
  INFO(r.err);
  REQUIRE(r.code == 0);

  // The files hold what the library predicts for the same setup, to the byte.
  const rom::TableInterpolator table(rom::read_damper_table(liftoff()), liftoff());
  rom::PredictionSetup setup;
  setup.table_name = liftoff();
  setup.table = &table.table();
  setup.host = {0.0376, 470, 0.01};
  setup.excitation = {rom::ExcitationKind::force, 0.05};
  setup.range = rom::parse_frequency_range("14:22:201", rom::Spacing::linear, "--freq");
  const rom::ResponseCurve curve =
      rom::predict_response(table, setup.host, setup.excitation, rom::frequencies_of(setup.range));
  CHECK(slurp(dir / "p.csv") == rom::prediction_csv(setup, curve));
  CHECK(slurp(dir / "p.json") == rom::prediction_json(setup, curve));
  CHECK(r.err.find("201 frequencies predicted in") != std::string::npos);

  // The terminal: the setup, a header, one line per row, the jumps of both sweeps.
  CHECK(r.out.find("host M = 0.0376 kg, K = 470 N/m, C = 0.01 N s/m; force F0 = 0.05 N; 201 frequencies 14 to 22 "
                   "Hz (linear)\n") != std::string::npos);
  const auto rows = rom::prediction_rows(setup, curve);
  CHECK(std::count(r.out.begin(), r.out.end(), '\n') ==
        static_cast<long>(2 + 1 + rows.size() + 2 + curve.jumps_up.size() + curve.jumps_down.size()));
  CHECK(r.out.find("f_Hz  branch  stability") != std::string::npos);
  CHECK(r.out.find("unstable") != std::string::npos);
  CHECK(r.out.find("saddle\n") != std::string::npos);
  CHECK(r.out.find("sweep up: 1 jump(s)\n  between ") != std::string::npos);
  CHECK(r.out.find("sweep down: 1 jump(s)\n  between ") != std::string::npos);
}

TEST_CASE("pdamp rom: base excitation, log spacing, a JSON table, --quiet") {
  test::TempDir dir("rom-base"), capture("rom-base-io");
  const auto json = (dir / "t.json").string(), out = (dir / "b.csv").string();
  REQUIRE(pdamp_rom({"--table", liftoff(), "--export-table", json}, capture).code == 0);
  const Outcome r = pdamp_rom(
      Args{"--table", json, "--base", "1e-4", "--freq", "12:26:50", "--spacing", "log", "--quiet", "--out", out} + host,
      capture);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out.empty());
  const std::string csv = slurp(out);
  CHECK(csv.find("# excitation = base motion Y = 1e-04 m\n") != std::string::npos);
  CHECK(csv.find("# frequencies = 50 frequencies 12 to 26 Hz (log)\n") != std::string::npos);
  // Log spacing: the second frequency is 12 (26/12)^(1/49).
  const auto columns = csv_columns(csv);
  CHECK(std::stod(columns.at("frequency_hz").at(0)) == 12);
  const auto second = std::find_if(columns.at("frequency_hz").begin(), columns.at("frequency_hz").end(),
                                   [](const std::string& f) { return std::stod(f) > 12; });
  REQUIRE(second != columns.at("frequency_hz").end());
  CHECK(std::stod(*second) == doctest::Approx(12 * std::pow(26.0 / 12, 1.0 / 49)).scale(1.0).epsilon(1e-14));
}

TEST_CASE("pdamp rom exports a table as CSV and JSON that read back to the same text") {
  test::TempDir dir("rom-export"), capture("rom-export-io");
  const auto file = [&](const char* name) { return (dir / name).string(); };
  REQUIRE(pdamp_rom({"--table", liftoff(), "--export-table", file("a.json"), "--export-table", file("a.csv")}, capture)
              .code == 0);
  REQUIRE(pdamp_rom({"--table", file("a.json"), "--export-table", file("b.csv")}, capture).code == 0);
  REQUIRE(pdamp_rom({"--table", file("b.csv"), "--export-table", file("b.json")}, capture).code == 0);
  CHECK(slurp(file("a.csv")) == slurp(file("b.csv")));
  CHECK(slurp(file("a.json")) == slurp(file("b.json")));
  // The committed table, written by Python, reads to the same numbers as its export.
  CHECK(rom::read_damper_table(file("a.csv")) == rom::read_damper_table(liftoff()));
}

TEST_CASE("pdamp rom: bad input exits 2 with the reason and writes nothing") {
  test::TempDir inputs("rom-bad-in"), dir("rom-bad-out"), capture("rom-bad-io");
  const auto input = [&](const char* name) { return (inputs / name).string(); };
  {
    std::ofstream bad(input("ragged.csv"));
    bad << "# format = pdamp damper table 1\n# source = x\n# bed_mass_kg = 0.01\n# gravity_m_s2 = 9.81\n"
           "amplitude_m,frequency_hz,m_app_kg,c_eq_N_s_m,m_app_spread_kg,c_eq_spread_N_s_m,settled\n"
           "0.001,10,0.01,0,0,0,1\n0.01,10,0.01,0,0,0,1\n0.001,20,0.01,0,0,0,1\n";
  }
  std::filesystem::create_directory(input("folder.csv"));
  std::filesystem::create_symlink("/dev/zero", input("zero.csv"));  // endless if it were read
  { std::ofstream huge(input("huge.csv")); }
  std::filesystem::resize_file(input("huge.csv"), rom::max_table_file_bytes + 1);  // sparse: no disk used
  const std::vector<std::string> force = {"--force", "0.05", "--freq", "14:22:50"};
  const std::vector<std::string> good = Args{"--table", liftoff()} + host + force;
  const std::vector<std::string> outputs = {"--out",          (dir / "p.csv").string(),
                                            "--out",          (dir / "p.json").string(),
                                            "--export-table", (dir / "t.json").string()};
  struct Case {
    std::vector<std::string> args;
    std::string reason;
  };
  const auto table = [](const std::string& file) { return Args{"--table", file}; };
  const Case cases[] = {
      {table(input("ragged.csv")) + host + force, "no point at A = 0.01 m, f = 20 Hz"},
      {table(input("missing.csv")) + host + force, "missing.csv' cannot be read (no such file)"},
      {table(input("folder.csv")) + host + force, "folder.csv' is a directory, not a regular file"},
      {table(input("zero.csv")) + host + force, "zero.csv' is a device, not a regular file"},
      {table(input("huge.csv")) + host + force, "is larger than 16777216 bytes, the most a damper table file may have"},
      {table(liftoff() + ".txt") + host + force, "name it .csv or .json"},
      {{"--mass", "0.0376"}, "give exactly one of --table FILE (.csv or .json) and --study ID"},
      {table(liftoff()) + Args{"--study", "1"} + host + force, "give exactly one of --table FILE"},
      {table(liftoff()) + Args{"--model", "hard"} + host + force, "--model is for --study"},
      {table(liftoff()) + Args{"--mass", "0", "--stiffness", "470"} + force, "host mass M (kg) = 0"},
      {table(liftoff()) + Args{"--mass", "0.0376", "--stiffness", "-470"} + force, "stiffness K"},
      {table(liftoff()) + Args{"--mass", "0.0376", "--stiffness", "470", "--damping", "-1"} + force,
       "host damping C (N s/m) = -1"},
      {table(liftoff()) + host + Args{"--force", "0.05", "--freq", "0:22:50"}, "needs 0 < start < stop"},
      {table(liftoff()) + host + Args{"--force", "0.05", "--freq", "5:22:50"},
       "outside the table's frequencies, 10 to 28 Hz"},
      {table(liftoff()) + host + Args{"--force", "0.05", "--freq", "14:22:1"}, "frequency count 1"},
      {table(liftoff()) + host + Args{"--force", "0.05", "--freq", "14:22"}, "--freq"},
      {table(liftoff()) + host + Args{"--force", "0.05", "--freq", "14:22:50:"},
       "--freq '14:22:50:': expected three fields separated by ':', not 4 (write START:STOP:COUNT"},
      {table(liftoff()) + host + Args{"--force", "-0.05", "--freq", "14:22:50"}, "force amplitude F0 (N) = -0.05"},
      {table(liftoff()) + host + Args{"--freq", "14:22:50"}, "exactly one of --force"},
      {good + Args{"--base", "1e-4"}, "exactly one of --force"},
      {table(liftoff()) + host + Args{"--force", "0.05"}, "--freq is required"},
      {good + Args{"--spacing", "cubic"}, "--spacing 'cubic'"},
      {good + Args{"--mass", "x"}, "--mass"},
      {good + Args{"--colour"}, "--colour"},
      {table(liftoff()) + host + Args{"--force", "100", "--freq", "14:22:50"}, "the table cannot cover this host"},
      {table(liftoff()), "--out needs a prediction"},
      {good + Args{"--out", (dir / "p.txt").string()}, "name it .csv or .json"},
      {good + Args{"--out", (dir / "nowhere" / "p.csv").string()}, "' does not exist"},
  };
  for (const Case& c : cases) {
    std::string line;
    for (const auto& word : c.args) line += " " + word;
    CAPTURE(line);
    const Outcome r = pdamp_rom(c.args + outputs, capture);
    CHECK(r.code == 2);
    CHECK(r.err.find(c.reason) != std::string::npos);
    CHECK(r.err.rfind("pdamp: ", 0) == 0);
    CHECK(r.out.empty());
    CHECK(files_in(dir) == 0);
  }
  const Outcome idle = pdamp_rom({"--table", liftoff()}, capture);
  CHECK(idle.code == 2);
  CHECK(idle.err.find("nothing to do") != std::string::npos);
  const Outcome help = pdamp_rom({"--help"}, capture);
  CHECK(help.code == 0);
  CHECK(help.out.find("--export-table") != std::string::npos);
}

TEST_CASE("tools/plot_rom.py draws a prediction") {
  test::TempDir dir("rom-plot"), capture("rom-plot-io");
  const auto csv = (dir / "p.csv").string();
  REQUIRE(
      pdamp_rom(Args{"--table", liftoff(), "--force", "0.05", "--freq", "14:22:101", "--quiet", "--out", csv} + host,
                capture)
          .code == 0);
  const std::string script = (test::source_dir() / "tools" / "plot_rom.py").string();
  const Outcome r = run("/usr/bin/python3", {script, csv, "--out", (dir / "p.png").string()}, capture);
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(std::filesystem::file_size(dir / "p.png") > 10000);
  // Not a prediction: refused.
  const Outcome bad = run("/usr/bin/python3", {script, liftoff(), "--out", (dir / "q.png").string()}, capture);
  CHECK(bad.code != 0);
  CHECK(!std::filesystem::exists(dir / "q.png"));
}
