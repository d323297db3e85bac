/// The engine contract (docs/architecture.md), written once and run on both models: the
/// energy books, the same bits for any thread count, vertical momentum with a free host,
/// the host alone on its closed form, and what a stored run holds.
#include <doctest/doctest.h>
#include <omp.h>

#include <cmath>
#include <random>

#include "engine_models.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/model/placement.hpp"
#include "pdamp/sim/stored_run.hpp"
#include "pdamp/store/run_store.hpp"
#include "test_support.hpp"

using namespace pdamp;
using test::HardModel;
using test::SoftModel;

namespace {

Particles placed(const Scenario& s) { return place_particles(s.particles, s.cavity, HostModel(s).initial_state().z_m); }

/// The placement with every sphere moving at `speed_m_s` in a random direction and
/// spinning at about `spin_rad_s`: collisions from the start.
Particles moving(const Scenario& s, double speed_m_s, double spin_rad_s) {
  Particles p = placed(s);
  std::mt19937_64 rng(9);
  std::normal_distribution<double> normal;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    p.velocity_m_s.col(i) = speed_m_s * Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
    p.angular_velocity_rad_s.col(i) = spin_rad_s * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  }
  return p;
}

}  // namespace

TEST_CASE_TEMPLATE("contract: E(0) + W = E + D in every excitation mode, each sphere's share adding up", M, SoftModel,
                   HardModel) {
  for (const auto& mode : test::excitation_modes()) {
    CAPTURE(mode.empty() ? std::string("free") : mode[0]);
    const Scenario s = load_scenario(test::scenario_file("small"), mode);
    const auto engine = make_engine({M::model}, s, placed(s));
    const double e0 = engine->observe().energy.stored_J();
    double worst = 0;
    for (int k = 1; k <= 50; ++k) {
      engine->advance_to(0.001 * k);
      worst = std::max(worst, engine->observe().energy.balance_relative_error(e0));
    }
    CHECK(worst <= M::balance_tolerance);
    const EnergyLedger ledger = engine->observe().energy;
    CHECK(ledger.dissipated_impact_J > 0);
    CHECK(ledger.dissipated_friction_J > 0);
    test::check_dissipation_by_sphere(*engine);
  }
}

TEST_CASE_TEMPLATE("contract: one thread or two, the same bits", M, SoftModel, HardModel) {
  // 3,200 spheres: enough for the soft engine to share its passes among threads.
  const Scenario s = test::scenario_from(
      "[cavity]\ndiameter_m = 0.03\nheight_m = 0.03\n[particles]\ncount = 3200\ndiameter_m = 0.001\n");
  const Particles bed = moving(s, 0.2, 100.0);
  auto run_on = [&](int threads) {
    omp_set_num_threads(threads);
    const auto engine = make_engine({M::model}, s, bed);
    engine->advance_to(0.0005);
    return engine->state();
  };
  const int before = omp_get_max_threads();
  const State one = run_on(1), two = run_on(2);
  omp_set_num_threads(before);
  CHECK(one.observation.energy.dissipated_impact_J > 0);
  test::check_same_state(one, two);
}

TEST_CASE_TEMPLATE("contract: spheres and a free host conserve vertical momentum", M, SoftModel, HardModel) {
  // A free host with a negligible spring (its impulse over the run is below 1e-20 N s), no
  // damper, no gravity: M v_h + Σ m v_z is constant whatever the spheres hit (caps: normal
  // impulse; side wall: friction).
  const Scenario s = test::scenario_from(
      "[host]\nmass_kg = 0.002\nstiffness_N_m = 1e-20\ndamping_N_s_m = 0\nz0_m = 0\nv0_m_s = 0.05\n"
      "[gravity]\ng_m_s2 = 0\n[cavity]\ndiameter_m = 0.008\nheight_m = 0.006\n"
      "[particles]\ncount = 40\ndiameter_m = 0.001\n[hard]\nen = 0.7\nmu = 0.4\nbeta0 = 0.3\n");
  const auto engine = make_engine({M::model}, s, moving(s, 0.3, 200.0));
  auto momentum = [&] {
    const State st = engine->state();
    double p = s.host.mass_kg * st.observation.host.v_m_s;
    for (Eigen::Index i = 0; i < st.particles.size(); ++i)
      p += st.particles.mass_kg[i] * st.particles.velocity_m_s(2, i);
    return p;
  };
  const double p0 = momentum();
  const double scale = s.host.mass_kg * 0.05 + 40 * 4e-6 * 0.3;
  double worst = 0;
  for (int k = 1; k <= 50; ++k) {
    engine->advance_to(0.002 * k);
    worst = std::max(worst, std::abs(momentum() - p0));
  }
  CHECK(worst <= M::momentum_tolerance * scale);
  CHECK(engine->observe().energy.dissipated_impact_J > 0);
  CHECK(engine->observe().energy.dissipated_friction_J > 0);
  if constexpr (M::model == Model::hard) {  // every kind of collision was among them
    CHECK(test::statistic(*engine, "events_cap") > 50);
    CHECK(test::statistic(*engine, "events_wall") > 50);
    CHECK(test::statistic(*engine, "events_sphere_sphere") > 50);
  }
}

TEST_CASE_TEMPLATE("contract: without spheres either model runs the host alone on its exact free decay", M, SoftModel,
                   HardModel) {
  // make_engine gives the host-alone engine for a scenario without spheres, whatever the
  // model: the soft and hard engines size their cells by their spheres and need one at least.
  // Table 1's host released from z0 = 15.7 mm: z = z0 e^{-αt} (cos ω_d t + α/ω_d sin ω_d t).
  const Scenario s = load_scenario(test::scenario_file("table1"), {"particles.count=0"});
  const auto engine = make_engine({M::model}, s, Particles(0));
  const double m = 0.0376, k = 470, c = 0.1, z0 = 0.0157;
  const double alpha = c / (2 * m), wd = std::sqrt(k / m - alpha * alpha);
  const double e0 = engine->observe().energy.stored_J();
  double worst = 0, worst_balance = 0;
  for (int step = 1; step <= 1000; ++step) {
    const double t = 0.001 * step;
    engine->advance_to(t);
    const Observation o = engine->observe();
    const double envelope = z0 * std::exp(-alpha * t);
    const double exact = envelope * (std::cos(wd * t) + alpha / wd * std::sin(wd * t));
    worst = std::max(worst, std::abs(o.host.z_m - exact) / envelope);
    worst_balance = std::max(worst_balance, o.energy.balance_relative_error(e0));
  }
  CHECK(worst <= 1e-9);
  CHECK(worst_balance <= 1e-12);
  CHECK(engine->observe().energy.dissipated_viscous_J > 0.5 * e0);  // e^{-2αt}: 7 % left after 1 s
  CHECK(engine->observe().energy.dissipated_impact_J == 0.0);
}

TEST_CASE_TEMPLATE("contract: a stored run holds its samples, cycles, statistics, bed and books", M, SoftModel,
                   HardModel) {
  test::TempDir dir("contract-store");
  RunStore store(dir / "runs.sqlite");
  const Scenario s = load_scenario(test::scenario_file("small"), {"particles.count=30", "run.duration_s=0.1"});
  const InitialBed bed{placed(s), std::nullopt, false, 0.0};
  const StoredRun run = run_and_store(
      store, plan_run(M::model, s), [&]() -> const InitialBed& { return bed; }, RunControl{});
  REQUIRE(run.outcome.status == RunStatus::completed);
  const auto summary = store.summary(run.run_id);
  REQUIRE(summary);
  CHECK(summary->model == to_string(M::model));
  CHECK(summary->n_particles == 30);
  CHECK(summary->sim_time_s == 0.1);
  const auto samples = std::lround(s.run.duration_s / s.run.sample_interval_s) + 1;  // both ends included
  CHECK(summary->n_samples == samples);
  REQUIRE(summary->energy_balance_rel_err);
  CHECK(*summary->energy_balance_rel_err <= M::balance_tolerance);
  CHECK(!store.statistics(run.run_id).empty());
  const RunResults results = store.results(run.run_id);
  REQUIRE(std::ssize(results.samples) == samples);
  CHECK(results.samples.front().observation.t_s == 0.0);
  CHECK(results.samples.back().observation.t_s == 0.1);
  double worst = 0;
  for (const SampleRecord& sample : results.samples) worst = std::max(worst, sample.energy_balance_rel_err);
  CHECK(worst <= *summary->energy_balance_rel_err);  // the run's is over every observation, denser than samples
  CHECK(results.samples.back().observation.energy.dissipated_J() > 0);
  CHECK(!results.cycles.empty());  // small.ini's host cycles at ~20 Hz
}

TEST_CASE("the table of engines: each model once, in Model's order, parsed from its name, the others named") {
  REQUIRE(engine_kinds().size() == 2);
  for (std::size_t i = 0; i < engine_kinds().size(); ++i) {
    const EngineKind& kind = engine_kinds()[i];
    CHECK(static_cast<std::size_t>(kind.model) == i);
    CHECK(&engine_kind(kind.model) == &kind);
    CHECK(parse_model(kind.name) == kind.model);
    CHECK(to_string(kind.model) == kind.name);
  }
  CHECK_THROWS_WITH_AS(
      parse_model("squishy"),
      "--model 'squishy': must be 'soft' (time-stepped Hertz DEM) or 'hard' (event-driven hard spheres)", InputError);
}
