#pragma once
/// Which particles are in which cell, for a population that changes one particle at a
/// time (a sphere crossing a face, coming to rest, lifting off): O(1) to insert, remove
/// or move, no allocation after construction.
///
/// A cell keeps its first `inline_capacity` members in 16 bytes with their count, and
/// any further ones in an intrusive doubly linked list. A gas holds about one sphere per
/// cell and a dense bed rarely more than three, so `copy_members` gathers a cell with one
/// 16-byte copy and without walking a list: the number of members is a coin toss that a
/// loop over them would mispredict.

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <span>
#include <vector>

#include "pdamp/model/checkpoint.hpp"

namespace pdamp::hard {

class CellMembers {
 public:
  static constexpr int inline_capacity = 3;

  CellMembers(int cell_count, int particle_count)
      : cells_(cell_count),
        overflow_(cell_count, none),
        next_(particle_count, none),
        prev_(particle_count, none),
        cell_(particle_count, none) {}

  void insert(int particle, int cell) {
    cell_[particle] = cell;
    Cell& c = cells_[cell];
    if (c.count < inline_capacity) {
      c.members[c.count] = particle;
    } else {
      int& head = overflow_[cell];
      prev_[particle] = none;
      next_[particle] = head;
      if (head != none) prev_[head] = particle;
      head = particle;
    }
    ++c.count;
  }
  void remove(int particle) {
    const int cell = cell_[particle];
    Cell& c = cells_[cell];
    cell_[particle] = none;
    // Its inline slot (inline_capacity if none), without a branch per slot: where a
    // sphere sits among its cell's members is a coin toss. Slots beyond the count may
    // still hold former members: they do not count.
    int place = inline_capacity;
    for (int k = inline_capacity - 1; k >= 0; --k) place = ((k < c.count) & (c.members[k] == particle)) ? k : place;
    int* const slot = c.members.data() + place;
    int* const inline_end = c.members.data() + inline_capacity;
    --c.count;
    if (slot == inline_end) {
      unlink_overflow(cell, particle);
    } else if (overflow_[cell] != none) {
      // The first overflow member takes the freed slot: the inline members stay the first.
      *slot = overflow_[cell];
      unlink_overflow(cell, *slot);
    } else {
      *slot = c.members[c.count];
    }
  }
  void move(int particle, int cell) {
    remove(particle);
    insert(particle, cell);
  }
  bool contains(int particle) const { return cell_[particle] != none; }
  template <class Visit>
  void for_each_in(int cell, Visit visit) const {
    const Cell& c = cells_[cell];
    for (int k = 0; k < std::min(c.count, inline_capacity); ++k) visit(c.members[k]);
    if (c.count <= inline_capacity) return;  // without reading the overflow heads' cache line
    for (int p = overflow_[cell]; p != none; p = next_[p]) visit(p);
  }
  /// Writes the members of `cell` to `out` and returns how many there are; `out` must
  /// have room for them and for at least `copy_width` entries.
  int copy_members(int cell, int* out) const {
    const Cell& c = cells_[cell];
    std::memcpy(out, &c, sizeof(Cell));  // the members, then junk beyond them
    if (c.count > inline_capacity) {
      int k = inline_capacity;
      for (int p = overflow_[cell]; p != none; p = next_[p]) out[k++] = p;
    }
    return c.count;
  }
  static constexpr int copy_width = 4;
  /// Asks for the cache lines of `cells`, to be gathered soon. Inline, and always: as a
  /// call of its own it has no effect the compiler can see, and may be dropped.
  [[gnu::always_inline]] void prefetch(std::span<const int> cells) const {
    for (const int cell : cells) __builtin_prefetch(&cells_[cell]);
  }
  std::size_t cells_bytes() const { return cells_.size() * sizeof(Cell); }
  /// The members of the `cell_count` cells `cells` written one after another to `out`
  /// (room for all of them and copy_width more), and how many there are. Unrolled, and
  /// without looking at a cell's count but to add it and to OR it into the others' (which
  /// has bits beyond the inline capacity's if any count exceeds it): the rare cell with
  /// overflow members sends the whole gather down copy_members' path instead.
  template <int cell_count>
  int gather(const int* cells, int* out) const {
    static_assert(std::has_single_bit(static_cast<unsigned>(inline_capacity) + 1));
    int count = 0;
    int counts_or = 0;
#pragma GCC unroll 27
    for (int k = 0; k < cell_count; ++k) {
      const Cell& c = cells_[cells[k]];
      std::memcpy(out + count, &c, sizeof(Cell));
      count += c.count;
      counts_or |= c.count;
    }
    if (counts_or > inline_capacity) {
      count = 0;
      for (int k = 0; k < cell_count; ++k) count += copy_members(cells[k], out + count);
    }
    return count;
  }

  /// Its state verbatim (hard_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  static constexpr int none = -1;
  struct alignas(16) Cell {
    std::array<int, inline_capacity> members{};
    int count = 0;
  };
  static_assert(sizeof(Cell) == copy_width * sizeof(int));
  void unlink_overflow(int cell, int particle) {
    if (prev_[particle] != none) {
      next_[prev_[particle]] = next_[particle];
    } else {
      overflow_[cell] = next_[particle];
    }
    if (next_[particle] != none) prev_[next_[particle]] = prev_[particle];
  }

  std::vector<Cell> cells_;
  std::vector<int> overflow_;     ///< each cell's first member beyond the inline ones
  std::vector<int> next_, prev_;  ///< the overflow lists
  std::vector<int> cell_;
};

}  // namespace pdamp::hard
