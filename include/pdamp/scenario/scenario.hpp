#pragma once
/// The validated settings of one damper simulation. Both engines take a `Scenario`
/// and nothing else; `load_scenario` (scenario_loader.hpp) is the only way to build
/// one from user input, and it checks every value before anything runs.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>

namespace pdamp {

/// Single-degree-of-freedom host: M z'' + C z' + K z = F_excitation(t) + F_particles.
/// z is the vertical displacement (m) of the cavity from the static equilibrium of the
/// host alone (the spring preload carries the host's own weight; the particles' weight
/// reaches the host through contacts).
struct HostSettings {
  double mass_kg = 0.0376;
  double stiffness_N_m = 470.0;
  double damping_N_s_m = 0.1;
  double z0_m = 0.0157;  ///< initial displacement
  double v0_m_s = 0.0;   ///< initial velocity
  bool operator==(const HostSettings&) const = default;
};

enum class ExcitationMode {
  free_decay,         ///< no excitation
  base_motion,        ///< the spring and damper are anchored to a base y(t) = A sin(ωt + φ)
  force,              ///< F(t) = F0 sin(ωt + φ) acts on the host
  prescribed_motion,  ///< z(t) = A sin(ωt + φ), infinite host mass (K, C, z0, v0 unused)
};

struct ExcitationSettings {
  ExcitationMode mode = ExcitationMode::free_decay;
  double amplitude_m = 0.0;  ///< base or prescribed motion amplitude
  double force_N = 0.0;      ///< force amplitude
  double frequency_hz = 0.0;
  double phase_rad = 0.0;
  double angular_frequency_rad_s() const;
  bool operator==(const ExcitationSettings&) const = default;
};

/// Vertical closed cylinder cut into the host: side wall, bottom cap at the host's z,
/// top cap at z + height. Its axis is the lab z axis through x = y = 0.
struct CavitySettings {
  double diameter_m = 0.0254;
  double height_m = 0.00704;
  double radius_m() const { return 0.5 * diameter_m; }
  bool operator==(const CavitySettings&) const = default;
};

struct ParticleSettings {
  int count = 1246;
  double diameter_min_m = 0.00088;  ///< equal to diameter_max_m for a monodisperse fill
  double diameter_max_m = 0.00088;
  double density_kg_m3 = 9000.0;
  std::uint64_t seed = 1;
  bool operator==(const ParticleSettings&) const = default;
};

/// Hertz normal law with a constant dashpot, incremental tangential spring with Coulomb cap:
/// f_n = kn δ^{3/2} + cn δ', f_s = ks δ_s + cs δ_s' (|f_s| ≤ μ f_n).
struct SoftContactLaw {
  double kn_N_m1_5 = 3.6e5;  ///< N/m^1.5
  double cn_N_s_m = 0.01;
  double ks_N_m = 3.3e5;
  double cs_N_s_m = 0.015;
  double mu = 0.55;
  bool operator==(const SoftContactLaw&) const = default;
};

/// Walton's three-parameter impulse law: normal restitution, Coulomb friction and
/// tangential restitution of sticking collisions.
/// The defaults are the Table 1 soft law's restitution at a 0.5 m/s impact
/// (0.71 sphere–sphere; `Scenario::hard_wall` sets 0.80 sphere–wall).
struct HardContactLaw {
  double en = 0.71;
  double mu = 0.55;
  double beta0 = 0.35;  ///< Walton's typical value for metal spheres
  bool operator==(const HardContactLaw&) const = default;
};

/// How the hard-sphere engine ends bouncing sequences that would otherwise never stop
/// (docs/hard-engine.md, "Resting beds and inelastic collapse").
struct HardRestingSettings {
  /// A sphere that leaves the floor, the top cap or a resting sphere slower than this
  /// (normal speed relative to the host), while the host's acceleration presses it
  /// there, comes to rest and rides with the host as added mass. Taken as at least
  /// elastic_speed_m_s, below which it would bounce as fast as it came (if not 0).
  double rest_speed_m_s = 0.005;
  /// Also faster than rest_speed_m_s: a sphere that would land again within this many soft
  /// contact times (its flight 2 v / a under the pressing acceleration a, against the Hertz
  /// contact of the soft law at v), which the soft law holds in one enduring contact, comes
  /// to rest, and a rider hit slower than that stays on the bed; 0 turns it off.
  double rest_tc_window = 0.0;
  /// Collisions whose normal approach speed is below this are elastic in the normal
  /// direction, which stops inelastic collapse (infinitely many collisions in finite time).
  double elastic_speed_m_s = 1e-4;
  /// The same for collisions with the side wall, on its own: a loose bed that its host
  /// catches gently is held and dragged by its friction against the wall, which bounces off
  /// the wall would lose (docs/hard-engine.md, "Settings for dense beds").
  double side_wall_elastic_speed_m_s = 1e-4;
  /// Luding & McNamara's TC model: a collision within this many soft contact times t_c
  /// (the Hertz contact of the soft law at its approach speed) of an earlier collision of
  /// a sphere it involves is elastic in the normal direction; 0 turns it off.
  double tc_window = 0.0;
  /// Rigid clusters: a collision of two free spheres approaching slower than this merges
  /// them (and the clusters they are in) into one rigid body, which a sphere leaves when
  /// anything else changes its motion; 0 turns it off (docs/hard-engine.md, "Rigid clusters").
  double cluster_speed_m_s = 0.0;
  bool operator==(const HardRestingSettings&) const = default;
};

/// Where the hard-sphere engine takes e_n and β0 from.
enum class HardRestitution {
  constant,    ///< the [hard] and [hard_wall] values
  calibrated,  ///< e_n(v), β0(v) of the soft law, from isolated soft collisions (sim/calibration.hpp)
};

/// The run's length and resolution, and bounds on the work it may take (sim/run_budget.hpp):
/// a scenario whose steps or samples would exceed them is refused before anything runs;
/// the hard engine's events, which cannot be foreseen, end the run as failed at the bound.
struct RunSettings {
  double duration_s = 1.5;
  double sample_interval_s = 1e-3;
  std::optional<double> dt_s;  ///< soft engine time step; empty = automatic
  /// Time steps of the soft engine (the run's and settling's) and observation steps of the
  /// run loop (either model).
  std::int64_t max_steps = 1'000'000'000;
  std::int64_t max_samples = 1'000'000;      ///< stored samples
  std::int64_t max_events = 10'000'000'000;  ///< events of the hard engine, all kinds
  bool operator==(const RunSettings&) const = default;
};

/// Its member initializers are the defaults of every key (`pdamp keys` prints them, and
/// a scenario file that leaves a key out gets them): they are written nowhere else.
struct Scenario {
  std::string name;  ///< the scenario file's stem unless set in the file
  HostSettings host;
  ExcitationSettings excitation;
  CavitySettings cavity;
  Eigen::Vector3d gravity_m_s2{0.0, 0.0, -9.81};
  ParticleSettings particles;
  SoftContactLaw soft_particle;  ///< particle–particle
  SoftContactLaw soft_wall;      ///< particle–wall (defaults to the particle–particle law)
  HardContactLaw hard_particle;
  HardContactLaw hard_wall{.en = 0.80};
  HardRestingSettings hard_resting;
  HardRestitution hard_restitution = HardRestitution::constant;
  RunSettings run;

  /// Every key with its resolved value, in scenario-file syntax. Loading this text
  /// gives back an identical scenario; the store keeps it with each run.
  std::string canonical_text;

  bool host_has_infinite_mass() const { return excitation.mode == ExcitationMode::prescribed_motion; }
  bool operator==(const Scenario&) const = default;
};

}  // namespace pdamp
