#pragma once
/// Per-cycle damping analysis of the host motion, shared by both engines.
///
/// A cycle runs from one maximum of the host displacement to the next. A maximum counts
/// only after the host has been below its equilibrium since the previous one, so the
/// velocity jitter of impacts near a crest never splits a cycle. For each cycle:
///   amplitude A = (z_max − z_min) / 2, f = 1 / period, Γ = A (2πf)² / |g_z|,
///   ψ = (energy dissipated during the cycle) / (maximum host kinetic energy ½ M z'²
///       during the cycle), split by mechanism into ψ_impact + ψ_friction + ψ_viscous.
/// Observations must be dense (the runner feeds ≥ 256 per natural period); extrema
/// are refined by parabolic interpolation and crossings linearly.

#include <optional>

#include "pdamp/model/checkpoint.hpp"
#include "pdamp/model/state.hpp"

namespace pdamp {

struct CycleRecord {
  int cycle = 0;  ///< 1, 2, ...
  double t_start_s = 0.0;
  double t_end_s = 0.0;
  double amplitude_m = 0.0;
  double freq_hz = 0.0;
  std::optional<double> gamma;  ///< empty without vertical gravity
  double psi = 0.0;
  double psi_impact = 0.0;
  double psi_friction = 0.0;
  double psi_viscous = 0.0;
  double max_host_kinetic_J = 0.0;
  bool operator==(const CycleRecord&) const = default;
};

class CycleAnalyzer {
 public:
  /// `equilibrium_z_m`: the host's static equilibrium with the bed resting in it;
  /// `vertical_gravity_m_s2`: |g_z| (0 for microgravity: Γ is then undefined).
  CycleAnalyzer(double host_mass_kg, double equilibrium_z_m, double vertical_gravity_m_s2);

  /// Feed observations in time order; returns the cycle that this one completes, if any.
  std::optional<CycleRecord> feed(const Observation& now);

  /// Where the analysis stands, verbatim (sim/run_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  struct Crest {
    double t_s;
    double z_m;
    double impact_J, friction_J, viscous_J;
  };
  void start_cycle(const Crest& crest);

  double mass_kg_, equilibrium_z_m_, gravity_m_s2_;
  std::optional<Observation> previous_, before_previous_;
  std::optional<Crest> crest_;  ///< start of the cycle in progress
  bool armed_ = true;           ///< the host has been below equilibrium since the last crest
  double z_min_m_ = 0.0;
  double max_kinetic_J_ = 0.0;
  int cycles_ = 0;
};

}  // namespace pdamp
