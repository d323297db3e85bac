/// Characterisation studies ([characterise], docs/characterisation.md): the section's keys
/// and mistakes, the curves it expands into, the physics of a bed at rest and of the empty
/// container, the same bits for any --jobs and after a SIGKILL and resuming, and the damper
/// table a characterisation gives the reduced model.
#include <doctest/doctest.h>

#include <csignal>
#include <fstream>
#include <numbers>
#include <sstream>
#include <thread>

#include "pdamp/rom/table_files.hpp"
#include "pdamp/store/study_store.hpp"
#include "pdamp/study/study.hpp"
#include "study_compare.hpp"
#include "test_process.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::study;
using namespace pdamp::test;

namespace {

/// A [characterise] study on small.ini, hard model unless the section says otherwise.
std::string characterise_study(const std::string& sections) {
  return "[study]\nscenario = " + small() + "\nmodels = hard\n\n" + sections;
}

Study study_of(const std::string& text, const std::string& base = "") {
  return make_study({"/tmp/c.ini", text, small(), base}, false);
}

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("[characterise] sections: a curve per model and frequency, up the amplitudes, Gamma turned into A") {
  const Study s = study_of(
      characterise_study("[characterise]\namplitudes = 0.002, 0.001, 0.0005\nfrequencies = 20, 15\nmodels = both\n"));
  REQUIRE(s.points.size() == 12);
  const StudyPoint& first = s.points[0];
  REQUIRE(first.characterise);
  CHECK(first.characterise->model == Model::soft);
  CHECK(first.characterise->frequency_hz == "15");
  CHECK(first.characterise->amplitude_m == "0.0005");
  CHECK(first.characterise->previous == 0);
  CHECK(s.points[1].characterise->previous == 1);
  CHECK(s.points[2].characterise->amplitude_m == "0.002");
  CHECK(s.points[3].characterise->previous == 0);  // the next frequency starts from the bed
  CHECK(s.points[3].characterise->curve == 2);
  CHECK(s.points[6].characterise->model == Model::hard);
  const Scenario scenario = point_scenario(s, s.points[4]);
  CHECK(scenario.excitation.mode == ExcitationMode::prescribed_motion);
  CHECK(scenario.excitation.amplitude_m == 0.001);
  CHECK(scenario.excitation.frequency_hz == 20);
  CHECK(scenario.run.sample_interval_s == test::relative(1.0 / 20).epsilon(1e-15));

  const Study g = study_of(
      characterise_study("[characterise]\ngammas = 0.5, 2\nfrequencies = 10, 20\nstart = bed\nempty = true\n"));
  REQUIRE(g.points.size() == 4);
  for (const auto& p : g.points) {
    CHECK(p.characterise->previous == 0);
    CHECK(point_scenario(g, p).particles.count == 0);
  }
  // Γ = A ω² / g with the base scenario's g.
  const double omega = 2.0 * std::numbers::pi * 20;
  const Scenario at_2 = point_scenario(g, g.points[3]);
  CHECK(at_2.excitation.amplitude_m * omega * omega / 9.81 == doctest::Approx(2.0).scale(1.0).epsilon(1e-14));
  CHECK(g.points[3].characterise->gamma == "2");
}

TEST_CASE("[characterise] mistakes: one message naming the line, the key and what is valid") {
  const std::string head = "[study]\nscenario = base.ini\nmodels = hard\n";
  const std::string ok = "[characterise]\nfrequencies = 10, 20\n";
  for (const auto& bad : std::vector<std::pair<std::string, std::string>>{
           {ok + "amplitudes = 0.001\n", "amplitudes has 1 value: a characterisation needs two or more on each axis"},
           {ok + "gammas = 28\n", "gammas has 1 value: a characterisation needs two or more on each axis (an axis"},
           {"[characterise]\namplitudes = 0.001, 0.002\nfrequencies = 10\n",
            "frequencies has 1 value: a characterisation needs two or more"},
           {ok + "amplitudes = -0.001, 0.002\n", "'-0.001': each amplitude (m, of the container's motion"},
           {ok + "gammas = 0, 2\n", "'0': each Gamma"},
           {ok + "amplitudes = 0.001, 0.002\ngammas = 1, 2\n", "gammas and amplitudes are both given"},
           {"[characterise]\namplitudes = 0.001, 0.002\n", "[characterise] needs frequencies"},
           {ok, "[characterise] needs amplitudes (m) or gammas"},
           {ok + "amplitudes = 0.001, 0.002\nexcitation.mode = force\n", "excitation.mode is set by [characterise]"},
           {ok + "amplitudes = 0.001, 0.002\nempty = 1\n", "empty = '1': must be true or false"},
           {ok + "amplitudes = 0.001, 0.002\nstart = predict\n",
            "start = predict: the container's motion is prescribed, there is no host response to predict"},
           {ok + "amplitudes = 0.001, 0.002\nlevels = 1\n", "levels is not an [characterise] key"},
           {ok + "amplitudes = 0.001, 0.002\nhost.mass_kg = 1, 2\n", "a grid of characterisations is not supported"},
           {ok + "amplitudes = 0.001, 0.002\n[frf]\nmode = force\nlevels = 1\nfrequencies = 10\n",
            "a study has sections of one kind"},
       }) {
    CAPTURE(bad.first);
    CHECK(error_of([&] { parse_study_file(head + bad.first, "test.ini", "t"); }).find(bad.second) != std::string::npos);
  }
  CHECK(error_of([&] {
          study_of(characterise_study("[characterise]\ngammas = 1, 2\nfrequencies = 10, 20\n"),
                   "[gravity]\ng_m_s2 = 0\n");
        }).find("gammas: Gamma = A (2 pi f)^2 / g needs gravity, and the scenario has |g| = 0") != std::string::npos);
}

TEST_CASE("a bad [characterise] study exits 2, a dry submit writes nothing") {
  test::TempDir dir("characterise-bad");
  const auto db = dir / "runs.sqlite";
  const auto file = dir / "c.ini";
  write_file(file, characterise_study("[characterise]\namplitudes = 0.001\nfrequencies = 10, 20\n"));
  const Result one = pdamp_cli({"study", "run", file.string(), "--db", db.string()}, dir);
  CHECK(one.code == 2);
  CHECK(one.err.find("amplitudes has 1 value") != std::string::npos);
  CHECK(!std::filesystem::exists(db));
  write_file(file, characterise_study("[characterise]\namplitudes = 0.001, 0.002\nfrequencies = 10, 20\n"));
  check_curve_study_submit(file, db, dir);
}

// A bed resting on the floor moves with its container: its force on it is −m_p (z'' + g), so
// m_app = m_p. The soft bed rests on contact springs far stiffer than the drive (its own
// frequency ω_b well above ω): it follows the floor to (ω/ω_b)², and its contacts' viscous
// damping shows in the first harmonic as about 2ζ (ω/ω_b)² m_p ω. The hard bed is rigid (a
// resting sphere rides the floor exactly): both zero to rounding. So |c_eq| / (m_p ω) below
// 1e-3 for both (the soft bed gives up to 3e-4 at Γ = 0.8, 20 Hz). The empty container has
// no force at all: every metric exactly 0.
TEST_CASE("a bed at rest has m_app = m_p within 1 % and c_eq about 0, the empty container exactly 0") {
  test::TempDir dir("characterise-rest");
  const auto db = dir / "runs.sqlite";
  const auto file = dir / "c.ini";
  write_file(file, characterise_study("[characterise.rest]\namplitudes = 0.0001, 0.0005\nfrequencies = 15, 20\n"
                                      "models = both\nparticles.count = 40\nmin_cycles = 8\nmeasured_cycles = 6\n\n"
                                      "[characterise.empty]\namplitudes = 0.0005, 0.003\nfrequencies = 15, 20\n"
                                      "empty = true\n"));
  const Result r = pdamp_cli({"study", "run", file.string(), "--db", db.string(), "--jobs", "2"}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  RunStore store(db);
  const auto points = StudyStore(store).characterise_points(1);
  REQUIRE(points.size() == 12);
  for (const auto& p : points) {
    CAPTURE(p.point);
    REQUIRE(p.result);
    const CharacterisationMetrics& m = p.result->metrics;
    CHECK(m.settled);
    if (p.place.empty) {
      CHECK(p.result->particle_mass_kg == 0.0);
      for (const double zero : {m.apparent_mass_kg, m.equivalent_damping_N_s_m, m.apparent_mass_spread_kg,
                                m.equivalent_damping_spread_N_s_m, m.impact_J_per_cycle, m.friction_J_per_cycle,
                                m.loss_factor, m.floor_contact_fraction, m.lid_contact_fraction}) {
        CHECK(zero == 0.0);
      }
      CHECK(p.result->free_height_m == 0.010);
      continue;
    }
    const double m_p = p.result->particle_mass_kg;
    const double omega = 2.0 * std::numbers::pi * p.place.frequency_hz;
    REQUIRE(m.gamma.has_value());
    CHECK(*m.gamma < 1.0);
    CHECK(std::abs(m.apparent_mass_kg / m_p - 1.0) < 0.01);
    CHECK(std::abs(m.equivalent_damping_N_s_m) / (m_p * omega) < 1e-3);
    CHECK(m.floor_contact_fraction == 1.0);
    CHECK(m.lid_contact_fraction == 0.0);
    CHECK(p.result->free_height_m > 0.0);
    CHECK(p.result->free_height_m < 0.010);
    CHECK(m.amplitude_m == test::relative(p.place.amplitude_m).epsilon(1e-9));
  }
  const auto png = dir / "c.png";
  const Result plot = pdamp_cli({"study", "plot", "1", "--db", db.string(), "--out", png.string()}, dir);
  INFO(plot.err);
  CHECK(plot.code == 0);
  CHECK(std::filesystem::file_size(png) > 10'000);

  // The damper table: store -> pdamp rom's table -> CSV -> JSON -> CSV, the same text, and
  // the same prediction from the store and from the file.
  const std::vector<std::string> study_table{"rom", "--study", "1", "--db", db.string()};
  auto rom = [&](std::vector<std::string> args, const std::vector<std::string>& more) {
    args.insert(args.end(), more.begin(), more.end());
    return pdamp_cli(args, dir);
  };
  const Result no_model = rom(study_table, {"--export-table", (dir / "t.csv").string()});
  CHECK(no_model.code == 2);
  CHECK(no_model.err.find("has models hard, soft: choose one with --model") != std::string::npos);
  const Result no_section = rom(study_table, {"--model", "hard", "--export-table", (dir / "t.csv").string()});
  CHECK(no_section.code == 2);
  CHECK(no_section.err.find("has sections characterise.empty, characterise.rest: choose one with --section") !=
        std::string::npos);
  // A section that did not run the model asked for: that conflict is named, not a table
  // without points. Given one, the other option may be left out where it has one choice.
  const Result conflict = rom(
      study_table, {"--model", "soft", "--section", "characterise.empty", "--export-table", (dir / "t.csv").string()});
  CHECK(conflict.code == 2);
  CHECK(conflict.err.find("--section characterise.empty and --model soft: [characterise.empty] ran no soft points, "
                          "only hard (the sections with soft points are characterise.rest)") != std::string::npos);
  CHECK(!std::filesystem::exists(dir / "t.csv"));
  const Result soft_only = rom(study_table, {"--model", "soft", "--export-table", (dir / "soft.csv").string()});
  CHECK(soft_only.code == 0);
  CHECK(read_text(dir / "soft.csv").find("[characterise.rest], soft model") != std::string::npos);
  const std::vector<std::string> rest{"--model", "hard", "--section", "characterise.rest"};
  const std::vector<std::string> host{"--mass",  "0.0376", "--stiffness", "470",      "--damping", "0.1",
                                      "--force", "0.002",  "--freq",      "15:20:11", "--quiet"};
  auto with = [](std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  REQUIRE(rom(study_table, with(with(rest, host),
                                {"--export-table", (dir / "t.csv").string(), "--out", (dir / "p_store.csv").string()}))
              .code == 0);
  // A host whose response the table does not cover at all is refused, nothing written.
  CHECK(rom(study_table, with(rest, {"--mass", "0.0376", "--stiffness", "470", "--force", "5", "--freq", "15:20:3",
                                     "--out", (dir / "p_none.csv").string()}))
            .code == 2);
  CHECK(!std::filesystem::exists(dir / "p_none.csv"));
  const std::vector<std::string> from_csv{"rom", "--table", (dir / "t.csv").string()};
  REQUIRE(
      rom(from_csv, with(host, {"--export-table", (dir / "t.json").string(), "--out", (dir / "p_file.csv").string()}))
          .code == 0);
  REQUIRE(rom({"rom", "--table", (dir / "t.json").string()}, {"--export-table", (dir / "t2.csv").string()}).code == 0);
  const std::string table_text = read_text(dir / "t.csv");
  CHECK(table_text == read_text(dir / "t2.csv"));
  CHECK(table_text.find("# source = study 1 'c', [characterise.rest], hard model") != std::string::npos);
  CHECK(table_text.find("# bed_mass_kg = ") != std::string::npos);
  auto rows = [](const std::string& text) {
    std::string kept;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
      if (!line.starts_with('#')) kept += line + "\n";
    }
    return kept;
  };
  CHECK(rows(read_text(dir / "p_store.csv")) == rows(read_text(dir / "p_file.csv")));
  CHECK(rows(read_text(dir / "p_file.csv")).size() > 200);
}

TEST_CASE("a weightless [characterise] point has no Gamma: NULL in the store, '-' in study show") {
  test::TempDir dir("characterise-weightless");
  const auto db = dir / "runs.sqlite";
  const auto file = dir / "c.ini";
  write_file(file, characterise_study("[characterise]\namplitudes = 0.0002, 0.0004\nfrequencies = 20, 30\n"
                                      "max_cycles = 12\nmeasured_cycles = 3\ngravity.g_m_s2 = 0\n"));
  const Result r = pdamp_cli({"study", "run", file.string(), "--db", db.string()}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(count_rows(db,
                   "SELECT count(*) FROM study_characterisation WHERE status = 'completed' AND gamma IS NULL AND "
                   "gravity_m_s2 = 0") == 4);
  RunStore store(db, StoreAccess::read);
  for (const auto& p : StudyStore(store).characterise_points(1)) {
    REQUIRE(p.result);
    CHECK_FALSE(p.result->metrics.gamma.has_value());
  }
  CHECK(shown_column(r.out, "Gamma") == std::vector<std::string>(4, "-"));
}

// The container's work per cycle against the bed is π c_eq ω A² (only the force's first
// harmonic works against a sinusoidal velocity), and at a steady state the bed dissipates
// it: η from the ledger equals c_eq / (m_p ω) from the force, two independent routes.
TEST_CASE("a shaken bed: the ledger's loss per cycle is the first harmonic's, the bed leaves the floor") {
  test::TempDir dir("characterise-shaken");
  const auto db = dir / "runs.sqlite";
  const auto file = dir / "c.ini";
  write_file(file, characterise_study("[characterise]\ngammas = 2, 4\nfrequencies = 15, 25\n"
                                      "amplitude_tolerance = 0.02\nphase_tolerance_rad = 0.02\nmax_cycles = 40\n"));
  const Result r = pdamp_cli({"study", "run", file.string(), "--db", db.string(), "--jobs", "2"}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  RunStore store(db);
  for (const auto& p : StudyStore(store).characterise_points(1)) {
    CAPTURE(p.point);
    REQUIRE(p.result);
    const CharacterisationMetrics& m = p.result->metrics;
    const double damping_ratio =
        m.equivalent_damping_N_s_m / (p.result->particle_mass_kg * 2.0 * std::numbers::pi * p.place.frequency_hz);
    CHECK(damping_ratio > 0.1);
    CHECK(m.loss_factor == test::relative(damping_ratio).epsilon(0.03));
    CHECK(m.apparent_mass_kg < p.result->particle_mass_kg);
    CHECK(m.floor_contact_fraction < 1.0);
    CHECK(m.impact_J_per_cycle > 0.0);
  }
  // The damper table of a Γ grid has rows of Γ, each node the stored point's values.
  const Result gammas =
      pdamp_cli({"rom", "--study", "1", "--db", db.string(), "--export-table", (dir / "t.csv").string()}, dir);
  INFO(gammas.err);
  REQUIRE(gammas.code == 0);
  const rom::DamperTable table = rom::read_damper_table(dir / "t.csv");
  CHECK(table.row_axis == rom::RowAxis::gamma);
  CHECK(table.rows == std::vector<double>{2, 4});
  CHECK(table.frequencies_hz == std::vector<double>{15, 25});
  for (const auto& p : StudyStore(store).characterise_points(1)) {
    const std::size_t i = p.place.gamma_given == 2.0 ? 0 : 1, j = p.place.frequency_hz == 15.0 ? 0 : 1;
    CHECK(table.amplitude_m(i, j) == p.place.amplitude_m);
    CHECK(table.at(i, j).m_app_kg == p.result->metrics.apparent_mass_kg);
    CHECK(table.at(i, j).c_eq_N_s_m == p.result->metrics.equivalent_damping_N_s_m);
    CHECK(table.at(i, j).settled == p.result->metrics.settled);
  }
  // No damper table from another study kind.
  write_file(dir / "s.ini",
             "[study]\nscenario = " + small() + "\nmodels = hard\n[sweep]\nrun.duration_s = 0.01, 0.02\n");
  REQUIRE(pdamp_cli({"study", "run", (dir / "s.ini").string(), "--db", db.string()}, dir).code == 0);
  const Result sweep =
      pdamp_cli({"rom", "--study", "2", "--db", db.string(), "--export-table", (dir / "s.csv").string()}, dir);
  CHECK(sweep.code == 2);
  CHECK(sweep.err.find("is not a characterisation") != std::string::npos);
  CHECK(!std::filesystem::exists(dir / "s.csv"));
}

TEST_CASE("a [characterise] study gives the same bits for any --jobs, after a SIGKILL and resuming") {
  test::TempDir dir("characterise-jobs");
  const auto file = dir / "c.ini";
  // A tolerance only a bed at rest meets: the others run their 30 cycles.
  write_file(file, characterise_study("[characterise]\namplitudes = 0.0005, 0.0015, 0.003\nfrequencies = 15, 20, 25\n"
                                      "amplitude_tolerance = 1e-9\nmax_cycles = 30\nmeasured_cycles = 5\n"));
  const auto stores = run_study_per_jobs(file, dir, {1, 2});
  CHECK(count_rows(stores.at(2), "SELECT count(*) FROM study_characterise_metrics") == 9);
  CHECK(characterise_metric_differences(stores.at(1), stores.at(2)) == 0);
  const auto [differing, compared] = sample_differences(stores.at(1), stores.at(2));
  CHECK(compared > 9 * 15);
  CHECK(differing == 0);

  // Killed once a point has a checkpoint, which then says it is of another pdamp: the point
  // is run from its start, and says so.
  const auto killed = dir / "killed.sqlite";
  kill_study_when(file, killed, dir, "study_characterisation",
                  "SELECT (SELECT count(*) >= 2 FROM study_points WHERE status = 'completed') AND (" +
                      std::string(checkpointed_unfinished_runs) + ") > 0",
                  {"--checkpoint-every", "0.01"});
  const std::string checkpointed = unfinished_checkpointed_run_ids(killed);
  REQUIRE(checkpointed != "()");
  sqlite::Database(killed).exec("UPDATE run_checkpoints SET pdamp_version = '0.0.1' WHERE run_id IN " + checkpointed);
  CHECK(count_rows(killed, "SELECT count(*) FROM study_points WHERE status = 'completed'") < 9);
  // A point's metrics, final state and completion are one transaction: none without the others.
  CHECK(count_rows(killed,
                   "SELECT count(*) FROM study_points p WHERE (p.status = 'completed') <> (EXISTS (SELECT 1 FROM "
                   "study_characterise_metrics m WHERE m.point = p.point) AND EXISTS (SELECT 1 FROM "
                   "study_point_states s WHERE s.point = p.point))") == 0);
  CHECK(count_rows(killed,
                   "SELECT count(*) FROM initial_states WHERE settle_key LIKE 'characterisation point end:%' AND "
                   "state_id NOT IN (SELECT state_id FROM study_point_states)") == 0);
  // An incomplete characterisation gives no table.
  const Result incomplete =
      pdamp_cli({"rom", "--study", "1", "--db", killed.string(), "--export-table", (dir / "t.csv").string()}, dir);
  CHECK(incomplete.code == 2);
  CHECK(incomplete.err.find("are not completed; run 'pdamp study resume 1' first") != std::string::npos);
  const Result resumed = pdamp_cli({"study", "resume", "1", "--db", killed.string(), "--jobs", "2"}, dir);
  INFO(resumed.err);
  REQUIRE(resumed.code == 0);
  CHECK(resumed.err.find("of an earlier attempt is run again from its start: run ") != std::string::npos);
  CHECK(resumed.err.find("'s checkpoint was written by pdamp 0.0.1") != std::string::npos);
  CHECK(runs_continued_by_their_points(killed, checkpointed) == 0);
  CHECK(characterise_metric_differences(stores.at(1), killed) == 0);
  CHECK(sample_differences(stores.at(1), killed).first == 0);

  // Resuming skips completed points; a changed file is refused with the difference named.
  const std::int64_t runs = count_rows(killed, "SELECT count(*) FROM runs");
  const Result again = pdamp_cli({"study", "run", file.string(), "--db", killed.string()}, dir);
  CHECK(again.code == 0);
  CHECK(count_rows(killed, "SELECT count(*) FROM runs") == runs);
  write_file(file, characterise_study("[characterise]\namplitudes = 0.0005, 0.0015, 0.004\nfrequencies = 15, 20, 25\n"
                                      "amplitude_tolerance = 1e-9\nmax_cycles = 30\nmeasured_cycles = 5\n"));
  const Result changed = pdamp_cli({"study", "run", file.string(), "--db", killed.string()}, dir);
  CHECK(changed.code == 2);
  CHECK(changed.err.find("[characterise] amplitudes: '0.0005, 0.0015, 0.004' now, '0.0005, 0.0015, 0.003' stored") !=
        std::string::npos);
}

TEST_CASE(
    "snapshots of [characterise] points: frames at their cycle boundaries, the same bits as without, after a "
    "SIGKILL too") {
  test::TempDir dir("characterise-snapshots");
  const auto file = dir / "c.ini";
  // Gamma 0.6 to 19 (the bed rides the floor, or flies), 25 cycles each.
  write_file(file, characterise_study("[characterise]\namplitudes = 0.0004, 0.003\nfrequencies = 20, 40\n"
                                      "amplitude_tolerance = 1e-9\nmax_cycles = 20\nmeasured_cycles = 5\n"));
  const auto plain = run_study_per_jobs(file, dir, {1}).at(1);
  // A frame every 0.15 s / T cycles: 3 at 20 Hz, 6 at 40 Hz.
  const std::string cycle_frames =
      "SELECT count(*) FROM run_snapshots s JOIN study_characterisation c USING (run_id) WHERE s.frames = "
      "c.cycles_run / CAST(round(0.15 * c.frequency_hz) AS INTEGER) + 1 AND abs(s.interval_s - 0.15) <= 1e-15";
  const auto db = dir / "snapshots.sqlite";
  run_study_with_snapshots(file, db, "0.15", dir);
  CHECK(characterise_metric_differences(plain, db) == 0);
  CHECK(sample_differences(plain, db).first == 0);
  CHECK(count_rows(db, cycle_frames) == 4);
  for (const std::int64_t run : {1, 2, 3, 4}) check_stored_snapshots(db, run, dir);

  // Killed once a point has a checkpoint, resumed: its snapshots go on in its folder.
  const auto killed = dir / "killed.sqlite";
  kill_and_resume_with_snapshots(file, killed, "study_characterisation", "0.15", dir);
  CHECK(characterise_metric_differences(plain, killed) == 0);
  CHECK(count_rows(killed, cycle_frames) == 4);
  for (const int point : {1, 2, 3, 4}) {
    check_stored_snapshots(
        killed, count_rows(killed, "SELECT run_id FROM study_characterisation WHERE point = " + std::to_string(point)),
        dir);
  }
}
