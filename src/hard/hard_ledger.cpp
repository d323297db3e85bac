#include "hard/hard_ledger.hpp"

namespace pdamp::hard {

EngineStatistics HardStatistics::named() const {
  return {{"events_sphere_sphere", sphere_sphere},
          {"events_wall", side_wall},
          {"events_cap", cap},
          {"events_rider", rider},
          {"events_cell_crossing", cell_crossing},
          {"events_host_check", host_check},
          {"events_host_margin", host_margin},
          {"events_stale", stale},
          {"bed_rests", rests},
          {"bed_knock_offs", knocked_off},
          {"bed_releases", bed_releases},
          {"bed_jammed", jammed},
          {"jam_merges", jam_merges},
          {"jam_merged_spheres", jam_merged_spheres},
          {"jam_stuck_to_host", jam_stuck_to_host},
          {"host_impulses", host_impulses},
          {"near_sweeps", tier_sweeps[0]},
          {"near_repredictions", tier_repredictions[0]},
          {"imminent_sweeps", tier_sweeps[1]},
          {"imminent_repredictions", tier_repredictions[1]},
          {"close_sweeps", tier_sweeps[2]},
          {"close_repredictions", tier_repredictions[2]},
          {"touching_repredictions", touching_repredictions},
          {"touching_deferrals", touching_deferrals},
          {"prediction_rebuilds", rebuilds}};
}

void HardLedger::add_host_since_booked(double& viscous_sum_J, double& excitation_sum_J, HostLoadBooks& load_sums,
                                       const HostTrajectory& trajectory, double t_s, const Riders& riders) const {
  const HostTrajectory::Stretch stretch =
      trajectory.stretch(t_host_booked_s_, t_s, riders.mass_kg, riders.gravity_z_m_s2);
  viscous_sum_J += stretch.viscous_J;
  excitation_sum_J += stretch.excitation_J;
  if (riders.carried_by_prescribed_host) {
    excitation_sum_J += riders.energy_J(trajectory.at(t_s)) - riders.energy_J(trajectory.at(t_host_booked_s_));
  }
  load_sums.add(stretch.load);
}

void HardLedger::book_host(const HostTrajectory& trajectory, double t_s, const Riders& riders) {
  add_host_since_booked(viscous_J, excitation_J, load, trajectory, t_s, riders);
  t_host_booked_s_ = t_s;
}

void HardLedger::write_to(Observation& o, const HostTrajectory& trajectory, double t_s, const Riders& riders) const {
  EnergyLedger& e = o.energy;
  e.dissipated_impact_J = impact_J;
  e.dissipated_friction_J = friction_J;
  e.dissipated_viscous_J = viscous_J;
  e.excitation_work_J = excitation_J;
  HostLoadBooks load_now = load;
  add_host_since_booked(e.dissipated_viscous_J, e.excitation_work_J, load_now, trajectory, t_s, riders);
  o.host_load = load_now.value();
}

}  // namespace pdamp::hard
