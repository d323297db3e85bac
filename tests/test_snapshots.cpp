/// Snapshots for ParaView: each engine's share of the losses by sphere, the checks of the
/// settings, and the files read back by VTK's own reader (tools/check_snapshots.py, with
/// Debian's python3-vtk9), against the engines' states and the stored samples.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <set>
#include <thread>
#include <vector>

#include "pdamp/errors.hpp"
#include "pdamp/model/placement.hpp"
#include "pdamp/sim/engine_factory.hpp"
#include "pdamp/sim/run.hpp"
#include "pdamp/sim/snapshots.hpp"
#include "pdamp/store/run_store.hpp"
#include "study_compare.hpp"
#include "test_process.hpp"
#include "test_support.hpp"

using namespace pdamp;

namespace {

constexpr Model both_models[] = {Model::soft, Model::hard};

/// Three 1 mm spheres in a wide cavity without gravity, on a host at rest: two about to
/// meet off-centre (a sliding impact), the third far from both.
Scenario free_space() {
  return test::scenario_from(
      "[host]\nz0_m = 0\nv0_m_s = 0\n[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = 0.05\nheight_m = 0.05\n"
      "[particles]\ncount = 3\ndiameter_m = 0.001\n");
}

struct Discard final : RunRecorder {
  void record_sample(const Observation&, double) override {}
  void record_cycle(const CycleRecord&) override {}
  void flush() override {}
  void flush_with_checkpoint(const RunCheckpoint&) override {}
};

struct Result {
  int code;
  std::string out, err;
};

Result run(const std::string& executable, const std::vector<std::string>& args, const test::TempDir& dir,
           const std::string& stem) {
  test::Process p(executable, args, dir, stem);
  const int code = p.wait();
  return {code, p.out(), p.err()};
}

/// tools/check_snapshots.py on a collection, with VTK's reader: fails, with its report, if
/// python3-vtk9 is missing.
Result check_with_vtk(const std::filesystem::path& collection, const std::vector<std::string>& options,
                      const test::TempDir& dir) {
  std::vector<std::string> args{(test::source_dir() / "tools" / "check_snapshots.py").string(), collection.string()};
  args.insert(args.end(), options.begin(), options.end());
  return run("/usr/bin/python3", args, dir, "check_snapshots");
}

/// Writes every sphere of `engine` as the checker reads it: a line `frame t`, then per
/// sphere id, centre, radius, velocity, spin, impact and friction losses, to 17 digits.
void dump_state(std::ostream& out, const Engine& engine) {
  const State state = engine.state();
  const SphereDissipation lost = engine.dissipation_by_sphere();
  const Particles& p = state.particles;
  char line[512];
  std::snprintf(line, sizeof line, "frame %.17g\n", state.observation.t_s);
  out << line;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    std::snprintf(line, sizeof line, "%ld %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n",
                  static_cast<long>(i), p.position_m(0, i), p.position_m(1, i), p.position_m(2, i), p.radius_m[i],
                  p.velocity_m_s(0, i), p.velocity_m_s(1, i), p.velocity_m_s(2, i), p.angular_velocity_rad_s(0, i),
                  p.angular_velocity_rad_s(1, i), p.angular_velocity_rad_s(2, i), lost.impact_J[i], lost.friction_J[i]);
    out << line;
  }
}

std::string message_of(const SnapshotSettings& settings, const Scenario& scenario) {
  try {
    check_snapshot_settings(settings, scenario);
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

}  // namespace

TEST_CASE("two spheres meeting in free space: each takes half of the losses, a sphere apart none") {
  for (const Model model : both_models) {
    CAPTURE(to_string(model));
    const Scenario s = free_space();
    const Particles p = test::spheres({{-0.002, 0.0, 0.025}, {0.002, 0.0003, 0.025}, {0.0, 0.01, 0.025}},
                                      {{0.5, 0.0, 0.0}, {-0.5, 0.0, 0.0}, {0.0, 0.0, 0.0}});
    const auto engine = make_engine({model}, s, p);
    engine->advance_to(0.01);
    const EnergyLedger ledger = engine->observe().energy;
    const SphereDissipation lost = engine->dissipation_by_sphere();
    REQUIRE(ledger.dissipated_impact_J > 0.0);
    REQUIRE(ledger.dissipated_friction_J > 0.0);
    CHECK(lost.impact_J[0] == lost.impact_J[1]);
    CHECK(lost.friction_J[0] == lost.friction_J[1]);
    CHECK(lost.impact_J[2] == 0.0);
    CHECK(lost.friction_J[2] == 0.0);
    test::check_dissipation_by_sphere(*engine);
  }
}

TEST_CASE("a sphere bouncing to rest on the floor keeps all of its losses") {
  for (const Model model : both_models) {
    CAPTURE(to_string(model));
    const Scenario s = test::scenario_from(
        "[host]\nz0_m = 0\nv0_m_s = 0\n[cavity]\ndiameter_m = 0.02\nheight_m = 0.02\n[particles]\ncount = 1\n"
        "diameter_m = 0.001\n");
    const auto engine = make_engine({model}, s, test::spheres({{0.001, 0.0, 0.005}}, {{0.1, 0.0, 0.0}}));
    engine->advance_to(0.5);
    const EnergyLedger ledger = engine->observe().energy;
    const SphereDissipation lost = engine->dissipation_by_sphere();
    REQUIRE(ledger.dissipated_impact_J > 0.0);
    REQUIRE(ledger.dissipated_friction_J > 0.0);
    CHECK(lost.impact_J[0] == ledger.dissipated_impact_J);
    CHECK(lost.friction_J[0] == ledger.dissipated_friction_J);
  }
}

TEST_CASE("small.ini, both models: every sphere's share of the losses adds up to the ledger's") {
  const Scenario s = load_scenario(test::scenario_file("small"));
  const Particles placed = place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m);
  for (const Model model : both_models) {
    CAPTURE(to_string(model));
    const auto engine = make_engine({model}, s, placed);
    engine->advance_to(s.run.duration_s);
    test::check_dissipation_by_sphere(*engine);
    const SphereDissipation lost = engine->dissipation_by_sphere();
    CHECK(lost.impact_J.minCoeff() > 0.0);  // every sphere took part
    if (model == Model::hard) {
      // Collisions with the riding bed share their losses with the rider, resting spheres keep theirs.
      CHECK(test::statistic(*engine, "events_rider") > 0);
      CHECK(test::statistic(*engine, "bed_rests") > 0);
    }
  }
}

TEST_CASE("snapshot settings are refused, naming the value, before anything is written") {
  test::TempDir dir("snapshot-settings");
  const Scenario table1 = load_scenario(test::scenario_file("table1"));
  const std::filesystem::path folder = dir / "frames";
  // Table 1 observes every 1/6000 s (a sample interval of 0.5 ms in three steps).
  CHECK(message_of({0.01, folder}, table1) == "accepted");
  CHECK(message_of({0.0005 / 3.0, folder}, table1) == "accepted");
  CHECK(message_of({0.0, folder}, table1).find("--snapshots 0: must be a positive, finite number") == 0);
  CHECK(message_of({-0.01, folder}, table1).find("--snapshots -0.01: must be a positive") == 0);
  CHECK(message_of({std::nan(""), folder}, table1).find("--snapshots nan: must be a positive") == 0);
  CHECK(message_of({HUGE_VAL, folder}, table1).find("--snapshots inf: must be a positive") == 0);
  const std::string between = message_of({0.0001, folder}, table1);
  CHECK(between.find(
            "--snapshots 0.0001: frames are taken where the run loop observes the engine, every 0.000166667 s") == 0);
  CHECK(between.find("give a whole multiple of it, e.g. 0.000166667 s") != std::string::npos);
  const Scenario long_run = load_scenario(test::scenario_file("table1"), {"run.duration_s=30"});
  const std::string many = message_of({0.0005 / 3.0, folder}, long_run);
  CHECK(many.find("would take 180001 frames, more than the 100000 a run may write") != std::string::npos);
  std::ofstream(dir / "a-file") << "not a folder";
  CHECK(message_of({0.01, dir / "a-file"}, table1)
            .find("--snapshot-dir '" + (dir / "a-file").string() + "' cannot be used: '") == 0);
  CHECK(message_of({0.01, dir / "a-file" / "frames"}, table1)
            .find("cannot be created: '" + (dir / "a-file").string() + "' is not a folder") != std::string::npos);
  CHECK_THROWS_WITH_AS(parse_snapshot_settings("0.01s", "", folder), doctest::Contains("--snapshots '0.01s'"),
                       InputError);
  CHECK_FALSE(std::filesystem::exists(folder));
}

TEST_CASE("snapshots of both engines, read back by VTK, hold the engines' states at their times") {
  test::TempDir dir("snapshots-vtk");
  const Scenario s = load_scenario(test::scenario_file("small"), {"run.duration_s=0.05"});
  const Particles placed = place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m);
  const SnapshotSettings settings{0.005, dir / "frames"};
  check_snapshot_settings(settings, s);
  for (const Model model : both_models) {
    CAPTURE(to_string(model));
    const std::int64_t run_id = model == Model::soft ? 1 : 2;
    const auto engine = make_engine({model}, s, placed);
    SnapshotWriter writer(settings, s, run_id);
    std::ofstream dump(dir / ("dump-" + std::to_string(run_id)));
    RunControl control;
    control.at_observation = [&](const Engine& e, const ObservationStep& step) {
      const std::int64_t frames = writer.frames();
      writer.at_observation(e, step);
      if (writer.frames() > frames) dump_state(dump, e);
    };
    Discard discard;
    REQUIRE(run_simulation(*engine, s, discard, control).status == RunStatus::completed);
    dump.close();
    CHECK(writer.frames() == 11);
    CHECK(writer.files().collection ==
          dir / "frames" / ("run-" + std::to_string(run_id)) / ("run-" + std::to_string(run_id) + ".pvd"));
    const Result checked =
        check_with_vtk(writer.files().collection, {"--dump", (dir / ("dump-" + std::to_string(run_id))).string()}, dir);
    INFO(checked.err);
    CHECK(checked.code == 0);
    CHECK(checked.out.find("11 frames") != std::string::npos);
  }
}

TEST_CASE("a run's folder that already holds files is not written into") {
  test::TempDir dir("snapshots-taken");
  const Scenario s = load_scenario(test::scenario_file("small"));
  std::filesystem::create_directories(dir / "run-1");
  std::ofstream(dir / "run-1" / "spheres_000000.vtp") << "another store's run 1";
  CHECK_THROWS_WITH_AS(SnapshotWriter({0.01, dir.path()}, s, 1), doctest::Contains("already holds files"),
                       RuntimeFailure);
  CHECK_NOTHROW(SnapshotWriter({0.01, dir.path()}, s, 2));
}

TEST_CASE("pdamp compare --snapshots: VTK reads every frame of both runs, and they agree with the stored samples") {
  test::TempDir dir("snapshots-cli");
  const auto db = dir / "runs.sqlite";
  const Result r = run(PDAMP_EXECUTABLE,
                       {"compare", "--scenario", test::scenario_file("small").string(), "--duration", "0.1",
                        "--snapshots", "0.01", "--db", db.string()},
                       dir, "pdamp");
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("pdamp: 11 snapshots of run 2: " + (dir / "runs.snapshots" / "run-2" / "run-2.pvd").string()) !=
        std::string::npos);
  for (const std::int64_t run_id : {1, 2}) {
    const std::string run_name = "run-" + std::to_string(run_id);
    // The default folder is beside the store, named after it.
    const auto collection = dir / "runs.snapshots" / run_name / (run_name + ".pvd");
    const Result checked = check_with_vtk(collection, {"--db", db.string(), "--run", std::to_string(run_id)}, dir);
    INFO(checked.err);
    CHECK(checked.code == 0);
    CHECK(checked.out.find("11 frames") != std::string::npos);
    const Result shown = run(PDAMP_EXECUTABLE, {"show", std::to_string(run_id), "--db", db.string()}, dir, "show");
    CHECK(shown.out.find("snapshots               11 frames every 0.01 s: " + collection.string()) !=
          std::string::npos);
  }
}

TEST_CASE("pdamp study run --snapshots: every run of every point has its frames, and the same bits as without") {
  test::TempDir dir("snapshots-study");
  const auto file = dir / "study.ini";
  std::ofstream(file) << "[study]\nscenario = " << test::scenario_file("small").string()
                      << "\nmodels = both\n[sweep]\nhost.damping_N_s_m = 0.1, 0.3\nrun.duration_s = 0.05\n";
  const auto plain = dir / "plain.sqlite", shot = dir / "shot.sqlite";
  Result r = run(PDAMP_EXECUTABLE, {"study", "run", file.string(), "--db", plain.string()}, dir, "plain");
  REQUIRE(r.code == 0);
  // Two workers, each writing where the study runner would have.
  r = run(PDAMP_EXECUTABLE,
          {"study", "run", file.string(), "--db", shot.string(), "--jobs", "2", "--snapshots", "0.01", "--snapshot-dir",
           (dir / "frames").string()},
          dir, "snapshots");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto [differing, compared] = test::sample_differences(plain, shot);
  CHECK(compared == 4 * 101);
  CHECK(differing == 0);
  CHECK(test::metric_differences(plain, shot) == 0);
  CHECK(test::count_rows(shot, "SELECT count(*) FROM run_snapshots WHERE frames = 6") == 4);
  for (const std::int64_t run_id : {1, 2, 3, 4}) {
    const std::string run_name = "run-" + std::to_string(run_id);
    const Result checked = check_with_vtk(dir / "frames" / run_name / (run_name + ".pvd"),
                                          {"--db", shot.string(), "--run", std::to_string(run_id)}, dir);
    INFO(checked.err);
    CHECK(checked.code == 0);
    CHECK(checked.out.find("6 frames") != std::string::npos);
  }

  // Checked for every point before anything is written.
  const auto refused = dir / "refused.sqlite";
  r = run(PDAMP_EXECUTABLE,
          {"study", "run", file.string(), "--db", refused.string(), "--snapshots", "0.0002", "--snapshot-dir",
           (dir / "other").string()},
          dir, "refused");
  CHECK(r.code == 2);
  CHECK(r.err.find(": point 1 of 2 ([sweep] host.damping_N_s_m = 0.1, run.duration_s = 0.05): --snapshots 0.0002") !=
        std::string::npos);
  CHECK(r.err.find("give a whole multiple of it") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(refused));
  CHECK_FALSE(std::filesystem::exists(dir / "other"));
}

TEST_CASE("bad snapshot options exit with code 2, name the value and write nothing") {
  test::TempDir dir("snapshots-cli-bad");
  const auto db = dir / "runs.sqlite";
  std::ofstream(dir / "a-file") << "not a folder";
  const std::string small = test::scenario_file("small").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases{
      {{"--snapshots", "0"}, "--snapshots 0: must be a positive, finite number"},
      {{"--snapshots", "-1"}, "--snapshots -1: must be a positive, finite number"},
      {{"--snapshots", "nan"}, "--snapshots nan: must be a positive, finite number"},
      {{"--snapshots", "inf"}, "--snapshots inf: must be a positive, finite number"},
      {{"--snapshots", "often"}, "--snapshots 'often': must be a number of seconds"},
      {{"--snapshots", "0.0002"}, "give a whole multiple of it"},
      {{"--snapshots", "0.0005", "--duration", "60"}, "would take 120001 frames"},
      {{"--snapshots", "0.01", "--snapshot-dir", (dir / "a-file" / "frames").string()}, "is not a folder"},
      {{"--snapshot-dir", (dir / "frames").string()}, "--snapshot-dir needs --snapshots EVERY_S"},
  };
  for (const auto& [options, message] : cases) {
    const auto& expected = message;  // by name: clang before 16 cannot capture a structured binding
    for (const char* command : {"run", "compare"}) {
      std::vector<std::string> args{command, "--scenario", small, "--db", db.string()};
      if (std::string(command) == "run") args.insert(args.end(), {"--model", "hard"});
      args.insert(args.end(), options.begin(), options.end());
      CAPTURE(command);
      CAPTURE(expected);
      const Result r = run(PDAMP_EXECUTABLE, args, dir, "pdamp");
      CHECK(r.code == 2);
      CHECK(r.err.find(expected) != std::string::npos);
    }
  }
  CHECK_FALSE(std::filesystem::exists(db));
  CHECK_FALSE(std::filesystem::exists(dir / "runs.snapshots"));
  CHECK_FALSE(std::filesystem::exists(dir / "frames"));
}

namespace {

std::string file_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// The files of run `a`'s snapshot folder that differ from run `b`'s, or are in one only
/// (each run's collection named after it); their number of files in `files`.
int differing_snapshot_files(const std::filesystem::path& directory, std::int64_t a, std::int64_t b, int& files) {
  const std::string name_a = "run-" + std::to_string(a), name_b = "run-" + std::to_string(b);
  auto names = [&](const std::string& run) {
    std::set<std::string> found;
    for (const auto& entry : std::filesystem::directory_iterator(directory / run)) {
      const std::string name = entry.path().filename().string();
      found.insert(name == run + ".pvd" ? std::string("collection") : name);
    }
    return found;
  };
  const std::set<std::string> of_a = names(name_a), of_b = names(name_b);
  files = static_cast<int>(of_a.size());
  int differing = of_a == of_b ? 0 : 1;
  for (const std::string& name : of_a) {
    if (!of_b.count(name)) continue;
    const auto in = [&](const std::string& run) {
      return directory / run / (name == "collection" ? run + ".pvd" : name);
    };
    if (file_bytes(in(name_a)) != file_bytes(in(name_b))) {
      MESSAGE(name << " differs");
      ++differing;
    }
  }
  return differing;
}

}  // namespace

TEST_CASE("pdamp resume continues a killed run's snapshots: the same files, byte for byte, as the run never stopped") {
  for (const std::string model : {"soft", "hard"}) {
    CAPTURE(model);
    test::TempDir dir("snapshots-resume-" + model);
    const auto db = dir / "runs.sqlite", frames = dir / "frames";
    // Seconds of wall time each on a quiet machine, several times the 0.4 s after which
    // the kill below comes, so that the run cannot end first.
    const std::string duration = model == "soft" ? "1.0" : "6", later = model == "soft" ? "1.5" : "6.5";
    auto run_args = [&](const std::string& every) {
      return std::vector<std::string>{"run",
                                      "--scenario",
                                      test::scenario_file("small").string(),
                                      "--model",
                                      model,
                                      "--duration",
                                      duration,
                                      "--db",
                                      db.string(),
                                      "--snapshots",
                                      "0.01",
                                      "--snapshot-dir",
                                      frames.string(),
                                      "--checkpoint-every",
                                      every};
    };
    REQUIRE(test::pdamp_cli(run_args("60"), dir).code == 0);  // run 1, uninterrupted
    // Run 2 (checkpoints every 0.3 s of wall time) killed once it has written a frame after
    // its latest checkpoint, which the resumed run writes again.
    const auto frames_written = [&] {  // each frame a file of spheres and one of the cavity, and the .pvd
      return std::distance(std::filesystem::directory_iterator(frames / "run-2"),
                           std::filesystem::directory_iterator()) /
             2;
    };
    test::Process killed(run_args("0.3"), dir, "pdamp", test::Group::own);
    // The store read with a short lock wait (store_is_ready): a run stopped while it commits
    // holds its lock, which RunStore would wait a minute for.
    const bool frame_after_checkpoint = test::stop_when(killed, [&] {
      std::int64_t written = 0;
      try {
        written = frames_written();
      } catch (const std::filesystem::filesystem_error&) {  // no folder yet
        return false;
      }
      char last_frame_s[32];
      std::snprintf(last_frame_s, sizeof last_frame_s, "%.17g", static_cast<double>(written - 1) * 0.01);
      return test::store_is_ready(
          db, "run_checkpoints",
          "SELECT count(*) FROM run_checkpoints WHERE run_id = 2 AND t_s < " + std::string(last_frame_s));
    });
    CHECK(frame_after_checkpoint);
    killed.kill_group();
    RunStore store(db, StoreAccess::read);
    REQUIRE(store.summary(2)->status == "dead");
    const double checkpoint_s = store.checkpoint(2)->checkpoint.t_s;
    const std::int64_t frames_before_kill = frames_written();
    INFO("killed at its checkpoint at " << checkpoint_s << " s with " << frames_before_kill << " frames written");
    CHECK(static_cast<double>(frames_before_kill - 1) * 0.01 > checkpoint_s);

    const test::Result refused = test::pdamp_cli({"resume", "2", "--db", db.string(), "--snapshots", "0.02"}, dir);
    CHECK(refused.code == 2);
    CHECK(refused.err.find("pdamp resume takes no --snapshots: a resumed run continues the snapshots it was started "
                           "with") != std::string::npos);
    const test::Result resumed = test::pdamp_cli({"resume", "2", "--db", db.string()}, dir);
    INFO(resumed.err);
    REQUIRE(resumed.code == 0);
    int files = 0;
    CHECK(differing_snapshot_files(frames, 1, 2, files) == 0);
    const int expected_frames = static_cast<int>(std::lround(std::stod(duration) / 0.01)) + 1;
    CHECK(files == 2 * expected_frames + 1);
    CHECK(test::count_rows(db, "SELECT frames FROM run_snapshots WHERE run_id = 2") == expected_frames);
    const Result checked = check_with_vtk(frames / "run-2" / "run-2.pvd", {"--db", db.string(), "--run", "2"}, dir);
    INFO(checked.err);
    CHECK(checked.code == 0);
    CHECK(checked.out.find(std::to_string(expected_frames) + " frames") != std::string::npos);

    // A frame before the checkpoint gone, or the folder: refused, nothing changed.
    const auto first = frames / "run-2" / "cavity_000000.vtp";
    std::filesystem::rename(first, dir / "moved.vtp");
    const test::Result missing = test::pdamp_cli({"resume", "2", "--until", later, "--db", db.string()}, dir);
    CHECK(missing.code == 2);
    CHECK(missing.err.find("run 2's snapshots (every 0.01 s in '" + (frames / "run-2").string() +
                           "') cannot be continued: '" + first.string() +
                           "', a frame before its checkpoint, is gone") != std::string::npos);
    std::filesystem::rename(frames / "run-2", dir / "moved");
    const test::Result gone = test::pdamp_cli({"resume", "2", "--until", later, "--db", db.string()}, dir);
    CHECK(gone.code == 2);
    CHECK(gone.err.find("cannot be continued: the folder is gone") != std::string::npos);
    CHECK(store.summary(2)->status == "completed");
    CHECK(store.summary(2)->duration_s == std::stod(duration));
  }
}
