#pragma once
/// Hard-sphere parameters from the soft contact law. The Hertz law with a constant dashpot
/// has a restitution coefficient that depends on the impact speed; this integrates
/// isolated soft collisions with the soft engine itself (no gravity, nothing else in
/// reach, a step of t_c/200 or T_s/40, soft/time_step.hpp) and tabulates, over impact
/// speeds from 1 mm/s to the fastest
/// impact the scenario can produce:
///   e_n(v)   head-on: the normal rebound speed over the impact speed;
///   β0(v)    oblique, with a tangential contact-point speed of 5 % of μ v (far inside the
///            sticking range): minus the tangential contact-point speed after over before;
/// for sphere–sphere and sphere–wall contacts of the scenario's mean sphere.

#include "pdamp/model/restitution.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

RestitutionTable calibrate_restitution(const Scenario& scenario, int speeds = 25);

}  // namespace pdamp
