#pragma once
/// The hard-sphere engine's future: every predicted event, earliest first.
///
/// Predictions go out of date all the time (a collision voids every event of its two
/// spheres), and most events never happen. So events are kept per owner (the sphere an
/// event was predicted for; one more owner for the host's events) in a small unsorted
/// list, and a 4-ary heap orders only the owners, by their earliest event. Then
/// - when a sphere's trajectory changes, its own events are forgotten at once
///   (`forget`), without touching the heap until the next look at the top;
/// - an owner's list is pruned of out-of-date events whenever it is re-keyed, so an
///   event voided by its partner usually leaves without ever reaching the top;
/// - the heap holds at most N + 1 entries, whatever the number of events.
/// Events still carry the trajectory counters they were predicted with: one that went out
/// of date after its owner was last re-keyed still reaches the top and is dropped there
/// (`HardEngine::is_current`).

#include <cstdint>
#include <limits>
#include <vector>

namespace pdamp::hard {

enum class EventKind : std::uint8_t {
  sphere_sphere,  ///< two free spheres touch
  side_wall,      ///< a free sphere reaches the cylinder's side wall
  bottom_cap,     ///< ... the bottom cap (moving with the host)
  top_cap,        ///< ... the top cap
  rider,          ///< a free sphere reaches a sphere riding with the host
  cell_crossing,  ///< a free sphere crosses a face of its cell; j = face (see HardEngine::Face)
  host_check,     ///< a free sphere may come within reach of the host's walls or bed (speed envelope)
  host_margin,    ///< a near sphere comes within the margin of a cap or rider, or its host horizon ends
  bed_release,    ///< the host's acceleration stops pressing the riding spheres against their cap
};

struct Event {
  double t_s;
  std::int32_t i;          ///< the particle (−1 for bed_release)
  std::int32_t j;          ///< the partner particle, or the crossed face
  std::uint32_t count_i;   ///< i's trajectory counter when predicted
  std::uint32_t count_j;   ///< j's counter (sphere_sphere), i's host stamp (caps, rider, host_margin) or the host epoch (bed_release)
  EventKind kind;
};

/// Strict order on time; ties broken by kind and particles so the order never depends on
/// the queue's internals (determinism).
inline bool earlier(const Event& a, const Event& b) {
  if (a.t_s != b.t_s) return a.t_s < b.t_s;
  if (a.kind != b.kind) return a.kind < b.kind;
  if (a.i != b.i) return a.i < b.i;
  return a.j < b.j;
}

class EventQueue {
 public:
  /// Owners 0 … particle_count − 1 are the spheres; events with i < 0 belong to the host.
  explicit EventQueue(int particle_count)
      : lists_(particle_count + 1), slot_(particle_count + 1, absent), dirty_flag_(particle_count + 1, 0) {}

  void push(const Event& event) {
    const int owner = owner_of(event);
    lists_[owner].push_back(event);
    mark_dirty(owner);
  }
  /// Drops every event predicted for sphere i (its trajectory changed).
  void forget(int i) {
    lists_[i].clear();
    mark_dirty(i);
  }
  void clear() {
    for (auto& list : lists_) list.clear();
    for (const int owner : dirty_) dirty_flag_[owner] = 0;
    dirty_.clear();
    for (const Entry& e : heap_) slot_[owner_of(e.event)] = absent;
    heap_.clear();
  }

  /// The earliest event, or nullptr if there is none. Owners changed since the last call
  /// are re-keyed first, keeping only the events `current` accepts (staleness is for ever).
  template <class Current>
  const Event* top(Current current) {
    for (const int owner : dirty_) rekey(owner, current);
    dirty_.clear();
    return heap_.empty() ? nullptr : &heap_.front().event;
  }
  /// Removes the event `top` returned.
  void pop() {
    const int owner = owner_of(heap_.front().event);
    std::vector<Event>& list = lists_[owner];
    list[heap_.front().index] = list.back();
    list.pop_back();
    mark_dirty(owner);
  }

 private:
  struct Entry {
    Event event;  ///< the owner's earliest event (a copy, so that sifting stays in the heap's memory)
    std::uint32_t index;  ///< its position in the owner's list
  };
  static constexpr int arity = 4;
  static constexpr std::uint32_t absent = std::numeric_limits<std::uint32_t>::max();

  int owner_of(const Event& e) const { return e.i >= 0 ? e.i : static_cast<int>(lists_.size()) - 1; }
  void mark_dirty(int owner) {
    if (!dirty_flag_[owner]) dirty_.push_back(owner);
    dirty_flag_[owner] = 1;
  }

  template <class Current>
  void rekey(int owner, Current current) {
    dirty_flag_[owner] = 0;
    std::vector<Event>& list = lists_[owner];
    std::size_t best = 0;
    for (std::size_t k = 0; k < list.size();) {
      if (!current(list[k])) {
        list[k] = list.back();
        list.pop_back();
        continue;
      }
      if (k > 0 && earlier(list[k], list[best])) best = k;
      ++k;
    }
    const std::uint32_t slot = slot_[owner];
    if (list.empty()) {
      if (slot != absent) erase(slot);
      return;
    }
    const Entry entry{list[best], static_cast<std::uint32_t>(best)};
    if (slot == absent) {
      heap_.push_back(entry);
      sift_up(static_cast<std::uint32_t>(heap_.size() - 1), entry);
    } else if (earlier(entry.event, heap_[slot].event)) {
      sift_up(slot, entry);
    } else {
      sift_down(slot, entry);
    }
  }
  void erase(std::uint32_t slot) {
    slot_[owner_of(heap_[slot].event)] = absent;
    const Entry last = heap_.back();
    heap_.pop_back();
    if (slot == heap_.size()) return;
    if (earlier(last.event, heap_[slot].event)) {
      sift_up(slot, last);
    } else {
      sift_down(slot, last);
    }
  }
  /// Puts `entry` at `slot` or above it, moving later parents down.
  void sift_up(std::uint32_t slot, const Entry& entry) {
    while (slot > 0) {
      const std::uint32_t parent = (slot - 1) / arity;
      if (!earlier(entry.event, heap_[parent].event)) break;
      place(slot, heap_[parent]);
      slot = parent;
    }
    place(slot, entry);
  }
  /// Puts `entry` at `slot` or below it, moving earlier children up.
  void sift_down(std::uint32_t slot, const Entry& entry) {
    const auto size = static_cast<std::uint32_t>(heap_.size());
    for (;;) {
      const std::uint32_t first = arity * slot + 1;
      if (first >= size) break;
      const std::uint32_t end = first + arity < size ? first + arity : size;
      std::uint32_t child = first;
      for (std::uint32_t c = first + 1; c < end; ++c) {
        if (earlier(heap_[c].event, heap_[child].event)) child = c;
      }
      if (!earlier(heap_[child].event, entry.event)) break;
      place(slot, heap_[child]);
      slot = child;
    }
    place(slot, entry);
  }
  void place(std::uint32_t slot, const Entry& entry) {
    heap_[slot] = entry;
    slot_[owner_of(entry.event)] = slot;
  }

  std::vector<std::vector<Event>> lists_;  ///< each owner's events, unsorted
  std::vector<Entry> heap_;                ///< owners with events, by their earliest
  std::vector<std::uint32_t> slot_;        ///< each owner's place in heap_, or absent
  std::vector<int> dirty_;                 ///< owners whose events changed since the last top()
  std::vector<std::uint8_t> dirty_flag_;
};

}  // namespace pdamp::hard
