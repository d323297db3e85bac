/// The shared model's parts of a checkpoint (docs/checkpoints.md): the host's trajectory
/// and the engine of the host alone.
#include "pdamp/model/host.hpp"
#include "pdamp/model/host_only_engine.hpp"

namespace pdamp {

template <class Self, class Archive>
void HostTrajectory::transfer(Self& t, Archive& a) {
  a.section("host trajectory");
  for (auto* value : {&t.t0_s_, &t.mass_kg_, &t.offset_m_, &t.forced_sin_m_, &t.forced_cos_m_, &t.u0_m_, &t.du0_m_s_,
                      &t.decay_rate_1_s_, &t.lambda_1_s2_, &t.omega0_sq_, &t.fastest_rate_1_s_, &t.speed_bound_,
                      &t.acceleration_bound_, &t.jerk_bound_}) {
    a.io(*value);
  }
}
template void HostTrajectory::transfer(const HostTrajectory&, CheckpointWriter&);
template void HostTrajectory::transfer(HostTrajectory&, CheckpointReader&);

template <class Self, class Archive>
void HostOnlyEngine::transfer(Self& e, Archive& a) {
  a.section("host-only engine");
  a.part(e.trajectory_);
  a.io(e.t_s_);
  a.io(e.viscous_J_);
  a.io(e.excitation_J_);
  a.io(e.load_);
}
template void HostOnlyEngine::transfer(const HostOnlyEngine&, CheckpointWriter&);
template void HostOnlyEngine::transfer(HostOnlyEngine&, CheckpointReader&);

}  // namespace pdamp
