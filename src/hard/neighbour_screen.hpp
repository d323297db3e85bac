#pragma once
/// Which of a sphere's neighbours it will meet: the contact test of every prediction
/// (PairQuadratic::meets), run over the neighbours four at a time in SIMD lanes.
///
/// Each lane performs the same IEEE operations in the same order as
/// PairQuadratic::of on Ballistic::position_at and velocity_at (the project is built
/// without floating-point contraction), so the answer is the same bits whichever
/// instruction set runs it, chosen by the process's SimdPath (pdamp/simd/simd_path.hpp):
/// AVX2, or the baseline's SSE2 (four lanes in pairs of registers). No eight-lane AVX-512 screen: the screen waits on
/// its loads more than on its arithmetic (tools/bench/HISTORY.md).

#include <Eigen/Core>
#include <bit>
#include <cstdint>
#include <vector>

#include "hard/event_prediction.hpp"
#include "hard/packed_particles.hpp"
#include "pdamp/simd/simd_path.hpp"

namespace pdamp::hard {

/// The sphere whose neighbours are screened, at time t_s.
struct ScreenedSphere {
  Eigen::Vector3d position_m, velocity_m_s;
  double radius_m, t_s;
  int index;  ///< the sphere itself, which pads the neighbours to whole groups of lanes
};

/// Lanes per group.
inline constexpr int screen_width = 4;

/// What screen_neighbours finds, for up to `capacity` neighbours: each one's quadratic,
/// and one bit per neighbour that the sphere meets.
class ScreenResult {
 public:
  explicit ScreenResult(int capacity)
      : b_(capacity + screen_width),
        c_(capacity + screen_width),
        discriminant_(capacity + screen_width),
        meets_((capacity + screen_width) / 64 + 1) {}

  /// Calls visit(k, quadratic) for each neighbour k < count (the count screened) that the
  /// sphere meets, in order: one loop over the meetings (about one neighbour in ten),
  /// which the engine times and enters as they come.
  template <class Visit>
  void for_each_met(int count, Visit visit) const {
    for (int word = 0; word * 64 < count; ++word) {
      for (std::uint64_t bits = meets_[word]; bits != 0; bits &= bits - 1) {
        const int k = 64 * word + std::countr_zero(bits);
        visit(k, PairQuadratic{b_[k], c_[k], discriminant_[k]});
      }
    }
  }

 private:
  friend struct ScreenAccess;
  std::vector<double> b_, c_, discriminant_;
  std::vector<std::uint64_t> meets_;
};

/// A screen: screens `neighbours[0 … count)` (the array must have room for screen_width
/// more) against `sphere`, under gravity `g`, into `result`.
using NeighbourScreen = void (*)(const ScreenedSphere& sphere, const Eigen::Vector3d& g, const FlightRecord* records,
                                 int* neighbours, int count, ScreenResult& result);

/// The screen compiled for `path`: AVX2's for AVX2 and AVX-512, SSE2's for SSE2. Every one
/// gives the same bits. Throws InputError if this build or CPU cannot run the path.
NeighbourScreen neighbour_screen(simd::SimdPath path);

}  // namespace pdamp::hard
