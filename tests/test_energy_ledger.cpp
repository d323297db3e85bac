/// The ledger's arithmetic, shared by both engines.
#include <doctest/doctest.h>

#include "pdamp/model/energy_ledger.hpp"

using namespace pdamp;

TEST_CASE("a compensated sum of many terms is exact to one rounding where a plain sum drifts") {
  // 10^6 times 0.1 (itself inexact): the exact sum of the double 0.1 is 10^6 · 0.1 to
  // within one rounding; adding it up plainly loses a part of an ulp of the growing total
  // at each step, ~10^-11 of it in all.
  constexpr int n = 1'000'000;
  CompensatedSum compensated;
  double plain = 0.0;
  for (int k = 0; k < n; ++k) {
    compensated += 0.1;
    plain += 0.1;
  }
  const double exact = 0.1 * n;  // one rounding of the exact product
  CHECK(std::abs(compensated.value() - exact) <= 2e-16 * exact);
  CHECK(std::abs(plain - exact) > 1e-12 * exact);  // what the ledger would report otherwise

  // Terms that cancel, large and small alternating in size: the small ones are kept.
  CompensatedSum cancelling;
  for (int k = 0; k < 1000; ++k) {
    cancelling += 1e16;
    cancelling += 1.0;
    cancelling += -1e16;
  }
  CHECK(cancelling.value() == 1000.0);
}

TEST_CASE("particle energy sums: translational, rotational and gravitational parts of each sphere") {
  ParticleEnergySums sums;
  const Eigen::Vector3d g(0.0, 0.0, -9.81);
  sums.add(2.0, 0.5, Eigen::Vector3d(0.0, 0.0, 0.3), Eigen::Vector3d(1.0, 2.0, 2.0), Eigen::Vector3d(0.0, 4.0, 0.0), g);
  sums.add(1.0, 0.25, Eigen::Vector3d(1.0, 0.0, -0.1), Eigen::Vector3d(0.0, 0.0, -3.0), Eigen::Vector3d(2.0, 0.0, 0.0),
           g);
  EnergyLedger ledger;
  sums.write_to(ledger);
  CHECK(ledger.particle_translational_J == doctest::Approx(0.5 * 2.0 * 9.0 + 0.5 * 1.0 * 9.0).scale(1.0));
  CHECK(ledger.particle_rotational_J == doctest::Approx(0.5 * 0.5 * 16.0 + 0.5 * 0.25 * 4.0).scale(1.0));
  CHECK(ledger.gravitational_potential_J == doctest::Approx(2.0 * 9.81 * 0.3 + 1.0 * 9.81 * -0.1).scale(1.0));
  CHECK(sums.translational_J() == ledger.particle_translational_J);
  CHECK(sums.rotational_J() == ledger.particle_rotational_J);
}
