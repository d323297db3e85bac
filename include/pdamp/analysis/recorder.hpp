#pragma once
/// Where a run's results go as it produces them (the run store, or a test's memory).

#include "pdamp/analysis/cycle_analyzer.hpp"
#include "pdamp/model/state.hpp"

namespace pdamp {

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
};

}  // namespace pdamp
