#pragma once
/// The hard-sphere engine's future: every predicted event, earliest first.
///
/// Predictions go out of date all the time (a collision voids every event of its two
/// spheres), and most events never happen. So events are kept per owner (the sphere an
/// event was predicted for; one more owner for the host's events) in a small unsorted
/// list, and only each owner's earliest event is ordered. Then
/// - when a sphere's trajectory changes, its own events are forgotten at once
///   (`forget`), without touching the order until the next look at the top;
/// - an owner's list is pruned of out-of-date events whenever it is re-keyed, so an
///   event voided by its partner usually leaves without ever reaching the top. Not a
///   fresh list, though (one refilled since its owner's trajectory changed, with no
///   trajectory or host stamp changed since: most re-keys, those of a collision's two
///   spheres): its events are known current, and asking would cost a load per event.
/// An event is thus always of its owner's current trajectory; it still carries the
/// partner's counter (or stamp) it was predicted with, and one whose partner changed after
/// its owner was last re-keyed still reaches the top and is dropped there
/// (`FreeFlight::is_current`). The lists keep events in 16 bytes (`Stored`): four to a
/// cache line, where every re-key reads its owner's whole list.
///
/// The owners' earliest events are ordered by a calendar (Paul, J. Comput. Phys. 221,
/// 2007): time is cut into buckets about as wide as the time in which a few events
/// happen. Only the current bucket's entries are in a Boost.Heap; later ones wait,
/// unsorted, in their bucket (or, beyond the calendar's reach, in a second Boost.Heap)
/// until the current bucket runs dry. A re-keyed owner is simply entered again, with its
/// new version; entries whose version is no longer their owner's are dropped wherever
/// they are met. The heap a pop sifts through thus holds a handful of entries, not one
/// per sphere: with ~N entries the sifting cost log N comparisons, most of them
/// mispredicted branches. A bucket's list is threaded through an array of its own (8
/// bytes an owner), not through the owners' records: with 10^5 spheres the records are far
/// out of cache, and a walk through them waits for each miss before the next, where the
/// links stay in cache and the records' loads overlap.

#include <algorithm>
#include <bit>
#include <boost/heap/d_ary_heap.hpp>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "pdamp/model/checkpoint.hpp"

namespace pdamp::hard {

enum class EventKind : std::uint8_t {
  sphere_sphere,  ///< two free spheres touch
  side_wall,      ///< a free sphere reaches the cylinder's side wall
  bottom_cap,     ///< ... the bottom cap (moving with the host)
  top_cap,        ///< ... the top cap
  rider,          ///< a free sphere reaches a sphere riding with the host
  cell_crossing,  ///< a free sphere crosses a face of its cell; j = face (see FreeFlight::Face)
  host_check,     ///< a free sphere may come within reach of the host's walls or bed (speed envelope)
  host_margin,    ///< a near sphere comes within the margin of a cap or rider, or its host horizon ends
  bed_release,    ///< the host's acceleration stops pressing the riding spheres against their cap
};

/// A predicted event. It needs no trajectory counter of i: a change of i's trajectory
/// forgets all of i's events (EventQueue::forget).
struct Event {
  double t_s;
  std::int32_t i;  ///< the particle (−1 for bed_release)
  /// The partner particle, the crossed face, or the tier a host_margin is of (its descent
  /// resumes there); ≥ 0.
  std::int32_t j;
  std::uint32_t count_j;  ///< j's counter (sphere_sphere), i's host stamp (caps, rider, host_margin) or the host epoch
                          ///< (bed_release)
  EventKind kind;
};

/// Whether an event's count_j is its sphere's host stamp (see Event::count_j).
/// A mask, not a chain of comparisons: the kinds of successive events are a coin toss.
constexpr bool carries_host_stamp(EventKind kind) {
  constexpr unsigned stamped =
      1u << static_cast<unsigned>(EventKind::bottom_cap) | 1u << static_cast<unsigned>(EventKind::top_cap) |
      1u << static_cast<unsigned>(EventKind::rider) | 1u << static_cast<unsigned>(EventKind::host_margin);
  return (stamped >> static_cast<unsigned>(kind)) & 1u;
}

/// The order of events at one time, by kind, then particle, then partner, packed into one
/// number (i + 1 and j below 2^28, see EventQueue::max_particles).
inline std::uint64_t tie_key(const Event& e) {
  return (static_cast<std::uint64_t>(e.kind) << 58) | (static_cast<std::uint64_t>(e.i + 1) << 29) |
         static_cast<std::uint64_t>(e.j);
}

/// Strict order on time; ties broken by kind and particles so the order never depends on
/// the queue's internals (determinism).
inline bool earlier(const Event& a, const Event& b) {
  if (a.t_s != b.t_s) return a.t_s < b.t_s;
  return tie_key(a) < tie_key(b);
}

class EventQueue {
 public:
  /// Owners 0 … particle_count − 1 are the spheres; events with i < 0 belong to the host.
  explicit EventQueue(int particle_count)
      : lists_(particle_count + 1),
        keyed_(particle_count + 1),
        links_(particle_count + 1),
        buckets_(std::bit_ceil(static_cast<std::size_t>(particle_count) + 1), none) {
    if (particle_count > max_particles) throw std::length_error("the event queue orders at most 2^28 - 2 spheres");
  }
  static constexpr int max_particles = (1 << 28) - 2;

  void push(const Event& event) {
    const int owner = owner_of(event);
    lists_[owner].push_back(Stored::of(event));
    mark_dirty(owner);
    fresh_filled_ |= keyed_[owner].fresh;
  }
  /// Drops every event predicted for sphere i (its trajectory changed). Other owners'
  /// events with i for partner may now be out of date.
  void forget(int i) {
    // Rare: a collision changes both trajectories before it predicts either.
    if (fresh_filled_) [[unlikely]]
      stale_fresh_lists();
    lists_[i].clear();
    mark_dirty(i);
    keyed_[i].fresh = 1;
  }
  /// Sphere i's host stamp changed: its events that carry the stamp are out of date.
  void host_stamp_changed(int i) {
    if (!lists_[i].empty()) keyed_[i].fresh = 0;
  }
  void clear() {
    for (auto& list : lists_) list.clear();
    for (Keyed& k : keyed_) k = Keyed{.version = k.version + 1};
    dirty_.clear();
    fresh_filled_ = 0;
    std::fill(buckets_.begin(), buckets_.end(), none);
    current_.clear();
    beyond_.clear();
  }

  /// The earliest event (valid until the next call), or nullptr if there is none. Owners
  /// changed since the last call are re-keyed first, keeping only the events `current`
  /// accepts (staleness is for ever).
  template <class Current>
  const Event* top(Current current) {
    for (const int owner : dirty_) rekey(owner, current);
    dirty_.clear();
    fresh_filled_ = 0;
    for (;;) {
      while (!current_.empty() && !is_keyed(current_.top())) current_.pop();
      if (!current_.empty()) break;
      if (!next_bucket()) return nullptr;
    }
    const Entry& top = current_.top();
    top_ = event_of(static_cast<int>(top.owner), lists_[top.owner][keyed_[top.owner].index]);
    return &top_;
  }
  /// Removes the event `top` returned.
  void pop() {
    const Entry top = current_.top();
    current_.pop();
    std::vector<Stored>& list = lists_[top.owner];
    Keyed& keyed = keyed_[top.owner];
    list[keyed.index] = list.back();
    list.pop_back();
    keyed.version++;
    keyed.place = Place::none;
    mark_dirty(static_cast<int>(top.owner));
    t_last_pop_s_ = top.t_s;
    adapt_bucket_width(top.t_s);
  }

  /// Its state verbatim (hard_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  static constexpr std::int32_t none = -1;
  /// An event in its owner's list: the owner is i (or the host, i = −1).
  struct Stored {
    double t_s;
    std::uint32_t kind_j;  ///< kind << 28 | j: for one owner, the order of tie_key
    std::uint32_t count_j;
    static Stored of(const Event& e) {
      return {e.t_s, static_cast<std::uint32_t>(e.kind) << 28 | static_cast<std::uint32_t>(e.j), e.count_j};
    }
    /// `earlier` for two events of one owner.
    bool earlier_than(const Stored& other) const {
      if (t_s != other.t_s) return t_s < other.t_s;
      return kind_j < other.kind_j;
    }
  };
  static_assert(sizeof(Stored) == 16);
  Event event_of(int owner, const Stored& s) const {
    const int i = owner == static_cast<int>(lists_.size()) - 1 ? -1 : owner;
    return {s.t_s, i, static_cast<std::int32_t>(s.kind_j & ((1u << 28) - 1)), s.count_j,
            static_cast<EventKind>(s.kind_j >> 28)};
  }
  /// An owner's earliest event as the heaps order it; out of date once its version is no
  /// longer the owner's.
  struct Entry {
    double t_s;
    std::uint64_t tie;  ///< tie_key of the event
    std::uint32_t owner;
    std::uint32_t version;
  };
  /// Where an owner's earliest event is ordered.
  enum class Place : std::uint8_t { none, current, bucket, beyond };
  /// What an owner's place in the calendar stands for (two to a cache line).
  struct Keyed {
    double t_s = 0.0;
    std::uint64_t tie = 0;
    std::uint32_t version = 0;  ///< of its entry in a heap (current or beyond)
    std::uint32_t index = 0;    ///< the event's position in the owner's list
    std::uint32_t slot = 0;     ///< its bucket's slot (place bucket)
    Place place = Place::none;
    std::uint8_t dirty = 0;  ///< re-key at the next top()
    /// Every event in the owner's list was entered since its trajectory last changed, and
    /// nothing any of them depends on has changed since: re-keying need not look at them.
    std::uint8_t fresh = 0;
  };
  static_assert(sizeof(Keyed) == 32);
  /// An owner's neighbours in its bucket's list (place bucket).
  struct Link {
    std::int32_t previous = none, next = none;
  };
  /// Boost.Heap puts the greatest element on top; here that is the earliest event. Free
  /// of branches (`earlier`, with the tie key at hand).
  struct Later {
    bool operator()(const Entry& a, const Entry& b) const {
      return (b.t_s < a.t_s) | ((b.t_s == a.t_s) & (b.tie < a.tie));
    }
  };
  using Heap = boost::heap::d_ary_heap<Entry, boost::heap::arity<4>, boost::heap::compare<Later>>;

  int owner_of(const Event& e) const { return e.i >= 0 ? e.i : static_cast<int>(lists_.size()) - 1; }
  void mark_dirty(int owner) {
    if (!keyed_[owner].dirty) dirty_.push_back(owner);
    keyed_[owner].dirty = 1;
  }
  /// No list refilled since its owner's trajectory changed can be vouched for any more.
  [[gnu::cold, gnu::noinline]] void stale_fresh_lists() {
    for (const int owner : dirty_) keyed_[owner].fresh = 0;
    fresh_filled_ = 0;
  }
  bool is_keyed(const Entry& e) const { return keyed_[e.owner].version == e.version; }

  template <class Current>
  void rekey(int owner, Current current) {
    Keyed& keyed = keyed_[owner];
    keyed.dirty = 0;
    const bool fresh = keyed.fresh;
    keyed.fresh = 0;  // events entered from now on join older ones
    std::vector<Stored>& list = lists_[owner];
    std::size_t best = 0;
    for (std::size_t k = 0; k < list.size();) {
#ifndef NDEBUG
      if (fresh && !current(event_of(owner, list[k])))
        throw std::logic_error("an event of a fresh list is out of date");
#endif
      if (!fresh && !current(event_of(owner, list[k]))) {
        list[k] = list.back();
        list.pop_back();
        continue;
      }
      if (k > 0 && list[k].earlier_than(list[best])) best = k;
      ++k;
    }
    keyed.index = static_cast<std::uint32_t>(best);
    if (list.empty()) {
      leave(owner);
      return;
    }
    const std::uint64_t tie = tie_key(event_of(owner, list[best]));
    const bool same_event = keyed.place != Place::none && keyed.t_s == list[best].t_s && keyed.tie == tie;
    if (same_event) return;  // perhaps moved in the list
    leave(owner);
    keyed.t_s = list[best].t_s;
    keyed.tie = tie;
    enter(owner);
  }

  // The calendar.
  /// Bucket n holds the owners whose earliest event has (t − origin) · (1 / width),
  /// truncated, = n (no event is earlier than the origin, the last refile's time); events
  /// too far ahead to count, or with no width yet, go to `far_bucket`. A product and a
  /// truncation, not a quotient and a floor: this sits in the dependency chain of every
  /// entry, and, monotonic in t like the quotient, it keeps the order of events the same.
  std::int64_t bucket_of(double t_s) const {
    const double scaled = (t_s - origin_s_) * buckets_per_s_;
    return scaled < static_cast<double>(far_bucket) ? static_cast<std::int64_t>(scaled) : far_bucket;
  }
  static constexpr std::int64_t far_bucket = std::int64_t{1} << 60;
  /// The slot of a bucket within reach (their number is a power of two).
  std::uint32_t slot_of(std::int64_t bucket) const {
    return static_cast<std::uint32_t>(static_cast<std::uint64_t>(bucket) & (buckets_.size() - 1));
  }
  std::int64_t reach() const { return static_cast<std::int64_t>(buckets_.size()); }
  Entry entry_of(int owner) const {
    const Keyed& k = keyed_[owner];
    return {k.t_s, k.tie, static_cast<std::uint32_t>(owner), k.version};
  }
  /// Orders owner's earliest event (keyed_[owner].t_s, .tie): into the current heap, a
  /// bucket's list or, beyond the calendar's reach, the other heap.
  void enter(int owner) {
    Keyed& k = keyed_[owner];
    const std::int64_t n = bucket_of(k.t_s);
    if (n <= current_bucket_) {
      k.place = Place::current;
      current_.push(entry_of(owner));
    } else if (n < current_bucket_ + reach()) {
      k.place = Place::bucket;
      k.slot = slot_of(n);
      Link& link = links_[owner];
      link.previous = none;
      link.next = buckets_[k.slot];
      if (link.next != none) links_[link.next].previous = owner;
      buckets_[k.slot] = owner;
    } else {
      k.place = Place::beyond;
      beyond_.push(entry_of(owner));
    }
  }
  /// Takes owner out of the calendar: out of its bucket's list, or its heap entry voided.
  void leave(int owner) {
    Keyed& k = keyed_[owner];
    if (k.place == Place::bucket) {
      const Link& link = links_[owner];
      (link.previous == none ? buckets_[k.slot] : links_[link.previous].next) = link.next;
      if (link.next != none) links_[link.next].previous = link.previous;
    } else {
      ++k.version;
    }
    k.place = Place::none;
  }
  /// Makes the next bucket with entries current; false if there are none.
  bool next_bucket() {
    // A whole calendar of empty buckets since the last owner came within reach: only then
    // is every bucket empty (an owner entered from beyond may sit up to reach() − 1 ahead).
    for (std::size_t empty_steps = 0; empty_steps < buckets_.size(); ++empty_steps) {
      ++current_bucket_;
      // Owners beyond the calendar's reach come within it as it moves on.
      for (; !beyond_.empty(); beyond_.pop()) {
        const Entry& e = beyond_.top();
        if (!is_keyed(e)) continue;
        if (bucket_of(e.t_s) >= current_bucket_ + reach()) break;
        ++keyed_[e.owner].version;
        enter(static_cast<int>(e.owner));
        empty_steps = 0;
      }
      std::int32_t& head = buckets_[slot_of(current_bucket_)];
      for (std::int32_t owner = head; owner != none; owner = links_[owner].next) {
        keyed_[owner].place = Place::current;
        current_.push(entry_of(owner));
        // Its events are wanted within the next few pops; they were last touched when it
        // was keyed, long enough ago to have left the cache.
        __builtin_prefetch(lists_[owner].data() + keyed_[owner].index);
      }
      head = none;
      if (!current_.empty()) return true;
    }
    // A whole calendar without entries: the buckets are too narrow for what comes next.
    // The calendar starts again at the earliest entry beyond it, with buckets at least
    // four times as wide as the gap just crossed.
    while (!beyond_.empty() && !is_keyed(beyond_.top())) beyond_.pop();
    if (beyond_.empty()) return false;
    const double t_next_s = beyond_.top().t_s;
    refile(t_next_s, std::max(width_s_, 4.0 * (t_next_s - t_last_pop_s_)));
    return true;
  }
  /// Keeps the buckets about `events_per_bucket` events wide, from the rate at which
  /// events have been popped lately: refiled when the width is off by more than twice.
  void adapt_bucket_width(double t_s) {
    constexpr double events_per_bucket = 4.0;
    if (pops_ == 0) t_first_pop_s_ = t_s;
    if (++pops_ < static_cast<std::int64_t>(buckets_.size()) + 64) return;
    const double span = t_s - t_first_pop_s_;
    pops_ = 0;
    if (!(span > 0.0)) return;
    const double width = events_per_bucket * span / static_cast<double>(buckets_.size() + 64);
    if (width > 0.5 * width_s_ && width < 2.0 * width_s_) return;
    refile(t_s, width);
  }
  /// Starts the calendar afresh at t_s with buckets `width_s` wide, entering every owner
  /// that has a place in it again.
  void refile(double t_s, double width_s) {
    std::vector<int> owners;
    for (int owner = 0; owner < static_cast<int>(keyed_.size()); ++owner) {
      if (keyed_[owner].place != Place::none) owners.push_back(owner);
    }
    std::fill(buckets_.begin(), buckets_.end(), none);
    current_.clear();
    beyond_.clear();
    origin_s_ = t_s;
    width_s_ = width_s;
    buckets_per_s_ = 1.0 / width_s;
    current_bucket_ = 0;
    for (const int owner : owners) enter(owner);
  }

  std::vector<std::vector<Stored>> lists_;  ///< each owner's events, unsorted
  Event top_{};                             ///< what top() last returned
  std::vector<Keyed> keyed_;
  std::vector<Link> links_;
  std::vector<int> dirty_;         ///< owners whose events changed since the last top()
  std::uint8_t fresh_filled_ = 0;  ///< an event was entered in a fresh list since the last top()
  /// The first owner in each later bucket's list (its slot: the bucket modulo their number).
  std::vector<std::int32_t> buckets_;
  Heap current_;  ///< entries of the current bucket (and any earlier: see enter)
  Heap beyond_;   ///< entries past the calendar's last bucket
  double origin_s_ = 0.0;
  double width_s_ = std::numeric_limits<double>::infinity();  ///< until events have been timed, one bucket holds all
  double buckets_per_s_ = 0.0;                                ///< 1 / width_s_
  std::int64_t current_bucket_ = 0;
  std::int64_t pops_ = 0;
  double t_first_pop_s_ = 0.0;
  double t_last_pop_s_ = 0.0;
};

}  // namespace pdamp::hard
