#include "pdamp/hard/neighbour_screen.hpp"

#include <bit>
#include <cstring>
#include <string_view>

// Four-double vectors are passed between the inline helpers below, which never leave
// this file: GCC's note that their ABI differs without AVX concerns no caller.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace pdamp::hard {
namespace {

static_assert(screen_width == 4, "the transposes below take four records at a time");
using Lanes = double __attribute__((vector_size(4 * sizeof(double))));

[[gnu::always_inline]] inline Lanes splat(double a) { return Lanes{a, a, a, a}; }

/// Four consecutive doubles of a record (32-byte aligned: records are 64-byte aligned).
[[gnu::always_inline]] inline Lanes load(const double* from) {
  Lanes lanes;
  std::memcpy(&lanes, from, sizeof lanes);
  return lanes;
}

/// Rows (a0 a1 a2 a3) of four records become columns: out[k] = (row0[k], row1[k], row2[k], row3[k]).
[[gnu::always_inline]] inline void transpose(Lanes row0, Lanes row1, Lanes row2, Lanes row3, Lanes (&out)[4]) {
  const Lanes even01 = __builtin_shufflevector(row0, row1, 0, 4, 2, 6);
  const Lanes odd01 = __builtin_shufflevector(row0, row1, 1, 5, 3, 7);
  const Lanes even23 = __builtin_shufflevector(row2, row3, 0, 4, 2, 6);
  const Lanes odd23 = __builtin_shufflevector(row2, row3, 1, 5, 3, 7);
  out[0] = __builtin_shufflevector(even01, even23, 0, 1, 4, 5);
  out[1] = __builtin_shufflevector(odd01, odd23, 0, 1, 4, 5);
  out[2] = __builtin_shufflevector(even01, even23, 2, 3, 6, 7);
  out[3] = __builtin_shufflevector(odd01, odd23, 2, 3, 6, 7);
}

[[gnu::always_inline]] inline void store(double* to, Lanes lanes) { std::memcpy(to, &lanes, sizeof lanes); }

/// The screen, written once; each instruction set below compiles its own copy. A first
/// pass tests every neighbour and keeps its quadratic and whether it meets (one bit in
/// `scratch.meets`); a second moves those met to the front. Compacting in the first pass
/// would chain every group's stores to the count of the group before.
[[gnu::always_inline]] inline int screen(const ScreenedSphere& sphere, const Eigen::Vector3d& g,
                                         const FlightRecord* records, int* neighbours, int count,
                                         ScreenScratch& scratch, PairQuadratic* meeting) {
  for (int k = 0; k < screen_width; ++k) neighbours[count + k] = sphere.index;  // pads: never meets itself
  const int padded = (count + screen_width - 1) / screen_width * screen_width;
  const Lanes t = splat(sphere.t_s), r = splat(sphere.radius_m);
  const Lanes x = splat(sphere.position_m.x()), y = splat(sphere.position_m.y()), z = splat(sphere.position_m.z());
  const Lanes vx = splat(sphere.velocity_m_s.x()), vy = splat(sphere.velocity_m_s.y()),
              vz = splat(sphere.velocity_m_s.z());
  const Lanes gx = splat(g.x()), gy = splat(g.y()), gz = splat(g.z());
  std::uint64_t* const meets_bits = scratch.meets.data();
  for (int first = 0; first < padded; first += 64) meets_bits[first / 64] = 0;
  for (int first = 0; first < padded; first += screen_width) {
    const int* const j = neighbours + first;
    Lanes position[4], velocity[4];  // x, y, z, t_ref and vx, vy, vz, radius of the four
    transpose(load(&records[j[0]].x_m), load(&records[j[1]].x_m), load(&records[j[2]].x_m),
              load(&records[j[3]].x_m), position);
    transpose(load(&records[j[0]].vx_m_s), load(&records[j[1]].vx_m_s), load(&records[j[2]].vx_m_s),
              load(&records[j[3]].vx_m_s), velocity);
    // Ballistic::position_at and velocity_at, then PairQuadratic::of and meets, operation for operation.
    const Lanes s = t - position[3], half_s = 0.5 * s;
    const Lanes dx = x - (position[0] + s * (velocity[0] + half_s * gx));
    const Lanes dy = y - (position[1] + s * (velocity[1] + half_s * gy));
    const Lanes dz = z - (position[2] + s * (velocity[2] + half_s * gz));
    const Lanes dvx = vx - (velocity[0] + s * gx), dvy = vy - (velocity[1] + s * gy), dvz = vz - (velocity[2] + s * gz);
    const Lanes contact = r + velocity[3];
    const Lanes b = (dx * dvx + dy * dvy) + dz * dvz;
    const Lanes c = ((dx * dx + dy * dy) + dz * dz) - contact * contact;
    const Lanes discriminant = b * b - ((dvx * dvx + dvy * dvy) + dvz * dvz) * c;
    const auto meets = (b < -min_approach_speed_m_s * contact) & ((c <= 0.0) | (discriminant >= 0.0));
    store(scratch.b.data() + first, b);
    store(scratch.c.data() + first, c);
    store(scratch.discriminant.data() + first, discriminant);
    const std::uint64_t bits = (meets[0] & 1) | (meets[1] & 2) | (meets[2] & 4) | (meets[3] & 8);
    meets_bits[first / 64] |= bits << (first % 64);
  }
  int met = 0;
  for (int word = 0; word * 64 < padded; ++word) {
    for (std::uint64_t bits = meets_bits[word]; bits != 0; bits &= bits - 1) {
      const int k = 64 * word + std::countr_zero(bits);
      neighbours[met] = neighbours[k];
      meeting[met] = {scratch.b[k], scratch.c[k], scratch.discriminant[k]};
      ++met;
    }
  }
  return met;
}

int screen_sse2(const ScreenedSphere& sphere, const Eigen::Vector3d& g, const FlightRecord* records, int* neighbours,
                int count, ScreenScratch& scratch, PairQuadratic* meeting) {
  return screen(sphere, g, records, neighbours, count, scratch, meeting);
}

[[gnu::target("avx2")]] int screen_avx2(const ScreenedSphere& sphere, const Eigen::Vector3d& g,
                                         const FlightRecord* records, int* neighbours, int count,
                                         ScreenScratch& scratch, PairQuadratic* meeting) {
  return screen(sphere, g, records, neighbours, count, scratch, meeting);
}

using Screen = int (*)(const ScreenedSphere&, const Eigen::Vector3d&, const FlightRecord*, int*, int, ScreenScratch&,
                       PairQuadratic*);

struct InstructionSet {
  const char* name;
  Screen screen;
};

const InstructionSet& best_instruction_set() {
  static const InstructionSet best = __builtin_cpu_supports("avx2") ? InstructionSet{"avx2", screen_avx2}
                                                                    : InstructionSet{"sse2", screen_sse2};
  return best;
}

}  // namespace

int screen_neighbours(const ScreenedSphere& sphere, const Eigen::Vector3d& g, const FlightRecord* records,
                      int* neighbours, int count, ScreenScratch& scratch, PairQuadratic* meeting) {
  return best_instruction_set().screen(sphere, g, records, neighbours, count, scratch, meeting);
}

const char* screen_instruction_set() { return best_instruction_set().name; }

bool screen_neighbours_with(const char* instruction_set, const ScreenedSphere& sphere, const Eigen::Vector3d& g,
                            const FlightRecord* records, int* neighbours, int count, ScreenScratch& scratch,
                            PairQuadratic* meeting, int& meeting_count) {
  const std::string_view name = instruction_set;
  Screen screen = nullptr;
  if (name == "sse2") screen = screen_sse2;
  if (name == "avx2" && __builtin_cpu_supports("avx2")) screen = screen_avx2;
  if (!screen) return false;
  meeting_count = screen(sphere, g, records, neighbours, count, scratch, meeting);
  return true;
}

}  // namespace pdamp::hard
