#include "pdamp/model/host_only_engine.hpp"

namespace pdamp {

HostOnlyEngine::HostOnlyEngine(const Scenario& scenario)
    : model_(scenario), trajectory_(model_, 0.0, model_.initial_state()) {}

void HostOnlyEngine::advance_to(double t_s) {
  viscous_J_ += trajectory_.viscous_dissipation_J(t_s_, t_s);
  excitation_J_ += trajectory_.excitation_work_J(t_s_, t_s);
  t_s_ = t_s;
}

Observation HostOnlyEngine::observe() const {
  Observation o;
  o.t_s = t_s_;
  o.host = trajectory_.at(t_s_);
  model_.write_energy_to(o.energy, t_s_, o.host);
  o.energy.dissipated_viscous_J = viscous_J_;
  o.energy.excitation_work_J = excitation_J_;
  return o;
}

State HostOnlyEngine::state() const { return {observe(), Particles(0)}; }

}  // namespace pdamp
