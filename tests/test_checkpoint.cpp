/// Checkpoints and resume (docs/checkpoints.md): an engine restored from a checkpoint, and
/// a run resumed from one, continue with the same bits as if they had never stopped, on
/// both engines; saving changes nothing; the store keeps a run's latest checkpoint with the
/// results up to it; `pdamp resume` refuses what it cannot continue, and continues runs
/// killed at random moments to the same rows as an uninterrupted run.
#include <doctest/doctest.h>
#include <omp.h>

#include <atomic>
#include <random>
#include <thread>
#include <tuple>

#include "engine_models.hpp"
#include "pdamp/model/placement.hpp"
#include "pdamp/sim/run.hpp"
#include "pdamp/sim/stored_run.hpp"
#include "pdamp/store/run_store.hpp"
#include "pdamp/study/point_runner.hpp"
#include "pdamp/study/study_runner.hpp"
#include "pdamp/version.hpp"
#include "soft/soft_engine_class.hpp"
#include "test_process.hpp"
#include "test_support.hpp"

using namespace pdamp;
using test::HardModel;
using test::SoftModel;

namespace {

Particles placed(const Scenario& s) { return place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m); }

/// Samples, cycles and checkpoints kept in memory.
struct MemoryRecorder final : RunRecorder {
  std::vector<SampleRecord> samples;
  std::vector<CycleRecord> cycles;
  std::vector<RunCheckpoint> checkpoints;
  void record_sample(const Observation& o, double error) override { samples.push_back({o, error}); }
  void record_cycle(const CycleRecord& c) override { cycles.push_back(c); }
  void flush() override {}
  void flush_with_checkpoint(const RunCheckpoint& c) override { checkpoints.push_back(c); }
};

const ScenarioOverrides short_run{"run.duration_s=0.1"};

}  // namespace

TEST_CASE_TEMPLATE("a run resumed from any of its checkpoints gives the same bits as the run never stopped", M,
                   SoftModel, HardModel) {
  for (const auto& mode : test::excitation_modes()) {
    CAPTURE(mode.empty() ? std::string("free") : mode[0]);
    ScenarioOverrides overrides = mode;
    overrides.push_back("run.duration_s=0.0997731");  // the last step ends off the observation grid
    const Scenario s = load_scenario(test::scenario_file("small"), overrides);
    const Particles bed = placed(s);
    // Uninterrupted without checkpoints, and with one at every observation it can.
    MemoryRecorder plain, saved;
    auto plain_engine = make_engine({M::model}, s, bed);
    REQUIRE(run_simulation(*plain_engine, s, plain).status == RunStatus::completed);
    RunControl every_observation;
    every_observation.checkpoint_interval = std::chrono::nanoseconds(1);
    auto saved_engine = make_engine({M::model}, s, bed);
    REQUIRE(run_simulation(*saved_engine, s, saved, every_observation).status == RunStatus::completed);
    // Every field equal (the records' defaulted ==: a memcmp would also compare their padding).
    CHECK(plain.samples == saved.samples);  // saving never perturbs the run
    CHECK(plain.cycles == saved.cycles);
    REQUIRE(saved.checkpoints.size() >= 20);
    CHECK(saved.checkpoints.back().t_s < s.run.duration_s);  // the state before the step off the grid

    for (const std::size_t k : {std::size_t{0}, saved.checkpoints.size() / 3, saved.checkpoints.size() - 1}) {
      const RunCheckpoint& c = saved.checkpoints[k];
      CAPTURE(c.t_s);
      MemoryRecorder resumed;
      resumed.samples.assign(plain.samples.begin(), plain.samples.begin() + c.samples);
      resumed.cycles.assign(plain.cycles.begin(), plain.cycles.begin() + c.cycles);
      CheckpointReader in(c.state);
      const RunLoopState loop = read_run_loop_state(in);
      const auto engine = restore_engine({M::model}, s, bed, in);
      const RunOutcome outcome = run_simulation(*engine, s, resumed, {}, &loop);
      CHECK(outcome.status == RunStatus::completed);
      CHECK(outcome.samples == static_cast<int>(plain.samples.size()));
      CHECK(plain.samples == resumed.samples);
      CHECK(plain.cycles == resumed.cycles);
      CHECK(engine->statistics() == plain_engine->statistics());
      test::check_same_state(engine->state(), plain_engine->state());
    }
  }
}

TEST_CASE_TEMPLATE("a stop request checkpoints the run where it stopped, and it resumes to the same bits", M, SoftModel,
                   HardModel) {
  const Scenario s = load_scenario(test::scenario_file("small"), short_run);
  const Particles bed = placed(s);
  MemoryRecorder plain;
  auto plain_engine = make_engine({M::model}, s, bed);
  REQUIRE(run_simulation(*plain_engine, s, plain).status == RunStatus::completed);
  // Requested before the first step, so inside the engine's advance: within its grace the
  // engine goes on to the next observation, where the run checkpoints.
  std::atomic<bool> stop{true};
  RunControl control;
  control.stop = &stop;
  control.checkpoint_interval = std::chrono::minutes(1);
  MemoryRecorder stopped;
  auto engine = make_engine({M::model}, s, bed);
  const RunOutcome outcome = run_simulation(*engine, s, stopped, control);
  CHECK(outcome.status == RunStatus::interrupted);
  REQUIRE(!stopped.checkpoints.empty());
  const RunCheckpoint c = stopped.checkpoints.back();
  CHECK(c.t_s > 0.0);
  CHECK(c.t_s == outcome.sim_time_s);
  CHECK(stopped.samples.size() == static_cast<std::size_t>(c.samples));
  CheckpointReader in(c.state);
  const RunLoopState loop = read_run_loop_state(in);
  const auto resumed_engine = restore_engine({M::model}, s, bed, in);
  REQUIRE(run_simulation(*resumed_engine, s, stopped, {}, &loop).status == RunStatus::completed);
  CHECK(plain.samples == stopped.samples);
  CHECK(plain.cycles == stopped.cycles);
  test::check_same_state(resumed_engine->state(), plain_engine->state());

  // Past its grace the engine stops inside its advance (here long before 1 s of the run).
  auto hasty = make_engine({M::model}, s, bed);
  hasty->set_stop_request(&stop, std::chrono::milliseconds(1));
  CHECK_THROWS_AS(hasty->advance_to(1.0), Interrupted);
}

TEST_CASE_TEMPLATE("an engine restored on two threads continues one saved on one with the same bits", M, SoftModel,
                   HardModel) {
  // 3,200 spheres: enough for the soft engine to share its passes among threads.
  const Scenario s = test::scenario_from(
      "[cavity]\ndiameter_m = 0.03\nheight_m = 0.03\n[particles]\ncount = 3200\ndiameter_m = 0.001\n");
  const Particles bed = placed(s);
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  const auto original = make_engine({M::model}, s, bed);
  original->advance_to(0.0005);
  CheckpointWriter out(RunStore::schema_version());
  original->save(out);
  const std::vector<std::byte> blob = out.finish();
  original->advance_to(0.001);
  omp_set_num_threads(2);
  CheckpointReader in(blob);
  const auto restored = restore_engine({M::model}, s, bed, in);
  restored->advance_to(0.001);
  if (M::model == Model::soft) CHECK(test::statistic(*restored, "threads_used") == 2);
  omp_set_num_threads(before);
  test::check_same_state(original->state(), restored->state());
  CHECK(original->statistics() == restored->statistics());
}

TEST_CASE("a checkpoint that is damaged, of another format or of another engine is refused") {
  const Scenario s = load_scenario(test::scenario_file("small"), short_run);
  const auto soft = make_engine({Model::soft}, s, placed(s));
  CheckpointWriter out(RunStore::schema_version());
  soft->save(out);
  std::vector<std::byte> blob = out.finish();
  {
    CheckpointReader in(blob);
    CHECK_THROWS_WITH_AS(restore_engine({Model::hard}, s, placed(s), in),
                         doctest::Contains("the checkpoint does not fit this engine"), RuntimeFailure);
  }
  blob[blob.size() / 2] ^= std::byte{1};
  CHECK_THROWS_WITH_AS(CheckpointReader{blob}, doctest::Contains("its checksum does not match"), InputError);
  blob.assign(4, std::byte{0});
  CHECK_THROWS_WITH_AS(CheckpointReader{blob}, doctest::Contains("not one pdamp wrote"), InputError);
}

namespace {

using test::pdamp_cli;
using test::Process;
using test::Result;
using test::small;

/// The rows of two runs that differ (samples and cycles, every column but the run's id):
/// runs `a` and `b` of `db`, or run `a` of `db` and run `b` of `other`.
std::int64_t differing_rows(const std::filesystem::path& db, std::int64_t a, std::int64_t b,
                            const std::filesystem::path& other = {}) {
  std::int64_t differ = 0;
  sqlite::Database d(db);
  std::string b_in = "main.";
  if (!other.empty()) {
    d.exec("ATTACH '" + other.string() + "' AS other");
    b_in = "other.";
  }
  for (const std::string table : {"samples", "cycles"}) {
    std::string columns;
    sqlite::Statement names(d, "SELECT name FROM pragma_table_info(?) WHERE name != 'run_id' ORDER BY cid");
    names.bind(1, table);
    while (names.step()) columns.append(columns.empty() ? "" : ", ").append(names.column_text(0));
    for (const auto& [x, x_in, y, y_in] :
         {std::tuple{a, std::string("main."), b, b_in}, std::tuple{b, b_in, a, std::string("main.")}}) {
      // Appended piece by piece, here and above: GCC 12's LTO warns (-Wstringop-overflow, a
      // false positive) on operator+ of these strings.
      std::string sql = "SELECT count(*) FROM (SELECT ";
      sql.append(columns).append(" FROM ").append(x_in).append(table).append(" WHERE run_id = ");
      sql.append(std::to_string(x)).append(" EXCEPT SELECT ").append(columns).append(" FROM ").append(y_in);
      sql.append(table).append(" WHERE run_id = ").append(std::to_string(y)).append(")");
      sqlite::Statement q(d, sql);
      q.step();
      differ += q.column_int(0);
    }
  }
  return differ;
}

}  // namespace

TEST_CASE("pdamp resume: runs killed by SIGKILL at random moments, several times, end as the run never stopped") {
  std::random_device seed_source;
  const unsigned seed = seed_source();
  INFO("kill times drawn with seed " << seed);
  std::mt19937 rng(seed);
  for (const std::string model : {"soft", "hard"})
    [&] {
      CAPTURE(model);
      test::TempDir dir("checkpoint-kill-" + model);
      const auto db = dir / "runs.sqlite";
      const std::string duration = model == "soft" ? "0.5" : "1.5";  // about a second of wall time each
      const std::vector<std::string> run{"run",       "--scenario",         small(),  "--model",
                                         model,       "--duration",         duration, "--db",
                                         db.string(), "--checkpoint-every", "0.05"};
      REQUIRE(pdamp_cli(run, dir).code == 0);  // run 1, uninterrupted
      RunStore store(db, StoreAccess::read);
      const std::int64_t reference_wall_ms = std::llround(1000 * store.summary(1)->wall_time_s.value());
      std::uniform_int_distribution<std::int64_t> moment(50, std::max<std::int64_t>(100, reference_wall_ms));
      Process first(run, dir);
      std::this_thread::sleep_for(std::chrono::milliseconds(moment(rng)));
      first.signal(SIGKILL);
      first.wait();
      int kills = 1;
      for (;;) {
        const auto s = store.summary(2);
        if (!s) {
          MESSAGE("killed before its run began");
          return;
        }
        if (s->status == "completed") break;
        CHECK(s->status == "dead");
        const Result runs = pdamp_cli({"runs", "--db", db.string()}, dir);
        CHECK(runs.out.find(" dead ") != std::string::npos);
        if (!store.checkpoint(2)) {  // killed before its first checkpoint: nothing to resume
          const Result refused = pdamp_cli({"resume", "2", "--db", db.string()}, dir);
          CHECK(refused.code == 2);
          CHECK(refused.err.find("has no checkpoint") != std::string::npos);
          return;
        }
        Process resume({"resume", "2", "--db", db.string(), "--checkpoint-every", "0.05"}, dir);
        if (kills < 3) {
          std::this_thread::sleep_for(std::chrono::milliseconds(moment(rng)));
          resume.signal(SIGKILL);
          ++kills;
        }
        resume.wait();
      }
      CHECK(differing_rows(db, 1, 2) == 0);
      CHECK(store.summary(2)->n_samples == store.summary(1)->n_samples);
      CHECK(store.statistics(2).size() == store.statistics(1).size());
    }();
}

TEST_CASE(
    "pdamp resume --until extends a completed run to what a longer run gives, and refusals exit 2 with the reason") {
  test::TempDir dir("checkpoint-until");
  const auto db = dir / "runs.sqlite";
  auto run = [&](const std::string& duration, const std::string& every) {
    return pdamp_cli({"run", "--scenario", small(), "--model", "hard", "--duration", duration, "--db", db.string(),
                      "--checkpoint-every", every},
                     dir);
  };
  REQUIRE(run("0.1995", "60").code == 0);  // run 1: its last step off the grid
  REQUIRE(run("0.3", "0").code == 0);      // run 2: the longer run, without checkpoints
  auto resume = [&](const std::vector<std::string>& more) {
    std::vector<std::string> args{"resume", "--db", db.string()};
    args.insert(args.end(), more.begin(), more.end());
    return pdamp_cli(args, dir);
  };
  auto refused = [&](const std::vector<std::string>& args, const std::string& why) {
    CAPTURE(why);
    const Result r = resume(args);
    CHECK(r.code == 2);
    CHECK(r.err.find(why) != std::string::npos);
  };
  refused({"1"}, "run 1 is completed (it ran to 0.1995 s); give --until T");
  refused({"1", "--until", "0.1"}, "--until 0.1 s must be beyond the end of run 1 (0.1995 s)");
  refused({"2", "--until", "0.5"}, "run 2 has no checkpoint");
  refused({"9", "--until", "0.5"}, "run 9 is not in");
  refused({"1", "--until", "-1"}, "--until '-1': must be a number of seconds above 0");
  refused({"1", "--until", "0.3", "--simd", "avx1024"}, "--simd 'avx1024': must be sse2, avx2 or avx512");
  // Resumed with another instruction set than run 2 used (the widest): the same bits.
  REQUIRE(resume({"1", "--until", "0.3", "--simd", "sse2", "--threads", "2"}).code == 0);
  CHECK(differing_rows(db, 1, 2) == 0);
  RunStore store(db);
  CHECK(store.summary(1)->duration_s == 0.3);
  CHECK(store.checkpoint(1)->checkpoint.t_s <= 0.3);
  CHECK(test::count_rows(db, "SELECT count(*) FROM run_checkpoints") == 1);  // only the latest, of run 1

  // A checkpoint of another pdamp version, and a run live in another process (its lease).
  sqlite::Database d(db);
  d.exec("UPDATE run_checkpoints SET pdamp_version = '0.0.1' WHERE run_id = 1");
  refused({"1", "--until", "0.5"}, "run 1's checkpoint was written by pdamp 0.0.1");
  // One of this pdamp under an older store schema (every checkpoint before a migration
  // that changed what it holds, e.g. schema 12's engine counters in the cycle analyzer's
  // observations) is refused as well.
  d.exec("UPDATE run_checkpoints SET pdamp_version = '" + std::string(version_string) +
         "', schema_version = " + std::to_string(RunStore::schema_version() - 1) + " WHERE run_id = 1");
  refused({"1", "--until", "0.5"}, "(store schema " + std::to_string(RunStore::schema_version() - 1) +
                                       "); this is pdamp " + std::string(version_string));
  const ProcessLease me = this_process_lease();
  d.exec("UPDATE runs SET status = 'running', lease_host = '" + me.host + "', lease_pid = " + std::to_string(me.pid) +
         ", lease_start = " + std::to_string(me.start_ticks) + " WHERE run_id = 1");
  CHECK(store.summary(1)->status == "running");
  refused({"1"}, "run 1 is live in process " + std::to_string(me.pid));
  d.exec("UPDATE runs SET lease_host = 'elsewhere' WHERE run_id = 1");
  CHECK(store.summary(1)->status == "running");  // another host's process cannot be checked from here
  const Result runs = pdamp_cli({"runs", "--db", db.string()}, dir);
  CHECK(runs.out.find("running on elsewhere") != std::string::npos);
  d.exec("UPDATE runs SET lease_host = '" + me.host + "', lease_pid = 4000000000 WHERE run_id = 1");
  CHECK(store.summary(1)->status == "dead");
}

namespace {

/// How many rows of a comparison's tables differ between comparison 1 of two stores (bit
/// for bit in every column but the ids, the creation time and the wall times), or are in
/// one only.
std::int64_t comparison_differences(const std::filesystem::path& a, const std::filesystem::path& b) {
  sqlite::Database d(a);
  d.exec("ATTACH '" + b.string() + "' AS b");
  // `same`: the columns that pair the rows of a comparison.
  auto differing = [&](const std::string& table, const std::string& same, std::initializer_list<const char*> columns) {
    std::string differs = "y.comparison_id IS NULL";
    for (const char* column : columns) differs += std::string(" OR x.") + column + " IS NOT y." + column;
    sqlite::Statement q(d, "SELECT coalesce(sum(" + differs + "), 0) + abs(count(*) - (SELECT count(*) FROM b." +
                               table + ")) FROM main." + table + " x LEFT JOIN b." + table +
                               " y ON y.comparison_id = x.comparison_id AND " + same);
    q.step();
    return q.column_int(0);
  };
  return differing("comparisons", "1",
                   {"scenario_name", "soft_run_id", "hard_run_id", "initial_state_id", "hard_restitution",
                    "envelope_max_rel_diff", "envelope_rms_rel_diff", "small_amplitude_freq_soft_hz",
                    "small_amplitude_freq_hard_hz", "gamma_below_1_soft_s", "gamma_below_1_hard_s", "psi_mean_abs_diff",
                    "dissipated_soft_J", "dissipated_hard_J", "dissipated_rel_diff", "soft_steps", "hard_events"}) +
         differing("comparison_psi_bins", "y.gamma_low = x.gamma_low",
                   {"gamma_high", "psi_soft", "psi_hard", "cycles_soft", "cycles_hard"}) +
         differing("comparison_energy", "y.t_s = x.t_s AND y.model = x.model", {"impact_J", "friction_J", "viscous_J"});
}

}  // namespace

TEST_CASE("pdamp resume of a killed comparison's run completes it: the same rows as pdamp compare uninterrupted") {
  for (const std::string killed_in : {"soft", "hard"}) {
    CAPTURE(killed_in);
    test::TempDir dir("checkpoint-compare-" + killed_in);
    const auto reference = dir / "reference.sqlite", db = dir / "runs.sqlite";
    auto compare = [&](const std::filesystem::path& store) {
      return std::vector<std::string>{"compare",      "--scenario",         small(), "--duration", "1", "--db",
                                      store.string(), "--checkpoint-every", "0.05"};
    };
    REQUIRE(pdamp_cli(compare(reference), dir).code == 0);
    // Killed once its soft (or hard) run has a checkpoint: soft about 2 s of wall time, hard 0.6 s.
    Process killed(compare(db), dir);
    const std::string checkpointed = "SELECT count(*) FROM run_checkpoints JOIN runs USING (run_id) WHERE model = '" +
                                     killed_in + "' AND status = 'running'";
    // The store's tables exist once its newest does (comparison_runs, migration 14).
    auto ready = [&] {
      return std::filesystem::exists(db) &&
             test::count_rows(db, "SELECT count(*) FROM sqlite_schema WHERE name = 'comparison_runs'") > 0 &&
             test::count_rows(db, checkpointed) > 0;
    };
    for (int i = 0; i < 20000 && !ready(); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    killed.signal(SIGKILL);
    killed.wait();
    const std::int64_t run_id = test::count_rows(db, "SELECT max(run_id) FROM runs");
    REQUIRE(test::count_rows(db, "SELECT count(*) FROM runs WHERE status = 'running'") == 1);
    CHECK(test::count_rows(db, "SELECT count(*) FROM comparisons") == 0);
    CHECK(test::count_rows(db, "SELECT count(*) FROM comparison_runs") == 1);

    const Result until = pdamp_cli({"resume", std::to_string(run_id), "--until", "2", "--db", db.string()}, dir);
    CHECK(until.code == 2);
    CHECK(until.err.find("is a run of a comparison under way (pdamp compare, soft run 1): resuming it completes the "
                         "comparison") != std::string::npos);
    const Result resumed = pdamp_cli({"resume", std::to_string(run_id), "--db", db.string()}, dir);
    INFO(resumed.err);
    REQUIRE(resumed.code == 0);
    CHECK(resumed.out.find(", soft run 1, hard run 2, hard restitution") != std::string::npos);
    CHECK(test::count_rows(db, "SELECT count(*) FROM runs") == 2);
    CHECK(test::count_rows(db, "SELECT count(*) FROM comparison_runs") == 0);
    CHECK(differing_rows(reference, 1, 1, db) == 0);
    CHECK(differing_rows(reference, 2, 2, db) == 0);
    CHECK(comparison_differences(reference, db) == 0);
  }
}

TEST_CASE("pdamp resume refuses a comparison's run without a checkpoint, changing nothing") {
  test::TempDir dir("checkpoint-compare-none");
  const auto db = dir / "runs.sqlite";
  // Killed in its soft run (about 2 s of wall time), which takes no checkpoints.
  Process killed({"compare", "--scenario", small(), "--duration", "1", "--db", db.string(), "--checkpoint-every", "0"},
                 dir);
  auto begun = [&] {
    return std::filesystem::exists(db) &&
           test::count_rows(db, "SELECT count(*) FROM sqlite_schema WHERE name = 'comparison_runs'") > 0 &&
           test::count_rows(db, "SELECT count(*) FROM comparison_runs") > 0;
  };
  for (int i = 0; i < 20000 && !begun(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  killed.signal(SIGKILL);
  killed.wait();
  REQUIRE(test::count_rows(db, "SELECT count(*) FROM runs WHERE status = 'running' AND model = 'soft'") == 1);
  const std::string samples = "SELECT count(*) FROM samples";
  const std::int64_t samples_before = test::count_rows(db, samples);
  const Result refused = pdamp_cli({"resume", "1", "--db", db.string()}, dir);
  CHECK(refused.code == 2);
  CHECK(refused.err.find("run 1 has no checkpoint") != std::string::npos);
  CHECK(test::count_rows(db, "SELECT count(*) FROM runs") == 1);
  CHECK(test::count_rows(db, samples) == samples_before);
  CHECK(test::count_rows(db, "SELECT count(*) FROM comparison_runs") == 1);
}

TEST_CASE(
    "pdamp resume refuses the run of an [frf] or [characterise] point, naming the study resume that continues it") {
  test::TempDir dir("checkpoint-curve-point");
  const auto db = dir / "runs.sqlite";
  const std::pair<std::string, std::string> sections[] = {
      {"frf", "[frf]\nmode = force\nhost.z0_m = 0\nparticles.count = 20\nlevels = 0.05\nfrequencies = 15, 17\n"},
      {"characterise", "[characterise]\namplitudes = 0.0005, 0.0015\nfrequencies = 15, 20\n"}};
  for (const auto& entry : sections) {
    const std::string& section = entry.first;  // by name: clang before 16 cannot capture a structured binding
    CAPTURE(section);
    const std::string& keys = entry.second;
    const auto file = dir / (section + ".ini");
    test::write_file(file, "[study]\nname = " + section + "\nscenario = " + small() + "\nmodels = hard\n\n" + keys);
    const study::Study s = study::make_study(study::read_study_source(file), false);
    std::int64_t study_id = 0, run_id = 0;
    {
      RunStore store(db);
      study_id = study::find_or_create_study(store, s);
      // Stopped once its run is under way: the run ends interrupted with a checkpoint.
      std::atomic<bool> stop{false};
      study::PointRunControl control;
      control.stop = &stop;
      control.checkpoint_interval = std::chrono::milliseconds(60'000);
      control.progress = [&](double, std::string_view phase) { stop = stop || phase != "settling"; };
      REQUIRE(study::run_study_point(store, study_id, s, 1, control).status == PointStatus::interrupted);
      run_id = test::count_rows(db, "SELECT max(run_id) FROM runs");
      CHECK(store.checkpoint(run_id));
    }
    const Result refused = pdamp_cli({"resume", std::to_string(run_id), "--db", db.string()}, dir);
    CHECK(refused.code == 2);
    const std::string id = std::to_string(study_id);
    CHECK(refused.err.find("run " + std::to_string(run_id) + " is the run of [" + section + "] point 1 of study " +
                           id) != std::string::npos);
    CHECK(refused.err.find("continued with its point, from its checkpoint, by 'pdamp study resume " + id + "'") !=
          std::string::npos);
    CHECK(RunStore(db, StoreAccess::read).summary(run_id)->status == "interrupted");
  }
}
