#pragma once
/// Which particles are in which cell, for a population that changes one particle at a
/// time (a sphere crossing a face, coming to rest, lifting off): an intrusive doubly
/// linked list per cell, O(1) to insert, remove or move, no allocation after construction.

#include <vector>

namespace pdamp::hard {

class CellMembers {
 public:
  CellMembers(int cell_count, int particle_count)
      : head_(cell_count, none), next_(particle_count, none), prev_(particle_count, none),
        cell_(particle_count, none) {}

  void insert(int particle, int cell) {
    cell_[particle] = cell;
    prev_[particle] = none;
    next_[particle] = head_[cell];
    if (head_[cell] != none) prev_[head_[cell]] = particle;
    head_[cell] = particle;
  }
  void remove(int particle) {
    const int cell = cell_[particle];
    if (prev_[particle] != none) {
      next_[prev_[particle]] = next_[particle];
    } else {
      head_[cell] = next_[particle];
    }
    if (next_[particle] != none) prev_[next_[particle]] = prev_[particle];
    cell_[particle] = none;
  }
  void move(int particle, int cell) {
    remove(particle);
    insert(particle, cell);
  }
  bool contains(int particle) const { return cell_[particle] != none; }
  template <class Visit>
  void for_each_in(int cell, Visit visit) const {
    for (int p = head_[cell]; p != none; p = next_[p]) visit(p);
  }

 private:
  static constexpr int none = -1;
  std::vector<int> head_, next_, prev_, cell_;
};

}  // namespace pdamp::hard
