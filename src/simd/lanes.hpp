#pragma once
/// Arithmetic for several contacts, spheres or planes side by side in SIMD lanes, for both
/// engines. Their kernels are written once, for a real type that is `double` or a GCC
/// vector of 2, 4 or 8 doubles (an SSE2, AVX2 or AVX-512 register): each lane performs the
/// same IEEE operations in the same order as the scalar code, so a result is the same bits
/// whatever the width that computes it. (The project is compiled with -ffp-contract=off, so
/// that no path fuses a multiply and an add that another does not.) Branches on data are
/// selects. Which width runs is chosen once per process (pdamp/simd/simd_path.hpp).

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <type_traits>
#include <utility>

namespace pdamp::simd {

using Lanes2 = double __attribute__((vector_size(16)));
using Lanes4 = double __attribute__((vector_size(32)));
using Lanes8 = double __attribute__((vector_size(64)));

template <class Real>
constexpr int lane_count = sizeof(Real) / sizeof(double);

/// As many ints as Real has lanes, in one register (GCC takes a vector's size only from a
/// constant, not from a template's argument).
template <class Real>
struct IntLanesOf {
  using type = int;
};
template <>
struct IntLanesOf<Lanes2> {
  using type = int __attribute__((vector_size(8)));
};
template <>
struct IntLanesOf<Lanes4> {
  using type = int __attribute__((vector_size(16)));
};
template <>
struct IntLanesOf<Lanes8> {
  using type = int __attribute__((vector_size(32)));
};
template <class Real>
using IntLanes = typename IntLanesOf<Real>::type;

// A few operations have a faster form in one instruction set: a comparison's lanes as bits,
// the indices of chosen lanes packed together. Those overloads carry their instruction set
// as a target attribute and are not forced inline: the kernels reach them only on their own
// path, where the flattened kernel (see soft_engine.cpp) inlines them. They take vectors by
// reference, so that a call, were one left, would not depend on how vectors are passed.

using Mask2 = decltype(Lanes2{} < Lanes2{});  ///< all ones in a lane where a comparison holds
using Mask4 = decltype(Lanes4{} < Lanes4{});
using Mask8 = decltype(Lanes8{} < Lanes8{});

/// The lanes where a comparison of reals holds, as bits (lane l is bit l).
[[gnu::always_inline]] inline unsigned lane_bits(bool mask) { return mask; }
[[gnu::always_inline]] inline unsigned lane_bits(const Mask2& mask) {
  return static_cast<unsigned>(__builtin_ia32_movmskpd(std::bit_cast<Lanes2>(mask)));
}
[[gnu::target("avx2")]] inline unsigned lane_bits(const Mask4& mask) {
  return static_cast<unsigned>(__builtin_ia32_movmskpd256(std::bit_cast<Lanes4>(mask)));
}
[[gnu::target("avx512f")]] inline unsigned lane_bits(const Mask8& mask) {
#ifdef __clang__
  // Clang lacks GCC's builtin; it only parses this file (tools/tidy.sh): GCC builds the engines.
  unsigned bits = 0;
  for (int l = 0; l < 8; ++l) bits |= (mask[l] != 0 ? 1U : 0U) << l;
  return bits;
#else
  using Longs8 = long long __attribute__((vector_size(64)));
  const auto lanes = std::bit_cast<Longs8>(mask);
  return __builtin_ia32_ptestmq512(lanes, lanes, 0xff);
#endif
}

/// The lanes l where p[l] ≠ 0, as bits.
template <class Real>
[[gnu::always_inline]] inline unsigned nonzero_bits(const int* p) {
  using Ints4 = int __attribute__((vector_size(16)));
  using Floats4 = float __attribute__((vector_size(16)));
  if constexpr (lane_count<Real> == 1) {
    return *p != 0;
  } else {
    // SSE2 compares four at a time.
    unsigned bits = 0;
    for (int quad = 0; quad * 4 < lane_count<Real>; ++quad) {
      Ints4 values{};
      std::memcpy(&values, p + std::ptrdiff_t{4} * quad, sizeof(int) * std::min(4, lane_count<Real>));
      const Ints4 nonzero = values != 0;
      bits |= static_cast<unsigned>(__builtin_ia32_movmskps(std::bit_cast<Floats4>(nonzero))) << (4 * quad);
    }
    return bits;
  }
}

[[gnu::target("avx512f,popcnt")]] inline void append_eight_lanes(int first, unsigned bits, int* out, int& count) {
  using Ints16 = int __attribute__((vector_size(64)));
  const Ints16 indices = first + Ints16{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};
  const Ints16 packed = __builtin_ia32_compresssi512_mask(indices, Ints16{}, static_cast<unsigned short>(bits));
  std::memcpy(out + count, &packed, 8 * sizeof(int));
  count += __builtin_popcount(bits);
}
/// Appends first + l to out[count...] for each lane l set in `bits`, without a branch
/// (writing a register's worth of lanes past the last).
template <class Real>
[[gnu::always_inline]] inline void append_lanes(int first, unsigned bits, int* out, int& count) {
  if constexpr (lane_count<Real> == 8) {
    append_eight_lanes(first, bits, out, count);
  } else {
    for (int l = 0; l < lane_count<Real>; ++l) {
      out[count] = first + l;
      count += (bits >> l) & 1;
    }
  }
}

/// Calls f(l) for each lane l, with l a compile-time constant (so that reading a lane
/// is one instruction, not a trip through memory).
template <class Real, class F>
[[gnu::always_inline]] inline void for_each_lane(const F& f) {
  [&]<int... l>(std::integer_sequence<int, l...>) { (f(std::integral_constant<int, l>{}), ...); }
  (std::make_integer_sequence<int, lane_count<Real>>{});
}

/// One value per lane, value(l) for lane l, built in registers.
template <class Real, class Value>
[[gnu::always_inline]] inline Real make_lanes(const Value& value) {
  if constexpr (lane_count<Real> == 1) {
    return value(std::integral_constant<int, 0>{});
  } else {
    return [&]<int... l>(std::integer_sequence<int, l...>) { return Real{value(std::integral_constant<int, l>{})...}; }
    (std::make_integer_sequence<int, lane_count<Real>>{});
  }
}

template <class Real>
[[gnu::always_inline]] inline double lane(Real a, int l) {
  if constexpr (lane_count<Real> == 1) {
    return a;
  } else {
    return a[l];
  }
}
/// f.template operator()<R>(s) for each s of [first, end): R = Real for each register's
/// worth of consecutive indices, double for those left over.
template <class Real, class F>
[[gnu::always_inline]] inline void for_each_register(int first, int end, const F& f) {
  int s = first;
  for (; s + lane_count<Real> <= end; s += lane_count<Real>) f.template operator()<Real>(s);
  for (; s < end; ++s) f.template operator()<double>(s);
}

template <class Real>
[[gnu::always_inline]] inline Real sqrt_of(Real a) {
  return make_lanes<Real>([&](auto l) { return std::sqrt(lane(a, l)); });  // one sqrtpd
}

/// `mask ? a : b`, per lane; the mask is a comparison of reals.
template <class LaneMask, class Real>
[[gnu::always_inline]] inline Real select(LaneMask mask, Real a, Real b) {
  return mask ? a : b;
}
/// `mask ? a : b` as and, and-not, or: two lanes that GCC would otherwise compile to a
/// branch per lane (the hard engine's root finders, where which lane holds is a coin toss).
inline double blend(bool mask, double a, double b) { return mask ? a : b; }
inline Lanes2 blend(Mask2 mask, Lanes2 a, Lanes2 b) {
  return reinterpret_cast<Lanes2>((reinterpret_cast<Mask2>(a) & mask) | (reinterpret_cast<Mask2>(b) & ~mask));
}

template <class Real>
[[gnu::always_inline]] inline Real broadcast(double value) {
  return make_lanes<Real>([&](auto) { return value; });
}

/// Consecutive values: p[0], ..., p[lanes − 1].
template <class Real>
[[gnu::always_inline]] inline Real load(const double* p) {
  Real a;
  std::memcpy(&a, p, sizeof a);
  return a;
}
template <class Real>
[[gnu::always_inline]] inline void store(double* p, Real a) {
  std::memcpy(p, &a, sizeof a);
}
/// Scattered values: base[index[0]], ..., base[index[lanes − 1]].
template <class Real>
[[gnu::always_inline]] inline Real gather(const double* base, const int* index) {
  return make_lanes<Real>([&](auto l) { return base[index[l]]; });
}

template <class Real>
struct Vec3 {
  Real x, y, z;
};

/// The four fields of records of four doubles, lane l holding record l's.
template <class Real>
struct Fields4 {
  Real a, b, c, d;
};

/// The 4 × 4 transpose of four registers of four lanes.
[[gnu::always_inline]] inline void transpose(Lanes4& r0, Lanes4& r1, Lanes4& r2, Lanes4& r3) {
  const Lanes4 ac01 = __builtin_shufflevector(r0, r1, 0, 4, 2, 6), bd01 = __builtin_shufflevector(r0, r1, 1, 5, 3, 7);
  const Lanes4 ac23 = __builtin_shufflevector(r2, r3, 0, 4, 2, 6), bd23 = __builtin_shufflevector(r2, r3, 1, 5, 3, 7);
  r0 = __builtin_shufflevector(ac01, ac23, 0, 1, 4, 5);
  r1 = __builtin_shufflevector(bd01, bd23, 0, 1, 4, 5);
  r2 = __builtin_shufflevector(ac01, ac23, 2, 3, 6, 7);
  r3 = __builtin_shufflevector(bd01, bd23, 2, 3, 6, 7);
}

/// Records of four doubles to their fields, and back: `row(l)` is where record l is.
template <class Real, class Row>
[[gnu::always_inline]] inline Fields4<Real> load_records(const Row& row) {
  if constexpr (lane_count<Real> == 1) {
    const double* const p = row(0);
    return {p[0], p[1], p[2], p[3]};
  } else if constexpr (lane_count<Real> == 2) {
    const Lanes2 ab0 = load<Lanes2>(row(0)), cd0 = load<Lanes2>(row(0) + 2);
    const Lanes2 ab1 = load<Lanes2>(row(1)), cd1 = load<Lanes2>(row(1) + 2);
    return {__builtin_shufflevector(ab0, ab1, 0, 2), __builtin_shufflevector(ab0, ab1, 1, 3),
            __builtin_shufflevector(cd0, cd1, 0, 2), __builtin_shufflevector(cd0, cd1, 1, 3)};
  } else if constexpr (lane_count<Real> == 4) {
    Fields4<Real> f{load<Lanes4>(row(0)), load<Lanes4>(row(1)), load<Lanes4>(row(2)), load<Lanes4>(row(3))};
    transpose(f.a, f.b, f.c, f.d);
    return f;
  } else {
    const Fields4<Lanes4> low = load_records<Lanes4>(row);
    const Fields4<Lanes4> high = load_records<Lanes4>([&](int l) { return row(l + 4); });
    auto join = [](Lanes4 first, Lanes4 second) {
      return __builtin_shufflevector(first, second, 0, 1, 2, 3, 4, 5, 6, 7);
    };
    return {join(low.a, high.a), join(low.b, high.b), join(low.c, high.c), join(low.d, high.d)};
  }
}
template <class Real, class Row>
[[gnu::always_inline]] inline void store_records(Fields4<Real> f, const Row& row) {
  if constexpr (lane_count<Real> == 1) {
    double* const p = row(0);
    p[0] = f.a;
    p[1] = f.b;
    p[2] = f.c;
    p[3] = f.d;
  } else if constexpr (lane_count<Real> == 2) {
    store(row(0), __builtin_shufflevector(f.a, f.b, 0, 2));
    store(row(0) + 2, __builtin_shufflevector(f.c, f.d, 0, 2));
    store(row(1), __builtin_shufflevector(f.a, f.b, 1, 3));
    store(row(1) + 2, __builtin_shufflevector(f.c, f.d, 1, 3));
  } else if constexpr (lane_count<Real> == 4) {
    transpose(f.a, f.b, f.c, f.d);
    store(row(0), f.a);
    store(row(1), f.b);
    store(row(2), f.c);
    store(row(3), f.d);
  } else {
    auto low = [](Lanes8 v) { return __builtin_shufflevector(v, v, 0, 1, 2, 3); };
    auto high = [](Lanes8 v) { return __builtin_shufflevector(v, v, 4, 5, 6, 7); };
    store_records<Lanes4>({low(f.a), low(f.b), low(f.c), low(f.d)}, row);
    store_records<Lanes4>({high(f.a), high(f.b), high(f.c), high(f.d)}, [&](int l) { return row(l + 4); });
  }
}

template <class Real>
Vec3<Real> zero_vec3() {
  return {Real{}, Real{}, Real{}};
}
template <class Real>
[[gnu::always_inline]] inline Vec3<double> lane(const Vec3<Real>& v, int l) {
  return {lane(v.x, l), lane(v.y, l), lane(v.z, l)};
}

template <class Real>
Vec3<Real> operator+(const Vec3<Real>& a, const Vec3<Real>& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <class Real>
Vec3<Real> operator-(const Vec3<Real>& a, const Vec3<Real>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class Real>
Vec3<Real> operator-(const Vec3<Real>& a) {
  return {-a.x, -a.y, -a.z};
}
template <class Real, class Scale>
Vec3<Real> operator*(const Vec3<Real>& a, Scale s) {
  return {a.x * s, a.y * s, a.z * s};
}
template <class Real, class Scale>
Vec3<Real> operator*(Scale s, const Vec3<Real>& a) {
  return {s * a.x, s * a.y, s * a.z};
}
template <class Real, class Scale>
Vec3<Real> operator/(const Vec3<Real>& a, Scale s) {
  return {a.x / s, a.y / s, a.z / s};
}
template <class Real>
Real dot(const Vec3<Real>& a, const Vec3<Real>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class Real>
Real squared_norm(const Vec3<Real>& a) {
  return dot(a, a);
}
template <class Real>
Vec3<Real> cross(const Vec3<Real>& a, const Vec3<Real>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class LaneMask, class Real>
Vec3<Real> select(LaneMask mask, const Vec3<Real>& a, const Vec3<Real>& b) {
  return {select(mask, a.x, b.x), select(mask, a.y, b.y), select(mask, a.z, b.z)};
}

}  // namespace pdamp::simd
