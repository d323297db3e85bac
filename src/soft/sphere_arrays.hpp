#pragma once
/// How the soft engine stores its data. Per-sphere data are structures of arrays: each
/// component of a vector quantity in an array of its own, aligned to cache lines, so that
/// SIMD lanes load the same component of consecutive spheres.

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <new>
#include <utility>
#include <vector>

namespace pdamp::soft {

template <class T>
struct CacheLineAllocator {
  using value_type = T;
  static constexpr std::align_val_t alignment{64};

  CacheLineAllocator() = default;
  template <class U>
  explicit CacheLineAllocator(const CacheLineAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), alignment)); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, alignment); }
  friend bool operator==(const CacheLineAllocator&, const CacheLineAllocator&) { return true; }
};

/// Appends to a vector that grows by a quarter, not twice its size, when full: the engine's
/// lists are most of its memory.
template <class Vector, class Value>
void push_back_compactly(Vector& v, Value&& value) {
  if (v.size() == v.capacity()) v.reserve(v.size() + v.size() / 4 + 16);
  v.push_back(std::forward<Value>(value));
}

/// Renumbers the spheres in place, a[s] ← a[order[s]], following the cycles of the
/// permutation (`visited` is scratch): no copy of the array is needed.
template <class Array>
void permute(Array& a, const std::vector<int>& order, std::vector<bool>& visited) {
  const int n = static_cast<int>(order.size());
  visited.assign(n, false);
  for (int start = 0; start < n; ++start) {
    if (visited[start]) continue;
    const auto first = a[start];
    int s = start;
    for (; order[s] != start; s = order[s]) {
      a[s] = a[order[s]];
      visited[s] = true;
    }
    a[s] = first;
    visited[s] = true;
  }
}

/// One number per sphere, and zeros past the last sphere, so that a SIMD register's worth
/// of consecutive spheres can be loaded from any sphere.
class SphereScalars {
 public:
  static constexpr int padding = 8;

  void assign(int spheres, double value) {
    values_.assign(spheres + padding, 0.0);
    std::fill_n(values_.begin(), spheres, value);
  }
  int size() const { return static_cast<int>(values_.size()) - padding; }
  double* data() { return values_.data(); }
  const double* data() const { return values_.data(); }
  double& operator[](int s) { return values_[s]; }
  double operator[](int s) const { return values_[s]; }

 private:
  std::vector<double, CacheLineAllocator<double>> values_;
};

/// Records of four doubles per sphere: a vector and a number that goes with it, so that
/// whoever needs one of them for a sphere finds the others in the same cache line (and SIMD
/// lanes load a record at once).
/// Where a sphere is and how large.
struct alignas(32) Ball {
  double x, y, z, radius;
};
/// A sphere's velocity and 1/m, or its spin and 1/I.
struct alignas(32) Motion {
  double x, y, z, inverse_inertia;
};
static_assert(sizeof(Ball) == 4 * sizeof(double) && sizeof(Motion) == 4 * sizeof(double));

/// One record per sphere, and blank ones past the last sphere (as for SphereScalars).
template <class Record>
class SphereRecords {
 public:
  static constexpr int padding = SphereScalars::padding;

  void assign(int spheres) { records_.assign(spheres + padding, Record{}); }
  int size() const { return static_cast<int>(records_.size()) - padding; }
  Record& operator[](int s) { return records_[s]; }
  const Record& operator[](int s) const { return records_[s]; }
  /// The records as arrays of four doubles.
  double* data() { return &records_.front().x; }
  const double* data() const { return &records_.front().x; }
  Eigen::Vector3d vector(int s) const { return {records_[s].x, records_[s].y, records_[s].z}; }
  void set_vector(int s, const Eigen::Vector3d& v) {
    records_[s].x = v.x();
    records_[s].y = v.y();
    records_[s].z = v.z();
  }

 private:
  std::vector<Record, CacheLineAllocator<Record>> records_;
};
using SphereBalls = SphereRecords<Ball>;
using SphereMotions = SphereRecords<Motion>;

/// One vector per sphere.
struct SphereVectors {
  SphereScalars x, y, z;

  void assign(int spheres, double value) {
    x.assign(spheres, value);
    y.assign(spheres, value);
    z.assign(spheres, value);
  }
  Eigen::Vector3d operator[](int s) const { return {x[s], y[s], z[s]}; }
  void set(int s, const Eigen::Vector3d& v) {
    x[s] = v.x();
    y[s] = v.y();
    z[s] = v.z();
  }
};

}  // namespace pdamp::soft
