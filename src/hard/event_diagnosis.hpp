#pragma once
/// Where a run's collisions come from: an opt-in diagnostic of the hard engine
/// (`pdamp run --model hard --diagnose-events`), off by default so that it costs the
/// event loop nothing but one test of a pointer per collision.
///
/// For each kind of collision (with a free sphere, the side wall, a cap, a riding sphere)
/// it counts the time since each sphere involved last collided, against the contact time
/// t_c the soft law would take at that collision's approach speed (the Hertz contact of
/// the soft scenario's k_n: hertz_contact_time_s), in decades of Δt / t_c; how many
/// collisions come within t_c of an earlier one of a sphere involved (sequences faster
/// than a soft contact, where the soft model would see one lasting contact); and the
/// approach speeds, in decades. The counts join the engine's statistics in the store as
/// `diagnosis_<kind>_<measure>` (docs/hard-engine.md, "Where dense beds spend their
/// collisions").

#include <array>
#include <cstdint>
#include <string>

#include "pdamp/model/engine.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp::hard {

class EventDiagnosis {
 public:
  enum Kind : std::uint8_t { sphere_sphere, side_wall, cap, rider, kind_count };
  /// Decades of Δt / t_c: the same instant, below 0.01, …, at least 100, and a sphere's
  /// first collision.
  enum Interval : std::uint8_t {
    same_instant,
    below_0_01,
    below_0_1,
    below_1,
    below_10,
    below_100,
    at_least_100,
    first,
    interval_count
  };
  /// Decades of the approach speed: below 10⁻⁴ m/s, …, at least 1 m/s.
  static constexpr std::size_t speed_bins = 6;

  explicit EventDiagnosis(const Scenario& scenario);
  /// With the soft law's stiffness of sphere pairs and of walls (N/m^1.5).
  EventDiagnosis(double sphere_kn_N_m1_5, double wall_kn_N_m1_5)
      : sphere_kn_N_m1_5_(sphere_kn_N_m1_5), wall_kn_N_m1_5_(wall_kn_N_m1_5) {}

  /// A collision of `kind` at t_s approaching at `approach_m_s`, of a sphere that last
  /// collided at `previous_s` (−never: not yet) with a partner of effective mass
  /// `effective_mass_kg` (the sphere's own against a wall) that last collided at
  /// `partner_previous_s` (a free sphere's; NaN for a wall or a rider, whose times are
  /// not the partner's own).
  void note(Kind kind, double t_s, double approach_m_s, double effective_mass_kg, double previous_s,
            double partner_previous_s);
  /// The counts, named as in the store.
  EngineStatistics named() const;

  /// The decade of Δt / t_c that a sphere's interval falls in.
  static Interval interval_of(double since_previous_s, double contact_time_s);
  /// The decade of an approach speed.
  static std::size_t speed_bin_of(double approach_m_s);

  /// Its state verbatim (hard_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  struct Counts {
    std::array<std::int64_t, interval_count> intervals{};  ///< per sphere involved
    std::array<std::int64_t, speed_bins> speeds{};         ///< per collision
    std::int64_t within_contact_time = 0;                  ///< collisions within t_c of a sphere's previous one
  };
  /// Counts a sphere's interval; whether it is shorter than t_c.
  static bool count_interval(Counts& counts, double since_previous_s, double contact_time_s);

  double sphere_kn_N_m1_5_, wall_kn_N_m1_5_;
  std::array<Counts, kind_count> counts_{};
};

}  // namespace pdamp::hard
