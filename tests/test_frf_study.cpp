/// Frequency-response studies ([frf], docs/studies.md): the section's keys and their
/// mistakes, the curves a section expands into, and end to end: the host alone against its
/// closed form, the state each point hands to the next, the same bits for any --jobs and
/// after a SIGKILL mid-curve.
#include <doctest/doctest.h>

#include <csignal>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <thread>

#include "pdamp/sim/frf_point.hpp"
#include "pdamp/sim/initial_bed.hpp"
#include "pdamp/store/study_store.hpp"
#include "pdamp/study/point_runner.hpp"
#include "pdamp/study/study.hpp"
#include "study_compare.hpp"
#include "test_process.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::study;
using namespace pdamp::test;

namespace {

/// An [frf] study on small.ini with 20 spheres, hard model.
std::string frf_study(const std::string& frf, int particles = 20) {
  return "[study]\nscenario = " + small() + "\nmodels = hard\n\n[frf]\nmode = force\nhost.z0_m = 0\n" +
         "particles.count = " + std::to_string(particles) + "\n" + frf;
}

Study study_of(const std::string& text) {
  return make_study({"/tmp/frf.ini", text, small(), "[particles]\ncount = 20\n"}, false);
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

/// Runs the study in FILE into DB; the test stops there, with pdamp's stderr, if it fails.
void run_study(const std::filesystem::path& file, const std::filesystem::path& db, const TempDir& dir) {
  const Result r = pdamp_cli({"study", "run", file.string(), "--db", db.string()}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
}

/// Beds kept as a point's final state that no completed point refers to.
std::int64_t orphan_end_states(const std::filesystem::path& db) {
  return count_rows(db,
                    "SELECT count(*) FROM initial_states WHERE settle_key LIKE 'frequency-response point end:%' "
                    "AND state_id NOT IN (SELECT state_id FROM study_point_states)");
}

}  // namespace

TEST_CASE("[frf] sections: curves by model, level and direction, each point after the one before") {
  const Study s =
      study_of(frf_study("levels = 0.05, 0.2\nfrequencies = 15, 19, 17\ndirection = both\n"
                         "host_alone = true\nmodels = both\nmax_cycles = 50\n"));
  REQUIRE(s.file.frfs.size() == 1);
  const FrfSection& f = s.file.frfs[0];
  CHECK(f.frequencies == std::vector<std::string>{"15", "17", "19"});
  CHECK(f.criterion.max_cycles == 50);
  CHECK(f.criterion.consecutive_cycles == SteadyStateCriterion{}.consecutive_cycles);
  // 2 models x 2 levels x 2 directions x 3 frequencies, and the host alone's 3.
  REQUIRE(s.points.size() == 27);
  CHECK(describe_curve(s.points[0]) == "soft up, curve 1, step 1 from the bed");
  CHECK(describe_curve(s.points[1]) == "soft up, curve 1, step 2 after point 1");
  CHECK(describe_curve(s.points[3]) == "soft down, curve 2, step 1 from the bed");
  CHECK(s.points[3].frf->frequency_hz == "19");
  CHECK(describe_curve(s.points[12]) == "hard up, curve 5, step 1 from the bed");
  CHECK(describe_curve(s.points[26]) == "soft host alone up, curve 9, step 3 after point 26");
  const Scenario last = point_scenario(s, s.points[26], HostState{0.25, -1.5});
  CHECK(last.particles.count == 0);
  CHECK(last.host.z0_m == 0.25);
  CHECK(last.excitation.frequency_hz == 19.0);
  CHECK(last.run.duration_s == doctest::Approx(60.0 / 19.0).scale(1.0));
  CHECK(last.run.sample_interval_s == test::relative(1.0 / 19.0));
  const Study bed = study_of(frf_study("levels = 0.05\nfrequencies = 15:17:3\nstart = bed\n"));
  for (const auto& p : bed.points) CHECK(p.frf->previous == 0);
}

TEST_CASE("[frf] mistakes: one message naming the line, the key and what is valid") {
  const std::string head = "[study]\nscenario = a.ini\nmodels = hard\n";
  struct Bad {
    std::string text, message;
  };
  for (const Bad& bad : std::vector<Bad>{
           {head + "[frf]\nmode = free\nlevels = 1\nfrequencies = 10\n", "line 5: [frf] mode = 'free': must be force"},
           {head + "[frf]\nmode = prescribed\nlevels = 1\nfrequencies = 10\n", "prescribed motion fixes the host"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 0, 10\n", "'0': each frequency (Hz) must be > 0"},
           {head + "[frf]\nmode = force\nlevels = -1\nfrequencies = 10\n", "each level (F0 in N under a force"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 20:10:3\n", "the range is reversed"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10, 10.0\n", "the value 10.0 appears twice"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\ndirection = sideways\n",
            "direction = 'sideways': must be up, down or both"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nstart = cold\n",
            "start = 'cold': must be continue"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nhost_alone = yes\n",
            "host_alone = 'yes': must be true or false"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nmax_cycles = 0\n",
            "max_cycles = '0': must be a whole number of cycles from 1 to 100000"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nmin_cycles = 20\nmax_cycles = 10\n",
            "max_cycles = 10 is below min_cycles = 20"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\namplitude_tolerance = 0\n",
            "amplitude_tolerance = '0': must be a number > 0"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nlevel = 2\n",
            "[frf] level is not an [frf] key (valid: mode, levels"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nexcitation.frequency_hz = 3\n",
            "excitation.frequency_hz is set by [frf]"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nhost.z0_m = 0, 0.0\n",
            "line 8: [frf] host.z0_m: the value '0.0' appears twice (values 1 and 2)"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nparticles.count = 20:10:3\n",
            "line 8: [frf] particles.count: '20:10:3': the range is reversed"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nparticles.count = 10,, 20\n",
            "an empty value in the list"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nparticles.count = 10, 20\n"
                   "host.mass_kg = 1, 2, 3\nzip = particles.count host.mass_kg\n",
            "line 9: [frf] host.mass_kg has 3 values and particles.count 2: zipped keys (line 10) need as many"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nparticles.count = 10, 20\n"
                   "zip = particles.count excitation.force_N\n",
            "line 9: [frf] zip = particles.count excitation.force_N: excitation.force_N is set by [frf]"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nparticles.count = 10, 20\n"
                   "zip = particles.count host.mass_kg\n",
            "[frf] zip names host.mass_kg, which has no values in this section"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nparticles.count = 10, 20\n"
                   "zip = particles.count\n",
            "a zip names two or more keys to vary together"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nparticles.count = 10, 20\n"
                   "host.mass_kg = 1, 2\nzip = particles.count host.mass_kg\nzip = host.mass_kg particles.count\n",
            "[frf] zip is given twice"},
           {head + "[frf]\nmode = force\nlevels = 1\nfrequencies = 10\nhost.zz = 1\n",
            "'host.zz' is not a scenario key"},
           {head + "[frf]\nmode = force\nlevels = 1\n", "[frf] needs frequencies"},
           {head + "[sweep]\nhost.z0_m = 1, 2\n[frf]\nmode = force\nlevels = 1\nfrequencies = 10\n",
            "a study has sections of one kind, [sweep], [frf] or [characterise]"},
       }) {
    CAPTURE(bad.text);
    CHECK(error_of([&] { parse_study_file(bad.text, "test.ini", "t"); }).find(bad.message) != std::string::npos);
  }
}

TEST_CASE("an [frf] grid: each combination of the keys with several values has its curves, the host alone its own") {
  const std::string head = "[study]\nscenario = " + small() + "\nmodels = hard\n[frf]\nmode = force\nlevels = 0.05\n" +
                           "frequencies = 15, 17\nhost_alone = true\nhost.z0_m = 0\n";
  const Study s = study_of(head + "particles.count = 10, 20\nhost.damping_N_s_m = 0.1, 0.2\n");
  const FrfSection& f = s.file.frfs.at(0);
  CHECK(f.settings == std::vector<std::pair<std::string, std::string>>{{"host.z0_m", "0"}});
  REQUIRE(f.grid.axes.size() == 2);
  // Four combinations, the last key fastest, a curve of two points each; the host alone
  // depends on the damping only: two curves.
  REQUIRE(s.points.size() == 12);
  CHECK(describe_curve(s.points[0]) ==
        "hard up (particles.count = 10, host.damping_N_s_m = 0.1), curve 1, step 1 from the bed");
  CHECK(describe_curve(s.points[3]) ==
        "hard up (particles.count = 10, host.damping_N_s_m = 0.2), curve 2, step 2 after point 3");
  CHECK(describe_curve(s.points[7]) ==
        "hard up (particles.count = 20, host.damping_N_s_m = 0.2), curve 4, step 2 after point 7");
  CHECK(describe_curve(s.points[8]) == "hard host alone up (host.damping_N_s_m = 0.1), curve 5, step 1 from the bed");
  CHECK(describe_curve(s.points[11]) ==
        "hard host alone up (host.damping_N_s_m = 0.2), curve 6, step 2 after point 11");
  CHECK(describe_values(s.points[5]) ==
        "host.z0_m = 0, particles.count = 20, host.damping_N_s_m = 0.1, excitation.mode = force, excitation.force_N = "
        "0.05, excitation.frequency_hz = 17");
  const Scenario third = point_scenario(s, s.points[2]);
  CHECK(third.name == "frf/3 (particles.count = 10, host.damping_N_s_m = 0.2)");
  CHECK(third.particles.count == 10);
  CHECK(third.host.damping_N_s_m == 0.2);
  const Scenario alone = point_scenario(s, s.points[10]);
  CHECK(alone.particles.count == 0);
  CHECK(alone.host.damping_N_s_m == 0.2);

  // Zipped keys vary together; a key of one value (zipped or not) is set on every point.
  const Study zipped = study_of(head +
                                "particles.count = 10, 20\nhost.damping_N_s_m = 0.1, 0.2\nzip = particles.count, "
                                "host.damping_N_s_m\nhost.mass_kg = 0.05\n");
  REQUIRE(zipped.points.size() == 8);
  CHECK(describe_curve(zipped.points[2]) ==
        "hard up (particles.count = 20, host.damping_N_s_m = 0.2), curve 2, step 1 from the bed");
  CHECK(point_scenario(zipped, zipped.points[2]).host.mass_kg == 0.05);
  CHECK(describe_curve(zipped.points[6]) ==
        "hard host alone up (host.damping_N_s_m = 0.2), curve 4, step 1 from the bed");
  const Study single = study_of(head +
                                "particles.count = 10\nhost.damping_N_s_m = 0.1\nzip = particles.count "
                                "host.damping_N_s_m\n");
  CHECK(single.file.frfs.at(0).grid.axes.empty());
  CHECK(single.points.size() == 4);
  CHECK(describe_curve(single.points[0]) == "hard up, curve 1, step 1 from the bed");

  // A changed grid is a changed study, named by its key.
  const Study other = study_of(head + "particles.count = 10, 30\nhost.damping_N_s_m = 0.1, 0.2\n");
  const auto differences = study_differences(s, other);
  REQUIRE(differences.size() == 1);
  CHECK(differences[0] == "[frf] particles.count: '10, 30' now, '10, 20' stored");

  // The size limits count the grid's curves.
  CHECK(error_of([&] {
          study_of(head + "particles.count = 1:1001:1001\n");
        }).find("the study has 2004 points, more than the 1000 allowed without --force") != std::string::npos);
  CHECK(error_of([&] {
          study_of(head + "particles.count = 1:10000:10000\nhost.mass_kg = 1:10:10\n");
        }).find("more than 100000 points") != std::string::npos);
}

TEST_CASE("a bad [frf] study and too many snapshot frames exit 2 and write nothing, study submit --dry-run neither") {
  test::TempDir dir("frf-bad");
  const auto db = dir / "runs.sqlite";
  const auto file = dir / "frf.ini";
  for (const auto& [text, message] : std::vector<std::pair<std::string, std::string>>{
           {frf_study("levels = 0.1\nfrequencies = 10\nmode = base\n"), "[frf] mode is given twice"},
           {frf_study("levels = 0.1\nfrequencies = 10, 20\nrun.max_steps = 1000\n"),
            "excitation.force_N = 0.1, excitation.frequency_hz = 10): run.max_steps = 1000: observing the run"},
           // A grid value out of range: the first point that has it is named.
           {frf_study("levels = 0.1\nfrequencies = 10, 20\nhost.mass_kg = 0.05, -1\n"),
            "point 3 of 4 ([frf] host.z0_m = 0, particles.count = 20, host.mass_kg = -1"},
       }) {
    write_file(file, text);
    const Result r = pdamp_cli({"study", "run", file.string(), "--db", db.string()}, dir);
    INFO(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find(message) != std::string::npos);
    CHECK(!std::filesystem::exists(db));
  }
  write_file(file, frf_study("levels = 0.1\nfrequencies = 10\n"));
  check_curve_study_submit(file, db, dir);
  // Snapshots whose frames at the cycle boundaries would be too many.
  write_file(file, frf_study("levels = 0.1\nfrequencies = 10\nmax_cycles = 100000\n"));
  const Result many = pdamp_cli({"study", "run", file.string(), "--snapshots", "1e-9", "--db", db.string()}, dir);
  CHECK(many.code == 2);
  CHECK(many.err.find("--snapshots 1e-09: a point of up to 100010 cycles of 0.1 s, a frame every 1, would take 100011 "
                      "frames, more than the 100000") != std::string::npos);
  CHECK(!std::filesystem::exists(db));
}

TEST_CASE("an [frf] host-alone curve gives the closed-form amplitude, phase and loss factor at every point") {
  test::TempDir dir("frf-host");
  const auto db = dir / "runs.sqlite";
  const auto file = dir / "host.ini";
  write_file(dir / "base.ini", "[host]\nz0_m = 0\ndamping_N_s_m = 1\n[particles]\ncount = 0\n");
  write_file(file,
             "[study]\nscenario = base.ini\nmodels = hard\n[frf]\nmode = force\nlevels = 0.2\nfrequencies = 12, 17.8, "
             "30\ndirection = both\namplitude_tolerance = 1e-10\nphase_tolerance_rad = 1e-10\n[frf.base]\nmode = base\n"
             "levels = 0.001\nfrequencies = 12, 17.8, 30\namplitude_tolerance = 1e-10\nphase_tolerance_rad = 1e-10\n");
  const Result r = pdamp_cli({"study", "run", file.string(), "--db", db.string(), "--jobs", "2"}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("point  curve  model") != std::string::npos);
  RunStore store(db, StoreAccess::read);
  const Study s = stored_study(*StudyStore(store).study(1));
  const auto points = StudyStore(store).frf_points(1);
  REQUIRE(points.size() == 9);
  for (const auto& p : points) {
    CAPTURE(p.point);
    REQUIRE(p.result);
    const Scenario scenario = point_scenario(s, s.points.at(static_cast<std::size_t>(p.point - 1)));
    const test::ClosedForm exact = test::host_alone(scenario);
    const ResponseMetrics& m = p.result->metrics;
    const double w = scenario.excitation.angular_frequency_rad_s();
    CHECK(m.settled);
    CHECK(m.amplitude_m == test::relative(exact.amplitude_m).epsilon(1e-6));
    CHECK(std::abs(m.phase_rad - exact.phase_rad) <= 1e-6);
    CHECK(m.loss_factor == test::relative(scenario.host.damping_N_s_m * w / scenario.host.stiffness_N_m).epsilon(1e-6));
    CHECK(m.apparent_mass_kg == 0.0);
  }
}

TEST_CASE("a weightless [frf] point has no Gamma: NULL in the store, '-' in study show") {
  test::TempDir dir("frf-weightless");
  const auto db = dir / "runs.sqlite";
  const auto file = dir / "w.ini";
  write_file(file, "[study]\nscenario = " + small() +
                       "\nmodels = hard\n[frf]\nmode = base\nlevels = 0.001\nfrequencies = 15, 17\nmax_cycles = 20\n"
                       "gravity.g_m_s2 = 0\n");
  run_study(file, db, dir);
  CHECK(count_rows(db, "SELECT count(*) FROM study_frf WHERE status = 'completed' AND gamma IS NULL") == 2);
  RunStore store(db, StoreAccess::read);
  for (const auto& p : StudyStore(store).frf_points(1)) {
    REQUIRE(p.result);
    CHECK_FALSE(p.result->metrics.gamma.has_value());
    CHECK(p.result->metrics.amplitude_m > 0.0);
  }
  const Result show = pdamp_cli({"study", "show", "1", "--db", db.string()}, dir);
  CHECK(shown_column(show.out, "Gamma") == std::vector<std::string>{"-", "-"});
}

TEST_CASE("continuation: each point starts from the stored final state of the one before, bit for bit") {
  for (const Model model : {Model::hard, Model::soft}) {
    CAPTURE(to_string(model));
    test::TempDir dir("frf-continue-" + std::string(to_string(model)));
    const auto db = dir / "runs.sqlite";
    const auto file = dir / "frf.ini";
    // The soft model at its cap of 6 cycles a point, for time.
    write_file(file, "[study]\nscenario = " + small() + "\nmodels = " + std::string(to_string(model)) +
                         "\n\n[frf]\nmode = force\nhost.z0_m = 0\nparticles.count = 20\nlevels = 0.2\n"
                         "frequencies = 16, 18\n" +
                         (model == Model::hard ? "max_cycles = 40\n" : "max_cycles = 6\nmin_cycles = 2\n"));
    run_study(file, db, dir);
    RunStore store(db, StoreAccess::read);
    StudyStore studies(store);
    const Study s = stored_study(*studies.study(1));
    const auto end1 = studies.end_state(1, 1);
    REQUIRE(end1);
    // The second point's run started from the first's final state: its host and its spheres.
    const std::int64_t run2 = count_rows(db, "SELECT run_id FROM study_frf_metrics WHERE point = 2");
    CHECK(count_rows(db, "SELECT initial_state_id FROM runs WHERE run_id = " + std::to_string(run2)) == end1->state_id);
    // The stored final state is the first point's last sample, and the second point's first
    // sample (its t = 0) is that state again.
    const RunResults one = store.results(end1->run_id), two = store.results(run2);
    REQUIRE(!one.samples.empty());
    REQUIRE(!two.samples.empty());
    const Observation& last = one.samples.back().observation;
    const Observation& first = two.samples.front().observation;
    CHECK(last.t_s == end1->t_s);
    CHECK(last.host.z_m == end1->host.z_m);
    CHECK(last.host.v_m_s == end1->host.v_m_s);
    CHECK(first.t_s == 0.0);
    const Scenario second = point_scenario(s, s.points[1], end1->host);
    if (model == Model::soft) {
      CHECK(first.host.z_m == last.host.z_m);
      CHECK(first.host.v_m_s == last.host.v_m_s);
    } else {
      // The hard engine's host is the closed form z_p(t) + u(t), u0 = z0 - z_p(0) rounded
      // (model/host.hpp, HostTrajectory): at its start it gives z0 within a rounding of
      // |z_p|, the forced amplitude, as after every impulse within a run.
      const double forced_m = test::host_alone(second).amplitude_m;
      const double w = second.excitation.angular_frequency_rad_s();
      const double eps = std::numeric_limits<double>::epsilon();
      CHECK(std::abs(first.host.z_m - last.host.z_m) <= 2 * eps * (std::abs(last.host.z_m) + forced_m));
      CHECK(std::abs(first.host.v_m_s - last.host.v_m_s) <= 2 * eps * (std::abs(last.host.v_m_s) + w * forced_m));
    }
    // The excitation is continuous: F0 sin(w t) at the first point's end, after whole
    // cycles, is zero within the rounding of w t (the second starts at sin 0 = 0).
    const double w1 = 2 * std::numbers::pi * 16.0;
    CHECK(std::abs(0.2 * std::sin(w1 * end1->t_s)) <=
          0.2 * 4 * std::numeric_limits<double>::epsilon() * w1 * end1->t_s);
    // The second point's engine holds every sphere where the first left it, bit for bit.
    const Particles stored = store.load_initial_particles(end1->state_id);
    auto next = make_engine({model}, second, stored);
    const State start = next->state();
    CHECK(start.particles.position_m == stored.position_m);
    CHECK(start.particles.velocity_m_s == stored.velocity_m_s);
    CHECK(start.particles.angular_velocity_rad_s == stored.angular_velocity_rad_s);
    CHECK(start.observation.host.z_m == first.host.z_m);
    CHECK(start.observation.host.v_m_s == first.host.v_m_s);
    if (model == Model::soft) continue;
    // The first point again in this process, from its bed: its final state is the stored one.
    const Particles bed = store.load_initial_particles(
        count_rows(db, "SELECT initial_state_id FROM runs WHERE run_id = " + std::to_string(end1->run_id)));
    const Scenario first_scenario = point_scenario(s, s.points[0]);
    auto engine = make_engine({model}, first_scenario, bed);
    const FrfPointOutcome again = run_frf_point(*engine, first_scenario, point_criterion(s, s.points[0]));
    State kept{engine->observe(), stored};
    kept.observation.host = end1->host;
    test::check_same_state(engine->state(), kept);
    CHECK(engine->observe().t_s == end1->t_s);
    // The second from that state gives the stored metrics.
    auto from_kept = make_engine({model}, second, kept.particles);
    const FrfPointOutcome next_point = run_frf_point(*from_kept, second, point_criterion(s, s.points[1]));
    const auto rows = studies.frf_points(1);
    CHECK(rows[0].result->metrics.amplitude_m == again.metrics.amplitude_m);
    CHECK(rows[1].result->metrics.amplitude_m == next_point.metrics.amplitude_m);
    CHECK(rows[1].result->metrics.apparent_mass_kg == next_point.metrics.apparent_mass_kg);
    CHECK(rows[1].result->cycles_run == next_point.cycles_run);
  }
}

TEST_CASE("start = predict: a continued point starts on its predicted steady state, the bed moved with the host") {
  test::TempDir dir("frf-predict");
  write_file(dir / "base.ini", "[host]\nz0_m = 0\ndamping_N_s_m = 1\n[particles]\ncount = 0\n");
  // The host alone: the prediction is its exact steady state, so a continued point settles
  // as soon as the criterion allows (min_cycles), where plain continuation sheds a transient.
  std::map<std::string, std::vector<FrfPointRecord>> curves;
  for (const std::string start : {"predict", "continue"}) {
    const auto db = dir / (start + ".sqlite");
    const auto file = dir / (start + ".ini");
    write_file(file,
               "[study]\nscenario = base.ini\nmodels = hard\n[frf]\nmode = force\nlevels = 0.2\n"
               "frequencies = 12, 14, 16\namplitude_tolerance = 1e-9\nphase_tolerance_rad = 1e-9\n"
               "start = " +
                   start + "\n");
    run_study(file, db, dir);
    RunStore store(db, StoreAccess::read);
    curves[start] = StudyStore(store).frf_points(1);
    REQUIRE(curves[start].size() == 3);
  }
  const int min_cycles = SteadyStateCriterion{}.min_cycles;
  for (std::size_t k = 0; k < 3; ++k) {
    CAPTURE(k);
    const ResponseMetrics& predicted = curves["predict"][k].result->metrics;
    const ResponseMetrics& continued = curves["continue"][k].result->metrics;
    CHECK(predicted.settled);
    CHECK(predicted.amplitude_m == test::relative(continued.amplitude_m).epsilon(1e-6));
    if (k == 0) {
      CHECK(predicted.cycles_to_steady == continued.cycles_to_steady);  // both from the bed
    } else {
      CHECK(predicted.cycles_to_steady == min_cycles);
      CHECK(continued.cycles_to_steady > 2 * min_cycles);
    }
  }

  // With a bed: the second point's spheres are the first's final ones moved by the host's
  // shift, which the run records beside that state instead of a copy of the moved bed.
  const auto db = dir / "bed.sqlite";
  const auto file = dir / "bed.ini";
  write_file(file, frf_study("levels = 0.2\nfrequencies = 16, 18\nmax_cycles = 40\nstart = predict\n"));
  run_study(file, db, dir);
  RunStore store(db, StoreAccess::read);
  StudyStore studies(store);
  const Study s = stored_study(*studies.study(1));
  const auto end1 = studies.end_state(1, 1);
  REQUIRE(end1);
  const auto rows = studies.frf_points(1);
  const HostState shift =
      predicted_shift(rows[0].result->metrics, 2 * std::numbers::pi * 16.0, HostModel(point_scenario(s, s.points[1])));
  CHECK(std::abs(shift.z_m) > 0.0);
  const std::int64_t run2 = rows[1].result->run_id;
  const std::string of_run2 = " FROM runs WHERE run_id = " + std::to_string(run2);
  CHECK(count_rows(db, "SELECT initial_state_id" + of_run2) == end1->state_id);
  {
    sqlite::Database bed_store(db, sqlite::Access::read_only);
    sqlite::Statement recorded(bed_store, "SELECT bed_shift_z_m, bed_shift_v_m_s" + of_run2);
    REQUIRE(recorded.step());
    CHECK(recorded.column_double(0) == shift.z_m);
    CHECK(recorded.column_double(1) == shift.v_m_s);
  }
  CHECK(count_rows(db, "SELECT count(*) FROM initial_states") == 3);  // the settled bed and two end states
  const Particles before = store.load_initial_particles(end1->state_id);
  const Particles after = moved_with_host(before, shift);
  REQUIRE(after.size() == before.size());
  for (Eigen::Index i = 0; i < before.size(); ++i) {
    CHECK(after.position_m(0, i) == before.position_m(0, i));
    CHECK(after.position_m(2, i) == before.position_m(2, i) + shift.z_m);
    CHECK(after.velocity_m_s(2, i) == before.velocity_m_s(2, i) + shift.v_m_s);
    CHECK(after.angular_velocity_rad_s.col(i) == before.angular_velocity_rad_s.col(i));
  }
  const Observation first = store.results(run2).samples.front().observation;
  // To the rounding of the sum: on the scale of its terms (either may be near 0).
  CHECK(
      first.host.z_m ==
      doctest::Approx(end1->host.z_m + shift.z_m).scale(std::abs(end1->host.z_m) + std::abs(shift.z_m)).epsilon(1e-12));
  CHECK(first.host.v_m_s == doctest::Approx(end1->host.v_m_s + shift.v_m_s)
                                .scale(std::abs(end1->host.v_m_s) + std::abs(shift.v_m_s))
                                .epsilon(1e-12));
  // The run began with the moved spheres, not the stored ones.
  REQUIRE(std::abs(shift.v_m_s) > 0.0);
  const double kinetic_J = first.energy.particle_translational_J + first.energy.particle_rotational_J;
  CHECK(kinetic_J == test::relative(test::kinetic_energy(after)).epsilon(1e-12));
  CHECK(kinetic_J != test::relative(test::kinetic_energy(before)).epsilon(1e-6));
}

TEST_CASE("a point's final state and its completion are one transaction: refused, neither is stored") {
  test::TempDir dir("frf-atomic");
  const auto db = dir / "runs.sqlite";
  const auto file = dir / "frf.ini";
  write_file(file, frf_study("levels = 0.2\nfrequencies = 16\nmax_cycles = 20\n"));
  REQUIRE(pdamp_cli({"study", "run", file.string(), "--db", db.string()}, dir).code == 0);
  RunStore store(db);
  StudyStore studies(store);
  const auto rows = studies.frf_points(1);
  REQUIRE(rows.size() == 1);
  const std::int64_t beds = count_rows(db, "SELECT count(*) FROM initial_states");
  // As if another process had taken the point: its completion is refused, and the final
  // state it carried is not left behind.
  sqlite::Database other(db);
  other.exec("DELETE FROM study_frf_metrics; DELETE FROM study_point_states;");
  other.exec("UPDATE study_points SET status = 'interrupted'");
  CHECK_THROWS_AS(studies.complete_frf_point(1, 1, 1, *rows[0].result, Particles(3), 0.0), RuntimeFailure);
  CHECK(count_rows(db, "SELECT count(*) FROM initial_states") == beds);
  CHECK(count_rows(db, "SELECT count(*) FROM study_frf_metrics") == 0);
}

TEST_CASE("an [frf] study gives the same bits for any --jobs, and after a SIGKILL mid-curve and resuming") {
  test::TempDir dir("frf-jobs");
  const auto file = dir / "frf.ini";
  write_file(file, frf_study("levels = 0.05, 0.2\nfrequencies = 15, 17, 19\ndirection = both\nhost_alone = true\n"
                             "max_cycles = 60\n"));
  const auto stores = run_study_per_jobs(file, dir, {1, 3});
  CHECK(count_rows(stores.at(3), "SELECT count(*) FROM study_frf_metrics") == 15);
  CHECK(frf_metric_differences(stores.at(1), stores.at(3)) == 0);
  const auto [differing, compared] = sample_differences(stores.at(1), stores.at(3));
  CHECK(compared > 15 * 10);
  CHECK(differing == 0);

  // Killed with its workers once the first curve is under way and a point has a checkpoint:
  // resumed, that point goes on from it, and the same bits.
  const auto killed = dir / "killed.sqlite";
  kill_study_when(file, killed, dir, "study_frf",
                  "SELECT (SELECT count(*) >= 3 FROM study_points WHERE status = 'completed') AND (" +
                      std::string(checkpointed_unfinished_runs) + ") > 0",
                  {"--checkpoint-every", "0.01"});
  CHECK(count_rows(killed, "SELECT count(*) FROM study_points WHERE status = 'completed'") < 15);
  CHECK(orphan_end_states(killed) == 0);
  resume_continuing_checkpoints(killed, dir);
  CHECK(frf_metric_differences(stores.at(1), killed) == 0);
  CHECK(sample_differences(stores.at(1), killed).first == 0);
  CHECK(orphan_end_states(killed) == 0);
  CHECK(count_rows(killed, "SELECT count(*) FROM study_point_states") == 15);
}

TEST_CASE("an [frf] grid runs each key value's curve on its own: continued within it, the same bits as it alone") {
  test::TempDir dir("frf-grid");
  const auto file = dir / "grid.ini";
  // Up to 120 cycles: points of 8-30 ms, so that the kill below finds one with a checkpoint
  // (at 30 cycles some took 4 ms, within one of stop_when's slices).
  const std::string frf = "levels = 0.2\nfrequencies = 16, 18, 20\nmax_cycles = 120\n";
  write_file(file, "[study]\nname = grid\nscenario = " + small() +
                       "\nmodels = hard\n\n[frf]\nmode = force\nhost.z0_m = 0\nparticles.count = 10, 20\n" + frf);
  const auto stores = run_study_per_jobs(file, dir, {1, 2});
  const auto& db = stores.at(1);
  CHECK(count_rows(db, "SELECT count(*) FROM study_frf_metrics") == 6);
  CHECK(frf_metric_differences(db, stores.at(2)) == 0);
  const auto [differing, compared] = sample_differences(db, stores.at(2));
  CHECK(compared > 6 * 10);
  CHECK(differing == 0);

  // Each curve's points continue from their own curve's point before; each curve's first
  // from its own settled bed.
  CHECK(count_rows(db,
                   "SELECT count(*) FROM study_frf_points WHERE previous_point IS NOT "
                   "(CASE WHEN point IN (1, 4) THEN NULL ELSE point - 1 END)") == 0);
  CHECK(count_rows(db,
                   "SELECT count(*) FROM study_frf f JOIN runs r USING (run_id) JOIN study_point_states s ON "
                   "s.study_id = f.study_id AND s.point = f.previous_point WHERE r.initial_state_id = s.state_id") ==
        4);
  CHECK(count_rows(db,
                   "SELECT count(DISTINCT r.initial_state_id) FROM study_frf f JOIN runs r USING (run_id) "
                   "WHERE f.step = 1") == 2);
  // The key values: in each point's scenario name, its values and its curve's grid.
  CHECK(count_rows(db,
                   "SELECT count(*) FROM study_frf f JOIN runs r USING (run_id) WHERE f.point = 4 AND "
                   "r.scenario_name = 'grid/4 (particles.count = 20)' AND f.grid = 'particles.count = 20'") == 1);
  CHECK(count_rows(db,
                   "SELECT count(*) FROM study_point_values WHERE key = 'particles.count' AND number = "
                   "CASE WHEN point <= 3 THEN 10 ELSE 20 END") == 6);
  CHECK(count_rows(db, "SELECT count(*) FROM (SELECT grid FROM study_frf GROUP BY grid, curve)") == 2);

  // The curve of 20 spheres is the same bits as an [frf] study of it alone.
  const auto alone = dir / "alone.sqlite";
  const auto alone_file = dir / "alone.ini";
  write_file(alone_file, frf_study(frf));
  run_study(alone_file, alone, dir);
  CHECK(frf_metric_differences(db, alone, 3) == 0);
  const auto [alone_differing, alone_compared] = sample_differences(db, alone, 3);
  CHECK(alone_compared > 3 * 10);
  CHECK(alone_differing == 0);

  // Shown and drawn one curve per key value.
  const Result shown = pdamp_cli({"study", "show", "1", "--db", db.string()}, dir);
  CHECK(shown.code == 0);
  CHECK(shown.out.find("  grid\n") != std::string::npos);
  CHECK(shown.out.find("particles.count = 10\n") != std::string::npos);
  const auto png = dir / "grid.png";
  const Result drawn = pdamp_cli({"study", "plot", "1", "--db", db.string(), "--out", png.string()}, dir);
  INFO(drawn.err);
  CHECK(drawn.code == 0);
  CHECK(std::filesystem::file_size(png) > 10'000);

  // Killed with its workers once a point has a checkpoint, resumed: the same bits.
  const auto killed = dir / "killed.sqlite";
  kill_study_when(file, killed, dir, "study_frf", "SELECT (" + std::string(checkpointed_unfinished_runs) + ") > 0",
                  {"--checkpoint-every", "0.01"});
  CHECK(count_rows(killed, "SELECT count(*) FROM study_points WHERE status = 'completed'") < 6);
  resume_continuing_checkpoints(killed, dir);
  CHECK(frf_metric_differences(db, killed) == 0);
  CHECK(sample_differences(db, killed).first == 0);
  CHECK(orphan_end_states(killed) == 0);
}

TEST_CASE(
    "snapshots of [frf] points: frames at their cycle boundaries, the same bits as without, after a SIGKILL too") {
  test::TempDir dir("frf-snapshots");
  const auto file = dir / "frf.ini";
  // Up to 120 cycles, as the grid test's: points long enough for the kill below to find one
  // with a checkpoint.
  write_file(file, frf_study("levels = 0.2\nfrequencies = 16, 18\nmax_cycles = 120\n"));
  const auto plain = run_study_per_jobs(file, dir, {1}).at(1);
  // Every other cycle at 16 Hz (0.1 s / 0.0625 s rounds to 2) and at 18 Hz (1.8 rounds to 2).
  const auto db = dir / "snapshots.sqlite";
  run_study_with_snapshots(file, db, "0.1", dir);
  CHECK(frf_metric_differences(plain, db) == 0);
  CHECK(sample_differences(plain, db).first == 0);
  CHECK(count_rows(db,
                   "SELECT count(*) FROM run_snapshots s JOIN study_frf f USING (run_id) WHERE s.frames = "
                   "f.cycles_run / 2 + 1 AND abs(s.interval_s - 2 / f.frequency_hz) <= 1e-15") == 2);
  for (const std::int64_t run : {1, 2}) check_stored_snapshots(db, run, dir);

  // Killed once a point has a checkpoint, resumed: its snapshots go on in its folder.
  const auto killed = dir / "killed.sqlite";
  kill_and_resume_with_snapshots(file, killed, "study_frf", "0.1", dir);
  CHECK(frf_metric_differences(plain, killed) == 0);
  CHECK(count_rows(killed,
                   "SELECT count(*) FROM run_snapshots s JOIN study_frf f USING (run_id) WHERE s.frames = "
                   "f.cycles_run / 2 + 1") == 2);
  for (const std::int64_t run : {count_rows(killed, "SELECT run_id FROM study_frf WHERE point = 1"),
                                 count_rows(killed, "SELECT run_id FROM study_frf WHERE point = 2")}) {
    check_stored_snapshots(killed, run, dir);
  }
}

TEST_CASE("a start = predict [frf] study killed in a predicted point and resumed: from its checkpoint, the same bits") {
  test::TempDir dir("frf-predict-kill");
  const auto file = dir / "frf.ini";
  // 40 spheres: with 20, a point ran in milliseconds, and the study could end before a
  // predicted point was seen running with a checkpoint.
  write_file(file, frf_study("levels = 0.05, 0.2\nfrequencies = 15, 17, 19\nmax_cycles = 60\nstart = predict\n", 40));
  const auto reference = run_study_per_jobs(file, dir, {2}).at(2);
  CHECK(count_rows(reference, "SELECT count(*) FROM study_frf_metrics") == 6);

  // Killed with its workers once a predicted point (one that continues another) has a
  // checkpoint: resumed, that point goes on from it, on the bed predicted before the kill.
  const auto killed = dir / "killed.sqlite";
  kill_study_when(file, killed, dir, "study_frf",
                  "SELECT count(*) FROM run_checkpoints JOIN runs r USING (run_id) JOIN study_point_runs l "
                  "USING (run_id) JOIN study_frf_points f ON f.study_id = l.study_id AND f.point = l.point "
                  "WHERE r.status <> 'completed' AND f.previous_point IS NOT NULL",
                  {"--checkpoint-every", "0.01"});
  CHECK(count_rows(killed, "SELECT count(*) FROM study_points WHERE status = 'completed'") < 6);
  resume_continuing_checkpoints(killed, dir);
  CHECK(frf_metric_differences(reference, killed) == 0);
  CHECK(frf_metric_differences(killed, reference) == 0);
  // A completed point keeps its end state, not its run's last checkpoint.
  CHECK(count_rows(killed, "SELECT count(*) FROM run_checkpoints") == 0);
  const auto [differing, compared] = sample_differences(reference, killed);
  CHECK(compared > 6 * 10);
  CHECK(differing == 0);
  CHECK(cycle_differences(reference, killed).first == 0);
  CHECK(orphan_end_states(killed) == 0);
  // Each continued point's completed run started from the previous point's end state, moved
  // by its recorded shift (a run the kill cut short before its first checkpoint stays, the
  // point ran again): no bed is stored for a start.
  const std::string predicted_starts =
      "SELECT count(*) FROM runs r JOIN study_point_states s ON s.state_id = r.initial_state_id "
      "WHERE r.status = 'completed' AND r.bed_shift_z_m IS NOT NULL AND r.bed_shift_v_m_s IS NOT NULL";
  CHECK(count_rows(killed, predicted_starts) == 4);
  CHECK(count_rows(reference, predicted_starts) == 4);
  CHECK(count_rows(killed, "SELECT count(*) FROM initial_states") == 1 + 6);  // the settled bed, six end states
}

TEST_CASE("pdamp study plot draws an [frf] study's response") {
  test::TempDir dir("frf-plot");
  const auto db = (dir / "runs.sqlite").string();
  const auto file = dir / "frf.ini";
  write_file(file, frf_study("levels = 0.05\nfrequencies = 15, 17\nhost_alone = true\nmax_cycles = 30\n"));
  REQUIRE(pdamp_cli({"study", "run", file.string(), "--db", db}, dir).code == 0);
  const auto png = dir / "frf.png";
  const Result r = pdamp_cli({"study", "plot", "1", "--db", db, "--out", png.string()}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(std::filesystem::file_size(png) > 10'000);
  CHECK(pdamp_cli({"study", "plot", "1", "--db", db, "--metric", "psi_peak"}, dir).code == 2);
}
