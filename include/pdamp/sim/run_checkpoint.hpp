#pragma once
/// A run's checkpoint as the run loop takes it (docs/checkpoints.md): its own state, then
/// the engine's, in one blob.

#include "pdamp/analysis/recorder.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/sim/run.hpp"

namespace pdamp {

/// The checkpoint of a run whose loop stands at `loop` with `engine` at t_s.
RunCheckpoint save_checkpoint(const RunLoopState& loop, const Engine& engine, double t_s);

}  // namespace pdamp
