#include "pdamp/model/host_only_engine.hpp"

namespace pdamp {

HostOnlyEngine::HostOnlyEngine(const Scenario& scenario)
    : model_(scenario), trajectory_(model_, 0.0, model_.initial_state()), load_(model_.excitation_phase()) {}

void HostOnlyEngine::advance_to(double t_s) {
  const HostTrajectory::Stretch stretch = trajectory_.stretch(t_s_, t_s, 0.0, 0.0);
  viscous_J_ += stretch.viscous_J;
  excitation_J_ += stretch.excitation_J;
  load_.add(stretch.load);
  t_s_ = t_s;
}

Observation HostOnlyEngine::observe() const {
  Observation o;
  o.t_s = t_s_;
  o.host = trajectory_.at(t_s_);
  model_.write_energy_to(o.energy, t_s_, o.host);
  o.energy.dissipated_viscous_J = viscous_J_;
  o.energy.excitation_work_J = excitation_J_;
  o.host_load = load_.value();
  return o;
}

State HostOnlyEngine::state() const { return {observe(), Particles(0)}; }

}  // namespace pdamp
