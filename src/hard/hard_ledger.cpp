#include "pdamp/hard/hard_ledger.hpp"

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

void HardLedger::add_host_since_booked(double& viscous_sum_J, double& excitation_sum_J,
                                       const HostTrajectory& trajectory, double t_s, const Riders& riders) const {
  viscous_sum_J += trajectory.viscous_dissipation_J(t_host_booked_s_, t_s);
  excitation_sum_J += trajectory.excitation_work_J(t_host_booked_s_, t_s);
  if (riders.carried_by_prescribed_host) {
    excitation_sum_J += riders.energy_J(trajectory.at(t_s)) - riders.energy_J(trajectory.at(t_host_booked_s_));
  }
}

void HardLedger::book_host(const HostTrajectory& trajectory, double t_s, const Riders& riders) {
  add_host_since_booked(viscous_J, excitation_J, trajectory, t_s, riders);
  t_host_booked_s_ = t_s;
}

void HardLedger::write_to(EnergyLedger& e, const HostTrajectory& trajectory, double t_s, const Riders& riders) const {
  e.dissipated_impact_J = impact_J;
  e.dissipated_friction_J = friction_J;
  e.dissipated_viscous_J = viscous_J;
  e.excitation_work_J = excitation_J;
  add_host_since_booked(e.dissipated_viscous_J, e.excitation_work_J, trajectory, t_s, riders);
}

}  // namespace pdamp::hard
