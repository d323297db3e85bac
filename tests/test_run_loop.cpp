/// The run loop (sim/run.hpp): how a run ends when its engine is interrupted inside an
/// advance, or its state stops being finite; the observation steps it reports.
#include <doctest/doctest.h>

#include <algorithm>
#include <limits>
#include <vector>

#include "pdamp/errors.hpp"
#include "pdamp/sim/engine_factory.hpp"
#include "pdamp/sim/run.hpp"
#include "test_support.hpp"

using namespace pdamp;

namespace {

/// An engine whose host rests at z = 0 until `fault_s`, where its state stops being finite
/// or its advance is interrupted.
class FaultyEngine final : public Engine {
 public:
  enum class Fault { non_finite, interrupted };
  FaultyEngine(Fault fault, double fault_s) : fault_(fault), fault_s_(fault_s) {}
  void advance_to(double t_s) override {
    if (t_s >= fault_s_ && fault_ == Fault::interrupted) throw Interrupted("stopped by a signal");
    t_s_ = t_s;
  }
  Observation observe() const override {
    Observation o;
    o.t_s = t_s_;
    if (t_s_ >= fault_s_) o.host.z_m = std::numeric_limits<double>::quiet_NaN();
    return o;
  }
  State state() const override { return {observe(), Particles(0)}; }
  SphereDissipation dissipation_by_sphere() const override { return {}; }
  double time_step_s() const override { return 0.0; }
  void save(CheckpointWriter& out) const override { out.put(t_s_); }
  void restore(CheckpointReader& in) override { in.get(t_s_); }

 private:
  Fault fault_;
  double fault_s_, t_s_ = 0.0;
};

struct CountSamples final : RunRecorder {
  int samples = 0;
  void record_sample(const Observation&, double) override { ++samples; }
  void record_cycle(const CycleRecord&) override {}
  void flush() override {}
  void flush_with_checkpoint(const RunCheckpoint&) override {}
};

const Scenario host_alone = test::scenario_from("[particles]\ncount = 0\n[run]\nduration_s = 0.1\n");

}  // namespace

TEST_CASE("a state that stops being finite ends the run as failed, saying so, with what came before kept") {
  FaultyEngine engine(FaultyEngine::Fault::non_finite, 0.0505);  // between observations
  CountSamples recorder;
  const RunOutcome outcome = run_simulation(engine, host_alone, recorder);
  CHECK(outcome.status == RunStatus::failed);
  CHECK(outcome.message.find("the state stopped being finite at t = 0.05") == 0);
  CHECK(recorder.samples == 51);  // t = 0, ..., 0.05 s every 1 ms
  CHECK(outcome.sim_time_s < 0.0505);
}

TEST_CASE("a stop inside the engine's advance ends the run as interrupted, with what came before kept") {
  FaultyEngine engine(FaultyEngine::Fault::interrupted, 0.0505);
  CountSamples recorder;
  const RunOutcome outcome = run_simulation(engine, host_alone, recorder);
  CHECK(outcome.status == RunStatus::interrupted);
  CHECK(outcome.message.find("stopped by a signal at t = 0.050") == 0);
  CHECK(recorder.samples == 51);
}

TEST_CASE("the run loop tells each observation's step, off the grid only at a duration between steps") {
  Scenario s = load_scenario(test::scenario_file("table1"), {"particles.count=0", "run.duration_s=0.0104"});
  const ObservationGrid grid = observation_grid(s);
  REQUIRE(grid.steps_per_sample == 3);  // 1/256 of the host's period is less than half a sample interval
  std::vector<ObservationStep> steps;
  RunControl control;
  control.at_observation = [&](const Engine& engine, const ObservationStep& step) {
    steps.push_back(step);
    const double t = engine.observe().t_s;
    if (step.on_grid) {
      CHECK(t == doctest::Approx(static_cast<double>(step.index) * grid.step_s).scale(grid.step_s).epsilon(1e-12));
    } else {
      CHECK(t == s.run.duration_s);
    }
  };
  const auto engine = make_engine({Model::hard}, s, Particles(0));
  CountSamples samples;
  REQUIRE(run_simulation(*engine, s, samples, control).status == RunStatus::completed);
  // 0.0104 s = 62.4 steps of 1/6000 s: steps 0 to 62, then the end before step 63.
  REQUIRE(steps.size() == 64);
  for (std::size_t k = 0; k < steps.size(); ++k) CHECK(steps[k].index == static_cast<std::int64_t>(k));
  CHECK(std::count_if(steps.begin(), steps.end(), [](const ObservationStep& o) { return !o.on_grid; }) == 1);
  CHECK_FALSE(steps.back().on_grid);
}
