#include "pdamp/sim/run_checkpoint.hpp"

#include "pdamp/store/run_store.hpp"

namespace pdamp {

template <class Self, class Archive>
void CycleAnalyzer::transfer(Self& c, Archive& a) {
  a.section("cycle analysis");
  for (auto* value : {&c.mass_kg_, &c.equilibrium_z_m_, &c.gravity_m_s2_, &c.z_min_m_, &c.max_kinetic_J_}) a.io(*value);
  a.io(c.previous_);
  a.io(c.before_previous_);
  a.io(c.crest_);
  a.io(c.armed_);
  a.io(c.cycles_);
}
template void CycleAnalyzer::transfer(const CycleAnalyzer&, CheckpointWriter&);
template void CycleAnalyzer::transfer(CycleAnalyzer&, CheckpointReader&);

namespace {

/// What a run has recorded so far, both ways.
template <class Outcome, class Archive>
void transfer_outcome(Outcome& outcome, Archive& a) {
  a.io(outcome.samples);
  a.io(outcome.cycles);
  for (auto* value :
       {&outcome.sim_time_s, &outcome.wall_time_s, &outcome.initial_energy_J, &outcome.energy_balance_rel_err}) {
    a.io(*value);
  }
}

/// The run loop's part, both ways.
template <class Loop, class Archive>
void transfer_loop(Loop& loop, Archive& a) {
  a.section("run loop");
  a.io(loop.interval);
  a.io(loop.step);
  transfer_outcome(loop.outcome, a);
  a.part(loop.cycles);
}

/// A cycle-by-cycle point's part, both ways.
template <class Loop, class Archive>
void transfer_cycle_loop(Loop& loop, Archive& a) {
  a.section("cycle-by-cycle loop");
  transfer_outcome(loop.outcome, a);
  a.io(loop.log.boundaries);
  a.io(loop.log.touches);
}

template <class Loop>
RunCheckpoint checkpoint_of(const Loop& loop, void (*transfer)(const Loop&, CheckpointWriter&), const Engine& engine,
                            double t_s) {
  CheckpointWriter out(RunStore::schema_version());
  transfer(loop, out);
  out.section("engine");
  engine.save(out);
  return {t_s, loop.outcome.samples, loop.outcome.cycles, out.finish()};
}

}  // namespace

RunCheckpoint save_checkpoint(const RunLoopState& loop, const Engine& engine, double t_s) {
  return checkpoint_of(loop, &transfer_loop<const RunLoopState, CheckpointWriter>, engine, t_s);
}

RunCheckpoint save_checkpoint(const CycleLoopState& loop, const Engine& engine, double t_s) {
  return checkpoint_of(loop, &transfer_cycle_loop<const CycleLoopState, CheckpointWriter>, engine, t_s);
}

RunLoopState read_run_loop_state(CheckpointReader& in) {
  RunLoopState loop{0, 0, {}, CycleAnalyzer(0.0, 0.0, 0.0)};
  transfer_loop(loop, in);
  in.section("engine");
  return loop;
}

CycleLoopState read_cycle_loop_state(CheckpointReader& in) {
  CycleLoopState loop;
  transfer_cycle_loop(loop, in);
  in.section("engine");
  return loop;
}

}  // namespace pdamp
