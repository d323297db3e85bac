/// The comparison of a soft and a hard run as a function of their results: synthetic runs
/// whose metrics are known by hand, and the store's round trip of what it compares.
#include <doctest/doctest.h>

#include <cmath>

#include "pdamp/compare/comparison.hpp"
#include "pdamp/errors.hpp"
#include "test_support.hpp"

using namespace pdamp;

namespace {

CycleRecord cycle(int number, double t_start_s, double t_end_s, double amplitude_m, double freq_hz,
                  std::optional<double> gamma, double psi) {
  return {number, t_start_s, t_end_s, amplitude_m, freq_hz, gamma, psi, psi, 0.0, 0.0, 1.0};
}

/// Samples every 0.1 s up to `end_s`, dissipating `rate_J_s` times (1, 2, 3) by impact,
/// friction and the damper; the counters count 100 per second (riding spheres none).
std::vector<SampleRecord> samples(double end_s, double rate_J_s) {
  std::vector<SampleRecord> out;
  for (int i = 0; i / 10.0 <= end_s; ++i) {
    SampleRecord s;
    const double t = i / 10.0;
    s.observation.t_s = t;
    s.observation.energy.dissipated_impact_J = rate_J_s * t;
    s.observation.energy.dissipated_friction_J = 2 * rate_J_s * t;
    s.observation.energy.dissipated_viscous_J = 3 * rate_J_s * t;
    s.observation.counters = {10 * i, 100 * i, i, std::nullopt};  // none riding: stored as NULL
    out.push_back(s);
  }
  return out;
}

/// The soft run: five cycles of amplitude 1 m whose mid-times are 0.5, 1.5, ... 4.5 s;
/// Γ = 4 for two cycles, then 0.5.
RunResults soft_run() {
  RunResults run{1, samples(1.0, 1.0), {}, 10.0};
  run.cycles = {cycle(1, 0, 1, 1.0, 10, 4.0, 0.1), cycle(2, 1, 2, 1.0, 10, 4.0, 0.3), cycle(3, 2, 3, 1.0, 20, 0.5, 0.2),
                cycle(4, 3, 4, 1.0, 22, 0.5, 0.2), cycle(5, 4, 5, 1.0, 24, std::nullopt, 0.9)};
  return run;
}

/// The hard run: amplitude 1, 2, ... 5 m at mid-times 0, 1, ... 4 s (so 1.5, 2.5, 3.5, 4.5 m
/// at the soft run's first four mid-times, and none at its fifth); Γ = 6, 6, 0.7.
RunResults hard_run() {
  RunResults run{2, samples(0.8, 0.5), {}, 2.5};
  run.cycles = {cycle(1, -0.5, 0.5, 1.0, 11, 6.0, 0.5), cycle(2, 0.5, 1.5, 2.0, 11, 6.0, 0.7),
                cycle(3, 1.5, 2.5, 3.0, 30, 0.7, 0.4), cycle(4, 2.5, 3.5, 4.0, 30, std::nullopt, 0.1),
                cycle(5, 3.5, 4.5, 5.0, 30, std::nullopt, 0.1)};
  return run;
}

}  // namespace

TEST_CASE("compare_runs: the envelope, the frequency and the onset of Γ < 1 of two known runs") {
  const ComparisonRecord c = compare_runs(soft_run(), hard_run());
  CHECK(c.soft_run_id == 1);
  CHECK(c.hard_run_id == 2);
  // |hard - soft| / (the soft run's first amplitude) at 0.5, 1.5, 2.5, 3.5 s: 0.5, 1.5, 2.5, 3.5.
  REQUIRE(c.envelope_max_rel_diff);
  CHECK(*c.envelope_max_rel_diff == doctest::Approx(3.5).scale(1.0).epsilon(1e-15));
  REQUIRE(c.envelope_rms_rel_diff);
  CHECK(*c.envelope_rms_rel_diff == doctest::Approx(std::sqrt(21.0 / 4)).scale(1.0).epsilon(1e-15));
  // The mean frequency of the cycles with Γ < 1, and where the first of them starts.
  CHECK(c.small_amplitude_freq_soft_hz == 21.0);
  CHECK(c.small_amplitude_freq_hard_hz == 30.0);
  CHECK(c.gamma_below_1_soft_s == 2.0);
  CHECK(c.gamma_below_1_hard_s == 1.5);
}

TEST_CASE("compare_runs: ψ by Γ bin (2^k up to 2^(k+1)), each model's mean and count, the mean difference where both") {
  const ComparisonRecord c = compare_runs(soft_run(), hard_run());
  // Γ 0.5 (soft) and 0.7 (hard) fall in [0.5, 1), Γ 4 (soft) and 6 (hard) in [4, 8); no
  // cycle falls in between, and a cycle without Γ (microgravity) in no bin.
  REQUIRE(c.psi_bins.size() == 2);
  const auto& low = c.psi_bins[0];
  CHECK(low.gamma_low == 0.5);
  CHECK(low.gamma_high == 1.0);
  REQUIRE(low.psi_soft);
  REQUIRE(low.psi_hard);
  CHECK(*low.psi_soft == test::relative(0.2));
  CHECK(*low.psi_hard == test::relative(0.4));
  CHECK(low.cycles_soft == 2);
  CHECK(low.cycles_hard == 1);
  const auto& high = c.psi_bins[1];
  CHECK(high.gamma_low == 4.0);
  CHECK(high.gamma_high == 8.0);
  REQUIRE(high.psi_soft);
  REQUIRE(high.psi_hard);
  CHECK(*high.psi_soft == test::relative(0.2));
  CHECK(*high.psi_hard == test::relative(0.6));
  CHECK(high.cycles_soft == 2);
  CHECK(high.cycles_hard == 2);
  REQUIRE(c.psi_mean_abs_diff);
  CHECK(*c.psi_mean_abs_diff == test::relative((0.2 + 0.4) / 2));
}

TEST_CASE("compare_runs: the energy dissipated at fixed times up to the shorter run, the counts and wall times") {
  const ComparisonRecord c = compare_runs(soft_run(), hard_run());
  // At the end of each run: 6 J per second for 1 s, 3 J per second for 0.8 s.
  CHECK(c.dissipated_soft_J == doctest::Approx(6.0).scale(1.0));
  CHECK(c.dissipated_hard_J == doctest::Approx(2.4).scale(1.0));
  REQUIRE(c.dissipated_rel_diff);
  CHECK(*c.dissipated_rel_diff == doctest::Approx(-0.6).scale(1.0));
  // 0.05 s (the last sample before it is at 0), 0.1, 0.2, 0.5 s and the hard run's end, 0.8 s.
  const double times[] = {0.05, 0.1, 0.2, 0.5, 0.8};
  REQUIRE(c.energy.size() == 2 * std::size(times));
  for (std::size_t i = 0; i < std::size(times); ++i) {
    const auto& soft = c.energy[2 * i];
    const auto& hard = c.energy[2 * i + 1];
    CAPTURE(times[i]);
    CHECK(soft.t_s == times[i]);
    CHECK(soft.model == "soft");
    CHECK(hard.model == "hard");
    const double sampled_s = i == 0 ? 0.0 : times[i];
    CHECK(soft.impact_J == doctest::Approx(sampled_s).scale(1.0));
    CHECK(soft.friction_J == doctest::Approx(2 * sampled_s).scale(1.0));
    CHECK(soft.viscous_J == doctest::Approx(3 * sampled_s).scale(1.0));
    CHECK(hard.impact_J == doctest::Approx(0.5 * sampled_s).scale(1.0));
    CHECK(hard.viscous_J == doctest::Approx(1.5 * sampled_s).scale(1.0));
  }
  CHECK(c.wall_time_soft_s == 10.0);
  CHECK(c.wall_time_hard_s == 2.5);
  CHECK(c.wall_time_ratio == 4.0);
  CHECK(c.soft_steps == 100);   // the soft run's last sample (1 s): 10 steps per 0.1 s
  CHECK(c.hard_events == 800);  // the hard run's last sample (0.8 s): 100 events per 0.1 s
}

TEST_CASE("compare_runs: runs without cycles have no cycle metrics, a run without samples is refused") {
  RunResults soft = soft_run(), hard = hard_run();
  soft.cycles.clear();
  hard.cycles.clear();
  const ComparisonRecord c = compare_runs(soft, hard);
  CHECK_FALSE(c.envelope_max_rel_diff);
  CHECK_FALSE(c.small_amplitude_freq_soft_hz);
  CHECK_FALSE(c.gamma_below_1_hard_s);
  CHECK(c.psi_bins.empty());
  CHECK_FALSE(c.psi_mean_abs_diff);
  CHECK(c.dissipated_soft_J == doctest::Approx(6.0).scale(1.0));
  hard.samples.clear();
  CHECK_THROWS_WITH_AS(compare_runs(soft, hard), doctest::Contains("run 2 has no samples"), InputError);
}

TEST_CASE("RunStore::results reads back the samples and cycles a run stored, in order") {
  test::TempDir dir("comparison-results");
  RunStore store(dir / "runs.sqlite");
  const std::int64_t id = store.begin_run({"hard", "synthetic", "", 1, 3, 5.0});
  const RunResults written = hard_run();
  store.append_results(id, written.samples, written.cycles);
  store.finish_run(id, {RunStatus::completed, "", 0.8, 2.5, 0.0, 0.0});
  const RunResults read = store.results(id);
  CHECK(read.run_id == id);
  CHECK(read.wall_time_s == 2.5);
  REQUIRE(read.samples.size() == written.samples.size());
  for (std::size_t i = 0; i < read.samples.size(); ++i) {
    const Observation &r = read.samples[i].observation, &w = written.samples[i].observation;
    CHECK(r.t_s == w.t_s);
    CHECK(r.energy.dissipated_friction_J == w.energy.dissipated_friction_J);
    CHECK(r.counters == w.counters);
    CHECK_FALSE(r.counters.riding_spheres.has_value());
  }
  REQUIRE(read.cycles.size() == written.cycles.size());
  for (std::size_t i = 0; i < read.cycles.size(); ++i) {
    CHECK(read.cycles[i].cycle == written.cycles[i].cycle);
    CHECK(read.cycles[i].t_start_s == written.cycles[i].t_start_s);
    CHECK(read.cycles[i].gamma == written.cycles[i].gamma);
    CHECK(read.cycles[i].psi == written.cycles[i].psi);
  }
  CHECK_THROWS_WITH_AS(store.results(id + 1), doctest::Contains("is not in"), InputError);
}
