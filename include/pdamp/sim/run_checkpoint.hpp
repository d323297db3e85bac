#pragma once
/// A run's checkpoint as its loop takes it (docs/checkpoints.md): the loop's own state (the
/// run loop's, or a point's run cycle by cycle), then the engine's, in one blob.

#include "pdamp/analysis/recorder.hpp"
#include "pdamp/model/engine.hpp"
#include "pdamp/sim/frf_point.hpp"
#include "pdamp/sim/run.hpp"

namespace pdamp {

/// The checkpoint of a run whose loop stands at `loop` with `engine` at t_s.
RunCheckpoint save_checkpoint(const RunLoopState& loop, const Engine& engine, double t_s);
/// The checkpoint of a point run cycle by cycle (frf_point.hpp), at a cycle boundary.
RunCheckpoint save_checkpoint(const CycleLoopState& loop, const Engine& engine, double t_s);

}  // namespace pdamp
