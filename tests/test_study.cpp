/// Studies: the study file's grammar, the points it expands to, their validation, what
/// counts as a changed study, and the study tables of the store.
#include <doctest/doctest.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/model/scenario_loader.hpp"
#include "pdamp/store/process_lease.hpp"
#include "pdamp/store/study_store.hpp"
#include "pdamp/study/study.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::study;

namespace {

std::string small_text() {
  std::ifstream in(test::scenario_file("small"));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A study of `body` (the sections after [study]) on small.ini, as if read from files.
Study study_of(const std::string& body, const std::string& models = "hard", bool force = false) {
  StudySource source{"/studies/test.ini",
                     "[study]\nscenario = ../scenarios/small.ini\nmodels = " + models + "\n" + body,
                     test::scenario_file("small"), small_text()};
  return make_study(source, force);
}

StudyFile file_of(const std::string& text) { return parse_study_file(text, "test.ini", "test"); }

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

std::int64_t scalar(RunStore& store, const std::string& sql) {
  sqlite::Database db(store.file());
  sqlite::Statement q(db, sql);
  q.step();
  return q.column_int(0);
}

/// The canonical scenario text without its name line.
std::string without_name(const std::string& canonical) {
  std::istringstream in(canonical);
  std::string out;
  for (std::string line; std::getline(in, line);) {
    if (!line.starts_with("name = ")) out += line + "\n";
  }
  return out;
}

}  // namespace

TEST_CASE("sweep values: lists keep spaces inside values, ranges are linear or geometric") {
  CHECK(parse_sweep_values("100, 200,400", "k") == std::vector<std::string>{"100", "200", "400"});
  CHECK(parse_sweep_values("0.0008 0.0012, 0.001", "k") == std::vector<std::string>{"0.0008 0.0012", "0.001"});
  CHECK(parse_sweep_values("0 0 -9.81", "k") == std::vector<std::string>{"0 0 -9.81"});
  CHECK(parse_sweep_values("0.001:0.005:5", "k") ==
        std::vector<std::string>{"0.001", "0.002", "0.003", "0.004", "0.005"});
  // The ends as written; the values between to 15 significant digits.
  CHECK(parse_sweep_values("1e-4:1e-2:5:log", "k") ==
        std::vector<std::string>{"1e-4", "0.000316227766016838", "0.001", "0.00316227766016838", "1e-2"});
  CHECK(parse_sweep_values("1:10:4:lin, 20", "k") == std::vector<std::string>{"1", "4", "7", "10", "20"});
  CHECK(parse_sweep_values("7", "k") == std::vector<std::string>{"7"});

  struct Bad {
    std::string text, message;
  };
  for (const Bad& bad : std::vector<Bad>{{"", "has no values"},
                                         {"1,,2", "empty value"},
                                         {"1:1:3", "empty (start = stop)"},
                                         {"5:1:3", "reversed"},
                                         {"1:5:1", "count must be at least 2"},
                                         {"1:5:0", "count must be at least 2"},
                                         {"1:5:2.5", "'2.5' is not a whole number"},
                                         {"1:5:100000", "at most 10000"},
                                         {"a:5:3", "start 'a' is not a finite number"},
                                         {"1:5", "start:stop:count"},
                                         {"1:5:3:cubic", "lin (the default) or log"},
                                         {"0:5:3:log", "log range needs start > 0"}}) {
    CAPTURE(bad.text);
    CHECK_THROWS_WITH_AS(parse_sweep_values(bad.text, "[sweep] host.z0_m"), doctest::Contains(bad.message.c_str()),
                         InputError);
    CHECK_THROWS_WITH_AS(parse_sweep_values(bad.text, "[sweep] host.z0_m"), doctest::Contains("[sweep] host.z0_m"),
                         InputError);
  }
}

TEST_CASE("study files: [study] keys, grid axes in file order, zips, named sweeps") {
  const StudyFile f = file_of(
      "# a comment\n[study]\nname = fill and size  # trailing comment\nscenario = a.ini\nmodels = both\n"
      "[sweep]\nparticles.count = 10, 20\nzip = host.z0_m run.duration_s\nhost.z0_m = 0.01, 0.02, 0.03\n"
      "particles.diameter_m = 0.001 0.0012, 0.0015\nrun.duration_s = 0.1, 0.2, 0.1\n"
      "[sweep.g]\ngravity.g_m_s2 = 9.81, 0 0 -9.81\n");
  CHECK(f.name == "fill and size");
  CHECK(f.scenario == "a.ini");
  CHECK(f.models == StudyModels::both);
  REQUIRE(f.sweeps.size() == 2);
  const Sweep& grid = f.sweeps[0];
  CHECK(grid.section == "sweep");
  REQUIRE(grid.axes.size() == 3);
  CHECK(grid.axes[0].keys == std::vector<std::string>{"particles.count"});
  // The zip takes the place of its first key.
  CHECK(grid.axes[1].keys == std::vector<std::string>{"host.z0_m", "run.duration_s"});
  CHECK(grid.axes[1].values[2] == std::vector<std::string>{"0.03", "0.1"});
  CHECK(grid.axes[2].values[0] == std::vector<std::string>{"0.001 0.0012"});
  CHECK(grid.points_up_to(1000) == 12);
  CHECK(grid.points_up_to(5) == 6);
  CHECK(f.sweeps[1].section == "sweep.g");
  CHECK(f.sweeps[1].axes[0].values[1][0] == "0 0 -9.81");
  CHECK(file_of("[study]\nscenario = a.ini\nmodels = soft\n[sweep]\nhost.z0_m = 0.01\n").name == "test");
  // A byte-order mark, CR LF line ends and a header with blanks read as in scenario files.
  const StudyFile dos =
      file_of("\xEF\xBB\xBF[study]\r\nscenario = a.ini\r\nmodels = hard\r\n[ sweep ]\r\nhost.z0_m = 1, 2\r\n");
  REQUIRE(dos.sweeps.size() == 1);
  CHECK(dos.sweeps[0].axes[0].values[1] == std::vector<std::string>{"2"});
}

TEST_CASE("study files: every mistake is one message naming the line, the key and what is valid") {
  const std::string head = "[study]\nscenario = a.ini\nmodels = hard\n";
  struct Bad {
    std::string text, message;
  };
  for (const Bad& bad : std::vector<Bad>{
           {head + "[sweep]\nparticles.cont = 1, 2\n",
            "test.ini, line 5: [sweep] 'particles.cont' is not a scenario key; "
            "did you mean particles.count?"},
           {head + "[sweep]\nwarp.speed = 1, 2\n", "'warp.speed' is not a scenario key (run 'pdamp keys'"},
           {head + "[sweep]\nscenario.name = a, b\n", "scenario.name cannot be set by a study"},
           {head + "[sweep]\nhost.z0_m = 1, 2\nhost.z0_m = 3\n", "test.ini, line 6: [sweep] host.z0_m is given twice"},
           {head + "[sweep]\nhost.z0_m = 0.01, 0.02, 1e-2\n", "the value '1e-2' appears twice (values 1 and 3)"},
           {head + "[sweep]\nhost.z0_m = 5:1:3\n", "reversed"},
           {head + "[sweep]\nhost.z0_m =\n", "host.z0_m has no values"},
           {head + "[sweep]\nzip = host.z0_m run.duration_s\nhost.z0_m = 1, 2\nrun.duration_s = 1, 2, 3\n",
            "run.duration_s has 3 values and host.z0_m 2: zipped keys (line 5) need as many values each"},
           {head + "[sweep]\nzip = host.z0_m run.duration_s\nhost.z0_m = 1, 2\n",
            "zip names run.duration_s, which has no values in this section"},
           {head + "[sweep]\nzip = host.z0_m\nhost.z0_m = 1, 2\n", "a zip names two or more keys"},
           {head + "[sweep]\nzip = host.z0_m host.v0_m_s\nzip = host.z0_m run.duration_s\n",
            "host.z0_m is already in another zip"},
           {head + "[sweep]\n", "test.ini, line 4: [sweep] has no keys"},
           {head, "no [sweep], [frf] or [characterise] section"},
           {head + "[sweeps]\nhost.z0_m = 1\n", "test.ini, line 4: unknown section [sweeps]"},
           {head + "[sweep.]\nhost.z0_m = 1\n", "unknown section [sweep.]"},
           {head + "[sweep]\nhost.z0_m = 1\n[sweep]\nhost.v0_m_s = 1\n", "[sweep] appears twice (first on line 4)"},
           {"[study]\nmodels = hard\n[sweep]\nhost.z0_m = 1\n", "[study] scenario is missing"},
           {"[study]\nscenario = a.ini\n[sweep]\nhost.z0_m = 1\n", "[study] models is missing (soft, hard or both)"},
           {"[study]\nscenario = a.ini\nmodels = all\n[sweep]\nhost.z0_m = 1\n",
            "test.ini, line 3: [study] models = 'all': must be soft, hard or both"},
           {head + "seed = 3\n", "[study] has no key 'seed' (valid: name, scenario, models)"},
           {"host.z0_m = 1\n" + head, "test.ini, line 1: 'host.z0_m = 1' comes before any [section] header"},
           {head + "[sweep]\njust words\n", "test.ini, line 5: 'just words' is not a 'key = value' line"},
           // The scenario files' syntax, from the same parser: a '#' glued to a value, a NUL.
           {head + "[sweep]\nhost.z0_m = 0.01, 0.02#cm\n",
            "test.ini, line 5: 'host.z0_m = 0.01, 0.02#cm': '#' directly"},
           {head + "[sweep]\nhost.z0_m = 1" + std::string(1, '\0') + "\n", "a NUL byte at offset"},
       }) {
    CAPTURE(bad.text);
    CHECK(error_of([&] { file_of(bad.text); }).find(bad.message) != std::string::npos);
  }
}

TEST_CASE("a study's points: each sweep a grid whose first axis varies slowest, then the next sweep") {
  const Study s = study_of(
      "[sweep]\nparticles.count = 10, 20\nhost.damping_N_s_m = 0.1, 0.2, 0.3\nrun.duration_s = 0.1\n"
      "[sweep.zipped]\nzip = host.z0_m host.v0_m_s\nhost.z0_m = 0.01, 0.02\nhost.v0_m_s = 0, 0.1\n");
  REQUIRE(s.points.size() == 8);
  CHECK(describe_values(s.points[0]) == "particles.count = 10, host.damping_N_s_m = 0.1, run.duration_s = 0.1");
  CHECK(describe_values(s.points[1]) == "particles.count = 10, host.damping_N_s_m = 0.2, run.duration_s = 0.1");
  CHECK(describe_values(s.points[3]) == "particles.count = 20, host.damping_N_s_m = 0.1, run.duration_s = 0.1");
  CHECK(s.points[6].point == 7);
  CHECK(s.points[6].section == "sweep.zipped");
  CHECK(describe_values(s.points[7]) == "host.z0_m = 0.02, host.v0_m_s = 0.1");

  const Scenario p5 = point_scenario(s, s.points[4]);
  CHECK(p5.name == "test/5");
  CHECK(p5.particles.count == 20);
  CHECK(p5.host.damping_N_s_m == 0.2);
  CHECK(p5.run.duration_s == 0.1);
  CHECK(p5.cavity.diameter_m == 0.012);  // from small.ini
  CHECK_NOTHROW(validate_study(s));
}

TEST_CASE("a grid over the size limit needs --force, and no study may pass the hard limit") {
  const std::string grid = "[sweep]\nhost.z0_m = 0.001:0.01:40\nhost.damping_N_s_m = 0.01:0.1:30\n";
  CHECK(error_of([&] {
          study_of(grid);
        }).find("the study has 1200 points, more than the 1000 allowed without --force") != std::string::npos);
  CHECK(study_of(grid, "hard", true).points.size() == 1200);
  const std::string huge = grid + "host.v0_m_s = 0:1:100\nhost.mass_kg = 0.01:1:100\n";
  CHECK(error_of([&] { study_of(huge, "hard", true); }).find("more than 100000 points") != std::string::npos);
}

TEST_CASE("validation names the point, its values, the key and what is valid") {
  // The third cavity height is too low for small.ini's 1.5 mm spheres.
  const Study s = study_of("[sweep]\nparticles.count = 10, 20\ncavity.height_m = 0.01, 0.02, 0.001\n");
  const std::string message = error_of([&] { validate_study(s); });
  CHECK(message.find("/studies/test.ini: point 3 of 6 ([sweep] particles.count = 10, cavity.height_m = 0.001): ") == 0);
  CHECK(message.find(
            "small.ini, line 21: particles.diameter_m = '0.0015': spheres of diameter 0.0015 m do not fit in the "
            "cavity (D = 0.012 m, H = 0.001 m)") != std::string::npos);
  CHECK(error_of([&] {
          validate_study(study_of("[sweep]\nhost.mass_kg = 1, -1\n"));
        }).find("point 2 of 2 ([sweep] host.mass_kg = -1): swept host.mass_kg: host.mass_kg = '-1': must be > 0") !=
        std::string::npos);
  CHECK(error_of([&] {
          validate_study(study_of("[sweep]\nparticles.count = 10, 10.5\n"));
        }).find("particles.count = '10.5': must be a whole number") != std::string::npos);
  CHECK(error_of([&] {
          validate_study(study_of("[sweep]\nexcitation.frequency_hz = 10, 20\n"));
        }).find("excitation.frequency_hz is not used by excitation.mode = free") != std::string::npos);
  // The run's budget (sim/run_budget.hpp), as pdamp run checks it: 2e6 samples of 0.5 ms.
  CHECK(error_of([&] { validate_study(study_of("[sweep]\nrun.duration_s = 0.1, 1000\n")); })
            .find("point 2 of 2 ([sweep] run.duration_s = 1000): run.max_samples = 1000000: run.duration_s = 1000 s "
                  "sampled every run.sample_interval_s = 0.0005 s would take 2e+06 samples") != std::string::npos);
  CHECK_NOTHROW(
      validate_study(study_of("[sweep]\nzip = run.duration_s run.max_samples\n"
                              "run.duration_s = 0.1, 1000\nrun.max_samples = 1e6, 3e6\n")));
}

TEST_CASE("the Table 4 study's points are exactly the Table 4 scenario files") {
  const Study s = make_study(read_study_source(test::source_dir() / "data" / "studies" / "table4.ini"), false);
  CHECK_NOTHROW(validate_study(s));
  const std::vector<std::string> files{"table4_packing95", "table4_packing50", "table4_packing25", "table4_f20",
                                       "table4_f100",      "table4_f250",      "table4_f500"};
  REQUIRE(s.points.size() == files.size());
  for (std::size_t i = 0; i < files.size(); ++i) {
    CAPTURE(files[i]);
    const Scenario point = point_scenario(s, s.points[i]);
    CHECK(point.name == "table4/" + std::to_string(i + 1));
    CHECK(without_name(point.canonical_text) ==
          without_name(load_scenario(test::scenario_file(files[i])).canonical_text));
  }
}

TEST_CASE("every study file in data/studies is valid: every point of every model") {
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(test::source_dir() / "data" / "studies")) {
    if (entry.path().extension() != ".ini") continue;
    CAPTURE(entry.path().string());
    ++files;
    CHECK_NOTHROW(validate_study(make_study(read_study_source(entry.path()), false)));
  }
  CHECK(files >= 7);
}

TEST_CASE("a study counts as changed only if it would run other points, and every difference is named") {
  const std::string body = "[sweep]\nparticles.count = 10, 20\nhost.damping_N_s_m = 0.1:0.3:3\n";
  const Study stored = study_of(body);
  CHECK(study_differences(stored, study_of("# reworded\n" + body)).empty());
  CHECK(study_differences(stored, study_of("[sweep]\nparticles.count = 10,20\nhost.damping_N_s_m = 0.1, 0.2, 0.3\n"))
            .empty());

  auto changed =
      study_differences(stored, study_of("[sweep]\nparticles.count = 10, 30\nhost.damping_N_s_m = 0.1:0.3:3\n"));
  REQUIRE(changed.size() == 1);
  CHECK(changed[0] == "[sweep] particles.count: '10, 30' now, '10, 20' stored");
  changed = study_differences(stored, study_of(body, "both"));
  REQUIRE(changed.size() == 1);
  CHECK(changed[0] == "[study] models: 'both' now, 'hard' stored");
  // The same keys in another order number the points differently.
  changed = study_differences(stored, study_of("[sweep]\nhost.damping_N_s_m = 0.1:0.3:3\nparticles.count = 10, 20\n"));
  REQUIRE(changed.size() == 1);
  CHECK(changed[0].starts_with("point 2: "));

  Study edited = study_of(body);
  edited.source.scenario_text += "\n[soft_wall]\nmu = 0.3\n";
  changed = study_differences(stored, edited);
  REQUIRE(changed.size() == 1);
  CHECK(changed[0] == "base scenario [soft_wall] mu: '0.3' now, '0.55' stored");
}

TEST_CASE("every [frf] and [characterise] key that changes what is computed is a difference, named") {
  const std::string frf =
      "[frf]\nmode = force\nlevels = 0.05, 0.1\nfrequencies = 15:19:3\ndirection = both\nhost_alone = true\n"
      "host.z0_m = 0\n";
  const std::string characterise = "[characterise]\namplitudes = 0.0002, 0.0004\nfrequencies = 20, 30\n";
  struct Case {
    std::string stored, now;
    std::vector<std::string> differences;
  };
  const std::vector<Case> cases{
      {frf + "start = predict\n", frf + "start = continue\n", {"[frf] start: 'continue' now, 'predict' stored"}},
      {frf, frf + "amplitude_tolerance = 0.5\n", {"[frf] amplitude_tolerance: '0.5' now, '0.001' stored"}},
      {frf, frf + "phase_tolerance_rad = 0.5\n", {"[frf] phase_tolerance_rad: '0.5' now, '0.001' stored"}},
      {frf, frf + "min_cycles = 30\n", {"[frf] min_cycles: '30' now, '10' stored"}},
      {frf, frf + "consecutive_cycles = 2\n", {"[frf] consecutive_cycles: '2' now, '5' stored"}},
      // The same run length (max_cycles + measured_cycles), measured otherwise.
      {frf + "max_cycles = 40\nmeasured_cycles = 5\n",
       frf + "max_cycles = 35\nmeasured_cycles = 10\n",
       {"[frf] max_cycles: '35' now, '40' stored", "[frf] measured_cycles: '10' now, '5' stored"}},
      {characterise,
       characterise + "amplitude_tolerance = 0.5\n",
       {"[characterise] amplitude_tolerance: '0.5' now, '0.001' stored"}},
      {characterise,
       characterise + "phase_tolerance_rad = 0.5\n",
       {"[characterise] phase_tolerance_rad: '0.5' now, '0.001' stored"}},
      {characterise, characterise + "min_cycles = 30\n", {"[characterise] min_cycles: '30' now, '10' stored"}},
      {characterise,
       characterise + "consecutive_cycles = 2\n",
       {"[characterise] consecutive_cycles: '2' now, '5' stored"}},
  };
  for (const auto& c : cases) {
    CAPTURE(c.now);
    CHECK(study_differences(study_of(c.stored), study_of(c.now)) == c.differences);
  }
  // The defaults written out are no difference.
  CHECK(study_differences(study_of(frf), study_of(frf + "start = continue\namplitude_tolerance = 1e-3\n"
                                                        "consecutive_cycles = 5\nmin_cycles = 10\n"))
            .empty());
}

TEST_CASE("numbers are compared by value: written otherwise they are no difference, other values are named") {
  const auto same = [](const std::string& stored, const std::string& now) {
    CAPTURE(now);
    CHECK(study_differences(study_of(stored), study_of(now)).empty());
  };
  const auto named = [](const std::string& stored, const std::string& now, const std::string& difference) {
    CAPTURE(now);
    const auto differences = study_differences(study_of(stored), study_of(now));
    REQUIRE(differences.size() == 1);
    CHECK(differences[0] == difference);
  };
  const std::string sweep = "[sweep]\nhost.damping_N_s_m = 0.1, 0.2\nrun.duration_s = 0.1\n";
  same(sweep, "[sweep]\nhost.damping_N_s_m = 0.1, 0.2\nrun.duration_s = 0.10\n");
  same(sweep, "[sweep]\nhost.damping_N_s_m = 1e-1, 2.0e-1\nrun.duration_s = 1e-1\n");
  named(sweep, "[sweep]\nhost.damping_N_s_m = 0.1, 0.2\nrun.duration_s = 0.11\n",
        "[sweep] run.duration_s: '0.11' now, '0.1' stored");
  // Integers exactly, beyond a double's 53 bits too.
  same("[sweep]\nparticles.seed = 7, 8\n", "[sweep]\nparticles.seed = 007, 8\n");
  named("[sweep]\nparticles.seed = 18446744073709551615, 1\n", "[sweep]\nparticles.seed = 18446744073709551614, 1\n",
        "[sweep] particles.seed: '18446744073709551614, 1' now, '18446744073709551615, 1' stored");

  const std::string frf = "[frf]\nmode = force\nfrequencies = 15, 17\nmax_cycles = 20\n";
  same(frf + "levels = 0.05, 0.1\nhost.z0_m = 0\n", frf + "levels = 0.05, 0.10\nhost.z0_m = 0.0\n");
  named(frf + "levels = 0.05, 0.1\nhost.z0_m = 0\n", frf + "levels = 0.05, 0.1\nhost.z0_m = 0.001\n",
        "[frf] host.z0_m: '0.001' now, '0' stored");
  named(frf + "levels = 0.05, 0.1\n", frf + "levels = 0.05, 0.15\n",
        "[frf] levels: '0.05, 0.15' now, '0.05, 0.1' stored");

  const std::string characterise = "[characterise]\nfrequencies = 20, 30\n";
  same(characterise + "amplitudes = 0.0002, 0.0004\n", characterise + "amplitudes = 2e-4, 4E-4\n");
  named(characterise + "amplitudes = 0.0002, 0.0004\n", characterise + "amplitudes = 0.0002, 0.0005\n",
        "[characterise] amplitudes: '0.0002, 0.0005' now, '0.0002, 0.0004' stored");
}

namespace {

/// A completed run with samples every 0.1 s and two cycles.
std::int64_t completed_run(RunStore& store, const std::string& model, double scale) {
  const auto id = store.begin_run({model, "p", "", 1, 10, 1.0});
  {
    RunWriter writer(store, id);
    for (int i = 0; i <= 10; ++i) {
      Observation o;
      o.t_s = 0.1 * i;
      o.energy.dissipated_impact_J = scale * i;
      o.energy.dissipated_friction_J = 2 * scale * i;
      o.energy.dissipated_viscous_J = 3 * scale * i;
      writer.record_sample(o, 0.0);
    }
    for (int c = 1; c <= 2; ++c) {
      CycleRecord r;
      r.cycle = c;
      r.amplitude_m = 0.01 / c;
      r.psi = 0.1 * (3 - c) * scale;
      r.gamma = 5.0 / c;
      r.max_host_kinetic_J = 1;
      writer.record_cycle(r);
    }
  }
  store.finish_run(id, {RunStatus::completed, "", 1.0, 2.5, 1.0, 3e-9});
  return id;
}

}  // namespace

TEST_CASE("the study tables round-trip: points and values, claims and attempts, metrics, views") {
  test::TempDir dir("study-store");
  RunStore store(dir / "runs.sqlite");
  StudyStore studies(store);
  const std::vector<NewStudyPoint> points{
      {1, "sweep", {{"particles.count", "10"}, {"particles.diameter_m", "1 2"}}, std::nullopt, std::nullopt},
      {2, "sweep", {{"particles.count", "20"}, {"particles.diameter_m", "1 2"}}, std::nullopt, std::nullopt}};
  const auto id = studies.create_study({"s", "both", "/s.ini", "study text", "/b.ini", "base text"}, points);
  CHECK(studies.find_study("s")->study_id == id);
  CHECK(!studies.find_study("t"));
  CHECK(studies.study(id)->scenario_text == "base text");
  CHECK(studies.summary(id)->pending == 2);
  CHECK(scalar(store, "SELECT count(*) FROM study_point_values WHERE number IS NULL") == 2);
  CHECK(scalar(store, "SELECT number FROM study_point_values WHERE point = 2 AND key = 'particles.count'") == 20);

  const ProcessLease lease{"host-a", 123, 456};
  const auto attempt = studies.claim_point(id, 1, lease);
  REQUIRE(attempt == 1);
  CHECK(!studies.claim_point(id, 1, lease));  // running: not claimed twice
  const auto soft = completed_run(store, "soft", 1.0), hard = completed_run(store, "hard", 1.1);
  studies.link_run(id, 1, 1, "soft", soft);
  studies.link_run(id, 1, 1, "hard", hard);
  const auto state = studies.points(id)[0];
  CHECK(state.status == PointStatus::running);
  REQUIRE(state.lease);
  CHECK(state.lease->pid == 123);
  studies.complete_point(id, 1, 1, {soft, hard}, std::nullopt);
  CHECK(!studies.claim_point(id, 1, lease));  // completed

  const auto metrics = studies.metrics(id);
  REQUIRE(metrics.size() == 2);
  CHECK(metrics[0].model == "soft");
  CHECK(metrics[0].dissipated_friction_J == 20.0);  // at the last sample
  CHECK(*metrics[0].psi_peak == test::relative(0.2));
  CHECK(*metrics[0].psi_peak_gamma == 5.0);       // the first cycle's
  CHECK(*metrics[0].final_amplitude_m == 0.005);  // the last cycle's
  CHECK(metrics[0].cycles == 2);
  CHECK(metrics[0].wall_time_s == 2.5);
  CHECK(metrics[0].energy_balance_rel_err == 3e-9);
  CHECK(scalar(store, "SELECT count(*) FROM study_results WHERE status = 'completed'") == 2);
  CHECK(scalar(store, "SELECT round(dissipated_total_J) FROM study_results WHERE model = 'hard'") == 66);

  // A failed point is claimed again by its next attempt; a lease whose process is gone is abandoned.
  REQUIRE(studies.claim_point(id, 2, lease) == 1);
  studies.end_point(id, 2, 1, PointStatus::failed, "it broke");
  CHECK(studies.points(id)[1].message == "it broke");
  REQUIRE(studies.claim_point(id, 2, lease) == 2);
  const auto left = store.begin_run({"soft", "p", "", 1, 10, 1.0});
  studies.link_run(id, 2, 2, "soft", left);
  CHECK(!studies.abandon_point(id, 2, {"host-a", 124, 456}, PointStatus::interrupted, "gone"));  // another lease
  CHECK(studies.abandon_point(id, 2, lease, PointStatus::interrupted, "gone"));
  CHECK(studies.points(id)[1].status == PointStatus::interrupted);
  CHECK(store.summary(left)->status == "interrupted");
  CHECK(store.summary(left)->message == "gone");
  // A late worker of an earlier attempt cannot complete the point.
  CHECK_THROWS_AS(studies.complete_point(id, 2, 1, {}, std::nullopt), RuntimeFailure);
  const auto summary = studies.summary(id);
  CHECK(summary->completed == 1);
  CHECK(summary->interrupted == 1);
  CHECK(studies.list_studies().size() == 1);

  // Deleting a completed point's run (pdamp delete) leaves it pending, to be run again.
  const std::int64_t deleted[] = {hard};
  store.delete_runs(deleted, false);
  const auto redo = studies.point(id, 1);
  CHECK(redo->status == PointStatus::pending);
  CHECK(redo->message == "its hard run " + std::to_string(hard) + " was deleted");
  CHECK(studies.metrics(id).empty());
  CHECK(studies.claim_point(id, 1, lease) == 2);
}

TEST_CASE("a lease is alive while its process is, on this host") {
  const ProcessLease me = this_process_lease();
  CHECK(me.pid == getpid());
  CHECK(me.start_ticks > 0);
  CHECK(lease_is_alive(me));
  CHECK(!lease_is_alive({me.host, me.pid, me.start_ticks + 1}));  // the id reused by a later process
  CHECK(!lease_is_alive({me.host, 4'000'000'000, 1}));            // no such process
  CHECK(lease_is_alive({me.host + "-elsewhere", 4'000'000'000, 1}));
}
