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

/// The run loop's part, both ways.
template <class Loop, class Archive>
void transfer_loop(Loop& loop, Archive& a) {
  a.section("run loop");
  a.io(loop.interval);
  a.io(loop.step);
  a.io(loop.outcome.samples);
  a.io(loop.outcome.cycles);
  for (auto* value : {&loop.outcome.sim_time_s, &loop.outcome.wall_time_s, &loop.outcome.initial_energy_J,
                      &loop.outcome.energy_balance_rel_err}) {
    a.io(*value);
  }
  a.part(loop.cycles);
}

}  // namespace

RunCheckpoint save_checkpoint(const RunLoopState& loop, const Engine& engine, double t_s) {
  CheckpointWriter out(RunStore::schema_version());
  transfer_loop(loop, out);
  out.section("engine");
  engine.save(out);
  return {t_s, loop.outcome.samples, loop.outcome.cycles, out.finish()};
}

RunLoopState read_run_loop_state(CheckpointReader& in) {
  RunLoopState loop{0, 0, {}, CycleAnalyzer(0.0, 0.0, 0.0)};
  transfer_loop(loop, in);
  in.section("engine");
  return loop;
}

}  // namespace pdamp
