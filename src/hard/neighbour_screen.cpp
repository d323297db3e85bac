#include "hard/neighbour_screen.hpp"

#include <cstring>

// Vectors are passed by value only into the always_inline helpers below, inlined at
// every optimisation level: GCC's note that their ABI differs without AVX concerns no call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace pdamp::hard {

/// The screen's way into a ScreenResult's arrays.
struct ScreenAccess {
  static double* b(ScreenResult& r) { return r.b_.data(); }
  static double* c(ScreenResult& r) { return r.c_.data(); }
  static double* discriminant(ScreenResult& r) { return r.discriminant_.data(); }
  static std::uint64_t* meets(ScreenResult& r) { return r.meets_.data(); }
};

namespace {

constexpr int width = screen_width;
using Lanes = simd::Lanes4;
using Mask = simd::Mask4;

/// The eight doubles of four records as eight vectors: x, y, z, t_ref, vx, vy, vz, radius.
[[gnu::always_inline]] inline void transpose(const FlightRecord* const (&record)[width], Lanes (&field)[8]) {
  for (std::ptrdiff_t half = 0; half < 2; ++half) {  // x y z t_ref, then vx vy vz radius
    Lanes r0 = simd::load<Lanes>(&record[0]->x_m + 4 * half), r1 = simd::load<Lanes>(&record[1]->x_m + 4 * half);
    Lanes r2 = simd::load<Lanes>(&record[2]->x_m + 4 * half), r3 = simd::load<Lanes>(&record[3]->x_m + 4 * half);
    simd::transpose(r0, r1, r2, r3);
    field[4 * half + 0] = r0;
    field[4 * half + 1] = r1;
    field[4 * half + 2] = r2;
    field[4 * half + 3] = r3;
  }
}

/// One bit per lane where the mask is set: AVX2 has an instruction for it
/// (simd::lane_bits). The mask comes by reference: the generic screen is not always
/// inlined into the entry points below (`flatten` may not, unoptimised), and a vector
/// passed in registers between code compiled for different instruction sets would arrive
/// garbled.
struct BitsSse2 {
  static unsigned of(const Mask& m) { return static_cast<unsigned>((m[0] & 1) | (m[1] & 2) | (m[2] & 4) | (m[3] & 8)); }
};
struct BitsAvx2 {
  [[gnu::target("avx2")]] static unsigned of(const Mask& m) { return simd::lane_bits(m); }
};

/// The screen, written once; each instruction set below compiles its own copy. It keeps
/// every neighbour's quadratic and one bit for whether they meet: picking out the few
/// met here would chain every group's stores to the count of the group before.
template <class Bits>
void screen(const ScreenedSphere& sphere, const Eigen::Vector3d& g, const FlightRecord* records, int* neighbours,
            int count, ScreenResult& result) {
  for (int k = 0; k < width; ++k) neighbours[count + k] = sphere.index;  // pads: never meets itself
  const int padded = (count + width - 1) / width * width;
  auto splat = [](double a) { return simd::broadcast<Lanes>(a); };
  const Lanes t = splat(sphere.t_s), r = splat(sphere.radius_m);
  const Lanes x = splat(sphere.position_m.x()), y = splat(sphere.position_m.y()), z = splat(sphere.position_m.z());
  const Lanes vx = splat(sphere.velocity_m_s.x()), vy = splat(sphere.velocity_m_s.y()),
              vz = splat(sphere.velocity_m_s.z());
  const Lanes gx = splat(g.x()), gy = splat(g.y()), gz = splat(g.z());
  double* __restrict const b_out = ScreenAccess::b(result);
  double* __restrict const c_out = ScreenAccess::c(result);
  double* __restrict const discriminant_out = ScreenAccess::discriminant(result);
  std::uint64_t* __restrict const meets_bits = ScreenAccess::meets(result);
  for (int first = 0; first < padded; first += 64) meets_bits[first / 64] = 0;
  for (int first = 0; first < padded; first += width) {
    const FlightRecord* record[width];
    for (int l = 0; l < width; ++l) record[l] = records + neighbours[first + l];
    Lanes field[8];  // x, y, z, t_ref, vx, vy, vz, radius of the group
    transpose(record, field);
    // Ballistic::position_at and velocity_at, then PairQuadratic::of and meets, operation for operation.
    const Lanes s = t - field[3], half_s = 0.5 * s;
    const Lanes dx = x - (field[0] + s * (field[4] + half_s * gx));
    const Lanes dy = y - (field[1] + s * (field[5] + half_s * gy));
    const Lanes dz = z - (field[2] + s * (field[6] + half_s * gz));
    const Lanes dvx = vx - (field[4] + s * gx), dvy = vy - (field[5] + s * gy), dvz = vz - (field[6] + s * gz);
    const Lanes contact = r + field[7];
    const Lanes b = (dx * dvx + dy * dvy) + dz * dvz;
    const Lanes c = ((dx * dx + dy * dy) + dz * dz) - contact * contact;
    const Lanes discriminant = b * b - ((dvx * dvx + dvy * dvy) + dvz * dvz) * c;
    const auto meets = (b < -min_approach_speed_m_s * contact) & ((c <= 0.0) | (discriminant >= 0.0));
    simd::store(b_out + first, b);
    simd::store(c_out + first, c);
    simd::store(discriminant_out + first, discriminant);
    meets_bits[first / 64] |= static_cast<std::uint64_t>(Bits::of(meets)) << (first % 64);
  }
}

[[gnu::flatten]] void screen_sse2(const ScreenedSphere& sphere, const Eigen::Vector3d& g, const FlightRecord* records,
                                  int* neighbours, int count, ScreenResult& result) {
  screen<BitsSse2>(sphere, g, records, neighbours, count, result);
}

[[gnu::target("avx2"), gnu::flatten]] void screen_avx2(const ScreenedSphere& sphere, const Eigen::Vector3d& g,
                                                       const FlightRecord* records, int* neighbours, int count,
                                                       ScreenResult& result) {
  screen<BitsAvx2>(sphere, g, records, neighbours, count, result);
}

}  // namespace

NeighbourScreen neighbour_screen(simd::SimdPath path) {
  simd::require_available(path, "the hard engine's neighbour screen");
  return path == simd::SimdPath::sse2 ? screen_sse2 : screen_avx2;
}

}  // namespace pdamp::hard
