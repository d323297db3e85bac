#pragma once
/// Arithmetic for one contact or two side by side. The contact law is written once, for a
/// real type that is either `double` or `Lanes` (two doubles in one SSE2 register, a GCC
/// vector extension): each lane performs the same IEEE operations in the same order as the
/// scalar code, so a contact gives the same bits whichever way it is evaluated. Branches
/// on data are selects, which work on both.

#include <Eigen/Core>
#include <cmath>
#include <type_traits>
#include <utility>

namespace pdamp::soft {

using Lanes = double __attribute__((vector_size(16)));

template <class Real>
constexpr int lane_count = std::is_same_v<Real, Lanes> ? 2 : 1;

inline double sqrt_of(double a) { return std::sqrt(a); }
inline Lanes sqrt_of(Lanes a) { return Lanes{std::sqrt(a[0]), std::sqrt(a[1])}; }  // one sqrtpd

/// `mask ? a : b`, per lane; the mask is a comparison of reals.
template <class Mask, class Real>
Real select(Mask mask, Real a, Real b) {
  return mask ? a : b;
}

inline double lane(double a, int) { return a; }
inline double lane(Lanes a, int l) { return a[l]; }
inline bool lane_is_set(bool mask, int) { return mask; }
template <class Mask>
bool lane_is_set(Mask mask, int l) {
  return mask[l] != 0;
}

/// Calls f(l) for each lane l, with l a compile-time constant (so that reading a lane
/// is one instruction, not a trip through memory).
template <class Real, class F>
[[gnu::always_inline]] inline void for_each_lane(const F& f) {
  [&]<int... l>(std::integer_sequence<int, l...>) {
    (f(std::integral_constant<int, l>{}), ...);
  }(std::make_integer_sequence<int, lane_count<Real>>{});
}

/// One value per lane, value(l) for lane l.
template <class Real, class Value>
Real gather(const Value& value) {
  if constexpr (lane_count<Real> == 1) {
    return value(0);
  } else {
    return Real{value(0), value(1)};
  }
}

template <class Real>
struct Vec3 {
  Real x, y, z;
};

template <class Real>
Vec3<Real> zero_vec3() {
  return {Real{}, Real{}, Real{}};
}
template <int axis>
double component(const Eigen::Vector3d& v) {
  return v[axis];
}
template <int axis>
double component(const Vec3<double>& v) {
  if constexpr (axis == 0) return v.x;
  if constexpr (axis == 1) return v.y;
  return v.z;
}
/// One vector per lane, vector(l) for lane l (an Eigen::Vector3d or a Vec3<double>).
template <class Real, class Vector>
Vec3<Real> gather3(const Vector& vector) {
  return {gather<Real>([&](int l) { return component<0>(vector(l)); }),
          gather<Real>([&](int l) { return component<1>(vector(l)); }),
          gather<Real>([&](int l) { return component<2>(vector(l)); })};
}
template <class Real>
Vec3<double> lane(const Vec3<Real>& v, int l) {
  return {lane(v.x, l), lane(v.y, l), lane(v.z, l)};
}
inline Vec3<double> to_vec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
inline Eigen::Vector3d to_eigen(const Vec3<double>& v) { return {v.x, v.y, v.z}; }

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
template <class Mask, class Real>
Vec3<Real> select(Mask mask, const Vec3<Real>& a, const Vec3<Real>& b) {
  return {select(mask, a.x, b.x), select(mask, a.y, b.y), select(mask, a.z, b.z)};
}

}  // namespace pdamp::soft
