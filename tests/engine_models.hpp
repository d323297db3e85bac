#pragma once
/// The two models as doctest template parameters: a test written once runs on both
/// (TEST_CASE_TEMPLATE(..., M, test::SoftModel, test::HardModel)), each with its engine's
/// own bounds, derived where that engine is tested.

#include "pdamp/sim/engine_factory.hpp"

namespace pdamp::test {

struct SoftModel {
  static constexpr Model model = Model::soft;
  /// Velocity Verlet's balance error on small.ini over 0.3 s (test_soft_engine.cpp: it
  /// converges at second order in the step and is below 1e-8 at the automatic step on
  /// one binary collision; a bed's many contacts add up to this).
  static constexpr double balance_tolerance = 1e-4;
  /// Vertical momentum of spheres and a free host: rounding of the forces' sums.
  static constexpr double momentum_tolerance = 1e-12;
};

struct HardModel {
  static constexpr Model model = Model::hard;
  /// Exact collisions between exact flights: the error is round-off.
  static constexpr double balance_tolerance = 1e-9;
  /// Vertical momentum of spheres and a free host: rounding of each impulse.
  static constexpr double momentum_tolerance = 1e-13;
};

}  // namespace pdamp::test
