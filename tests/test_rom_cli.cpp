/// End-to-end tests of `pdamp rom`: predictions and table exports written only when the input
/// is good, exit code 2 with the reason and nothing written otherwise, and the plot script.
#include <doctest/doctest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "pdamp/rom/table_files.hpp"
#include "test_support.hpp"

using namespace pdamp;

namespace {

struct Outcome {
  int code;
  std::string out, err;
};

std::string slurp(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Runs a command line through the shell (arguments here need no quoting) in `dir`.
Outcome shell(const std::string& command, const test::TempDir& dir) {
  const auto out = dir / "stdout", err = dir / "stderr";
  const std::string line =
      "cd '" + dir.path().string() + "' && " + command + " >'" + out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(line.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), slurp(out), slurp(err)};
}

Outcome pdamp_rom(const std::string& args, const test::TempDir& dir) {
  return shell(std::string(PDAMP_EXECUTABLE) + " rom " + args, dir);
}

std::string liftoff() { return (test::source_dir() / "data" / "rom" / "synthetic_liftoff.csv").string(); }

const std::string host = " --mass 0.0376 --stiffness 470 --damping 0.01 ";

/// The files in `dir` other than the captured output.
int written_files(const test::TempDir& dir) {
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    const auto name = entry.path().filename().string();
    n += name != "stdout" && name != "stderr" && name.rfind("input", 0) != 0;
  }
  return n;
}

}  // namespace

TEST_CASE("pdamp rom predicts the lift-off table's response and writes it as CSV and JSON") {
  test::TempDir dir("rom-predict");
  const Outcome r =
      pdamp_rom("--table " + liftoff() + host + "--force 0.05 --freq 14:22:201 --out p.csv --out p.json --time", dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("sweep up: 1 jump(s)") != std::string::npos);
  CHECK(r.out.find("sweep down: 1 jump(s)") != std::string::npos);
  CHECK(r.out.find("saddle") != std::string::npos);
  CHECK(r.err.find("201 frequencies predicted in") != std::string::npos);
  const std::string csv = slurp(dir / "p.csv");
  CHECK(csv.rfind("# format = pdamp rom prediction 1\n", 0) == 0);
  CHECK(csv.find("\nfrequency_hz,branch,stability,amplitude_m,") != std::string::npos);
  const std::string json = slurp(dir / "p.json");
  CHECK(json.find("\"format\": \"pdamp rom prediction\"") != std::string::npos);
  CHECK(json.find("\"sweep_up\": [\n      {\"from_frequency_hz\": ") != std::string::npos);
  // The same prediction in the other formats: the CSV's rows are the JSON's points.
  CHECK(std::count(csv.begin(), csv.end(), '\n') - 8 == [&] {
    long n = 0;
    for (std::size_t at = json.find("{\"frequency_hz\""); at != std::string::npos;
         at = json.find("{\"frequency_hz\"", at + 1))
      ++n;
    return n;
  }());

  // Base excitation and log spacing, the table only as JSON.
  REQUIRE(pdamp_rom("--table " + liftoff() + " --export-table t.json", dir).code == 0);
  const Outcome base =
      pdamp_rom("--table t.json" + host + "--base 1e-4 --freq 12:26:50 --spacing log --quiet --out b.csv", dir);
  INFO(base.err);
  CHECK(base.code == 0);
  CHECK(base.out.empty());
  CHECK(slurp(dir / "b.csv").find("# excitation = base motion Y = 1e-04 m\n") != std::string::npos);
}

TEST_CASE("pdamp rom exports a table as CSV and JSON that read back to the same text") {
  test::TempDir dir("rom-export");
  REQUIRE(pdamp_rom("--table " + liftoff() + " --export-table a.json --export-table a.csv", dir).code == 0);
  REQUIRE(pdamp_rom("--table a.json --export-table b.csv", dir).code == 0);
  REQUIRE(pdamp_rom("--table b.csv --export-table b.json", dir).code == 0);
  CHECK(slurp(dir / "a.csv") == slurp(dir / "b.csv"));
  CHECK(slurp(dir / "a.json") == slurp(dir / "b.json"));
  // The committed table, written by Python, reads to the same numbers as its export.
  const auto original = rom::read_damper_table(liftoff());
  const auto exported = rom::read_damper_table(dir / "a.csv");
  CHECK(original.amplitudes_m == exported.amplitudes_m);
  CHECK(original.points.size() == exported.points.size());
}

TEST_CASE("pdamp rom: bad input exits 2 with the reason and writes nothing") {
  test::TempDir dir("rom-bad");
  {
    std::ofstream bad(dir / "input-bad.csv");
    bad << "# format = pdamp damper table 1\n# source = x\n# bed_mass_kg = 0.01\n# gravity_m_s2 = 9.81\n"
           "amplitude_m,frequency_hz,m_app_kg,c_eq_N_s_m,m_app_spread_kg,c_eq_spread_N_s_m,settled\n"
           "0.001,10,0.01,0,0,0,1\n0.01,10,0.01,0,0,0,1\n0.001,20,0.01,0,0,0,1\n";
  }
  const std::string out = " --out p.csv --out p.json --export-table t.json";
  const std::string good = "--table " + liftoff() + host + "--force 0.05 --freq 14:22:50";
  struct Case {
    std::string args, reason;
  };
  const Case cases[] = {
      {"--table input-bad.csv" + host + "--force 0.05 --freq 14:22:50", "no point at A = 0.01 m, f = 20 Hz"},
      {"--table missing.csv" + host + "--force 0.05 --freq 14:22:50", "cannot be read"},
      {"--table " + liftoff() + " --mass 0 --stiffness 470 --force 0.05 --freq 14:22:50", "host mass M (kg) = 0"},
      {"--table " + liftoff() + " --mass 0.0376 --stiffness -470 --force 0.05 --freq 14:22:50", "stiffness K"},
      {"--table " + liftoff() + " --mass 0.0376 --stiffness 470 --damping -1 --force 0.05 --freq 14:22:50",
       "host damping C (N s/m) = -1"},
      {"--table " + liftoff() + host + "--force 0.05 --freq 0:22:50", "needs 0 < start < stop"},
      {"--table " + liftoff() + host + "--force 0.05 --freq 5:22:50", "outside the table's frequencies, 10 to 28 Hz"},
      {"--table " + liftoff() + host + "--force -0.05 --freq 14:22:50", "force amplitude F0 (N) = -0.05"},
      {"--table " + liftoff() + host + "--freq 14:22:50", "exactly one of --force"},
      {"--table " + liftoff() + host + "--force 1 --base 1 --freq 14:22:50", "exactly one of --force"},
      {"--table " + liftoff() + host + "--force 0.05", "--freq is required"},
      {"--table " + liftoff() + host + "--force 0.05 --freq 14:22:50 --spacing cubic", "--spacing 'cubic'"},
      {"--table " + liftoff() + host + "--force 100 --freq 14:22:50", "the table cannot cover this host"},
      {"--table " + liftoff(), "--out needs a prediction"},
      {good + " --out p.txt", "name it .csv or .json"},
      {good + " --out nowhere/p.csv", "folder 'nowhere' does not exist"},
      {good + " --mass", "--mass"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.args);
    const Outcome r = pdamp_rom(c.args + out, dir);
    CHECK(r.code == 2);
    CHECK(r.err.find(c.reason) != std::string::npos);
    CHECK(r.err.find("pdamp: ") == 0);
    CHECK(written_files(dir) == 0);
  }
  const Outcome idle = pdamp_rom("--table " + liftoff(), dir);
  CHECK(idle.code == 2);
  CHECK(idle.err.find("nothing to do") != std::string::npos);
}

TEST_CASE("tools/plot_rom.py draws a prediction") {
  test::TempDir dir("rom-plot");
  REQUIRE(pdamp_rom("--table " + liftoff() + host + "--force 0.05 --freq 14:22:101 --quiet --out p.csv", dir).code ==
          0);
  const Outcome r =
      shell("/usr/bin/python3 " + (test::source_dir() / "tools" / "plot_rom.py").string() + " p.csv --out p.png", dir);
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(std::filesystem::file_size(dir / "p.png") > 10000);
  // Not a prediction: refused.
  const Outcome bad = shell(
      "/usr/bin/python3 " + (test::source_dir() / "tools" / "plot_rom.py").string() + " " + liftoff() + " --out q.png",
      dir);
  CHECK(bad.code != 0);
  CHECK(!std::filesystem::exists(dir / "q.png"));
}
