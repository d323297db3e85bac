#pragma once
/// A set of particle indices with O(1) insert, erase and membership and a sweep that
/// visits the members in insertion order. Erased members leave the list lazily, at the
/// next sweep.

#include <cstdint>
#include <vector>

#include "pdamp/model/checkpoint.hpp"

namespace pdamp::hard {

class ParticleSet {
 public:
  explicit ParticleSet(int particle_count) : state_(particle_count, absent) {}

  void insert(int i) {
    if (state_[i] == absent) list_.push_back(i);
    state_[i] = member;
  }
  void erase(int i) {
    if (state_[i] == member) state_[i] = erased;
  }
  bool contains(int i) const { return state_[i] == member; }
  void clear() {
    for (const int i : list_) state_[i] = absent;
    list_.clear();
  }
  /// Takes every member out and calls visit(i) for it; visit may put members back
  /// (this set's or any other's) without disturbing the sweep.
  template <class Visit>
  void sweep(Visit visit) {
    sweeping_.swap(list_);
    list_.clear();
    for (const int i : sweeping_) {
      const bool was_member = state_[i] == member;
      state_[i] = absent;
      if (was_member) visit(i);
    }
    sweeping_.clear();
  }

  /// Its state verbatim (hard_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  enum : std::uint8_t { absent, member, erased };
  std::vector<std::uint8_t> state_;
  std::vector<int> list_;
  std::vector<int> sweeping_;
};

}  // namespace pdamp::hard
