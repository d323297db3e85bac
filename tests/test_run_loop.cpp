/// The run loop (sim/run.hpp): how a run ends when its engine is interrupted inside an
/// advance, or its state stops being finite.
#include <doctest/doctest.h>

#include <limits>

#include "pdamp/errors.hpp"
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
  double time_step_s() const override { return 0.0; }

 private:
  Fault fault_;
  double fault_s_, t_s_ = 0.0;
};

struct CountSamples final : RunRecorder {
  int samples = 0;
  void record_sample(const Observation&, double) override { ++samples; }
  void record_cycle(const CycleRecord&) override {}
  void flush() override {}
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
