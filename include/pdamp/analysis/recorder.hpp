#pragma once
/// Where a run's results go as it produces them (the run store, or a test's memory).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "pdamp/analysis/cycle_analyzer.hpp"
#include "pdamp/model/state.hpp"

namespace pdamp {

/// A run's state at one observation (docs/checkpoints.md), with what it had recorded then.
struct RunCheckpoint {
  double t_s = 0.0;          ///< the observation's time
  std::int64_t samples = 0;  ///< samples and cycles recorded up to it
  std::int64_t cycles = 0;
  std::vector<std::byte> state;  ///< the run loop's and the engine's (CheckpointWriter)
};

class RunRecorder {
 public:
  virtual ~RunRecorder() = default;
  RunRecorder() = default;
  RunRecorder(const RunRecorder&) = delete;
  RunRecorder& operator=(const RunRecorder&) = delete;

  virtual void record_sample(const Observation& sample, double energy_balance_rel_err) = 0;
  virtual void record_cycle(const CycleRecord& cycle) = 0;
  /// Makes everything recorded so far durable.
  virtual void flush() = 0;
  /// Makes everything recorded so far durable together with `checkpoint`, at once, as the
  /// run's latest (the samples and cycles recorded after it included: resuming drops them).
  virtual void flush_with_checkpoint(const RunCheckpoint& checkpoint) = 0;
};

}  // namespace pdamp
