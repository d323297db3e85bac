/// The hard engine's event queue against a brute-force reference: whatever the time
/// scales (bursts of events a femtosecond apart, then gaps of seconds), it hands out the
/// earliest current event every time.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "hard/event_queue.hpp"

using namespace pdamp::hard;

namespace {

/// Events of `owners` owners, each valid while its owner's counter (count_j here) is
/// unchanged: as in the engine, a change also forgets the owner's events.
struct Reference {
  std::vector<std::uint32_t> counter;
  std::vector<Event> events;
  bool current(const Event& e) const { return counter[e.i] == e.count_j; }
  const Event* earliest() const {
    const Event* best = nullptr;
    for (const Event& e : events) {
      if (current(e) && (!best || earlier(e, *best))) best = &e;
    }
    return best;
  }
};

}  // namespace

TEST_CASE("event queue: the earliest current event first, across time scales 1e-20 s to 1 s") {
  constexpr int owners = 300;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> owner(0, owners - 1);
  EventQueue queue(owners);
  Reference ref{std::vector<std::uint32_t>(owners, 0), {}};
  const auto current = [&](const Event& e) { return ref.current(e); };
  double now = 0.0;
  int j = 0;
  auto push = [&](int i, double t) {
    const Event e{t, i, j++ % 1000, ref.counter[i], EventKind::sphere_sphere};
    queue.push(e);
    ref.events.push_back(e);
  };
  for (int i = 0; i < owners; ++i) push(i, unit(rng));
  int popped = 0;
  for (int step = 0; step < 60000; ++step) {
    const Event* top = queue.top(current);
    const Event* expected = ref.earliest();
    REQUIRE((top == nullptr) == (expected == nullptr));
    if (!top) break;
    REQUIRE(top->t_s == expected->t_s);
    REQUIRE(tie_key(*top) == tie_key(*expected));
    REQUIRE(top->t_s >= now);
    now = top->t_s;
    const int i = top->i;
    queue.pop();
    ++popped;
    ref.events.erase(std::find_if(ref.events.begin(), ref.events.end(), [&](const Event& e) {
      return e.t_s == expected->t_s && tie_key(e) == tie_key(*expected) && e.count_j == expected->count_j;
    }));
    // The owner's trajectory changes (all its events void) or not; a few new events,
    // at time scales that change every few thousand steps: bursts, gaps and plain gas.
    if (unit(rng) < 0.7) {
      ++ref.counter[i];
      queue.forget(i);
    }
    const int phase = (step / 3000) % 4;
    const double scale = phase == 0 ? 1e-20 : phase == 1 ? 1e-3 : phase == 2 ? 1.0 : 1e-9;
    const int fresh = 1 + static_cast<int>(3 * unit(rng));
    for (int k = 0; k < fresh; ++k) push(unit(rng) < 0.8 ? i : owner(rng), now + scale * unit(rng) * unit(rng));
    if (unit(rng) < 0.01) push(owner(rng), now + 1e3 * unit(rng));  // far beyond the calendar
    if (unit(rng) < 0.002) {  // everything void: as HardEngine::rebuild_predictions
      queue.clear();
      for (auto& c : ref.counter) ++c;
      for (int k = 0; k < owners; ++k) push(k, now + scale * unit(rng));
    }
    if (ref.events.size() > 20000) {
      std::erase_if(ref.events, [&](const Event& e) { return !ref.current(e); });
    }
  }
  CHECK(popped == 60000);
}

TEST_CASE("event queue: events come back whole, ties in tie_key order, the host's with i = -1") {
  // One owner's events at one instant, of every kind and with partners up to the largest
  // index, pushed in scrambled order; the lists keep them packed (kind and partner in one
  // word), and must hand back every field as pushed.
  constexpr int owners = 5;
  EventQueue queue(owners);
  std::vector<Event> pushed;
  const std::int32_t largest = EventQueue::max_particles;
  std::uint32_t count = 7;
  for (const EventKind kind : {EventKind::host_margin, EventKind::sphere_sphere, EventKind::cell_crossing,
                               EventKind::rider, EventKind::side_wall, EventKind::top_cap}) {
    for (const std::int32_t j : {largest, 0, 3}) pushed.push_back({1.0, 2, j, count++, kind});
  }
  pushed.push_back({1.0, -1, 1, count++, EventKind::bed_release});
  pushed.push_back({0.5, -1, 0, count++, EventKind::bed_release});
  for (const Event& e : pushed) queue.push(e);
  std::vector<Event> expected = pushed;
  std::sort(expected.begin(), expected.end(), earlier);
  const auto every = [](const Event&) { return true; };
  for (const Event& want : expected) {
    const Event* got = queue.top(every);
    REQUIRE(got != nullptr);
    CHECK(got->t_s == want.t_s);
    CHECK(got->i == want.i);
    CHECK(got->j == want.j);
    CHECK(got->count_j == want.count_j);
    CHECK(got->kind == want.kind);
    queue.pop();
  }
  CHECK(queue.top(every) == nullptr);
}

TEST_CASE("event queue: a list refilled since its owner changed is trusted only while nothing it depends on changes") {
  // As in the engine: a sphere event is current while its partner's counter is unchanged,
  // a cap event while its owner's host stamp is; a change of the owner's own trajectory
  // forgets its events. An out-of-date event may still reach the top (the engine drops
  // it there), but only if what it depends on changed after its owner was last re-keyed:
  // a re-key prunes the others, except in a fresh list (EventQueue::forget), which it
  // trusts. This interleaves changes and refills in every order: a list trusted beyond
  // what it may be hands out an event that changed before its re-key.
  constexpr int owners = 40;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> owner(0, owners - 1);
  EventQueue queue(owners);
  std::vector<std::uint32_t> counter(owners, 0), stamp(owners, 0);
  // When each counter and stamp last changed, and each owner was last re-keyed, on one clock.
  std::int64_t clock = 0;
  std::vector<std::int64_t> counter_changed(owners, 0), stamp_changed(owners, 0), rekeyed(owners, 0);
  std::vector<int> dirty;  // as the queue's: owners pushed to, forgotten or popped since the last top()
  std::vector<Event> events;
  const auto current = [&](const Event& e) {
    return e.kind == EventKind::sphere_sphere ? counter[e.j] == e.count_j : stamp[e.i] == e.count_j;
  };
  double now = 0.0;
  auto push = [&](int i) {
    const int j = owner(rng);
    const Event e = unit(rng) < 0.3 ? Event{now + unit(rng), i, 0, stamp[i], EventKind::top_cap}
                                    : Event{now + unit(rng), i, j, counter[j], EventKind::sphere_sphere};
    queue.push(e);
    events.push_back(e);
    dirty.push_back(i);
  };
  auto replace_stamp = [&](int i) {
    queue.host_stamp_changed(i);
    ++stamp[i];
    stamp_changed[i] = ++clock;
  };
  auto top = [&]() {
    const Event* e = queue.top(current);
    for (const int o : dirty) rekeyed[o] = clock;
    dirty.clear();
    return e;
  };
  for (int i = 0; i < owners; ++i) push(i);
  int popped = 0, stale_at_top = 0;
  for (int step = 0; step < 30000; ++step) {
    const Event* next = top();
    while (next && !current(*next)) {
      const std::int64_t changed =
          next->kind == EventKind::sphere_sphere ? counter_changed[next->j] : stamp_changed[next->i];
      REQUIRE(changed > rekeyed[next->i]);
      ++stale_at_top;
      dirty.push_back(next->i);
      queue.pop();
      next = top();
    }
    const Event* expected = nullptr;
    for (const Event& e : events) {
      if (current(e) && (!expected || earlier(e, *expected))) expected = &e;
    }
    REQUIRE((next == nullptr) == (expected == nullptr));
    if (!next) break;
    REQUIRE(next->t_s == expected->t_s);
    REQUIRE(tie_key(*next) == tie_key(*expected));
    now = next->t_s;
    const int i = next->i;
    queue.pop();
    dirty.push_back(i);
    ++popped;
    std::erase_if(events, [&](const Event& e) { return e.t_s == expected->t_s && tie_key(e) == tie_key(*expected); });
    // A handler: up to three owners change trajectory, each refilled at once or later,
    // with host stamps replaced and refills in between.
    std::vector<int> changed{i};
    for (int k = static_cast<int>(3 * unit(rng)); k > 0; --k) changed.push_back(owner(rng));
    for (const int c : changed) {
      ++counter[c];
      counter_changed[c] = ++clock;
      queue.forget(c);
      dirty.push_back(c);
      std::erase_if(events, [&](const Event& e) { return e.i == c; });
      if (unit(rng) < 0.5) push(c);
      if (unit(rng) < 0.2) replace_stamp(c);
    }
    for (const int c : changed) {
      for (int k = static_cast<int>(3 * unit(rng)); k >= 0; --k) push(c);
    }
    if (unit(rng) < 0.2) {  // a sphere elsewhere crosses into a new cell: more events for it
      const int c = owner(rng);
      if (unit(rng) < 0.5) replace_stamp(c);
      push(c);
    }
    std::erase_if(events, [&](const Event& e) { return !current(e); });
  }
  CHECK(popped == 30000);
  CHECK(stale_at_top > 1000);  // out-of-date events did reach the top, and were checked
}

TEST_CASE("event queue: an owner taken in from beyond the calendar while it scans empty buckets comes back") {
  // Four buckets. A run of pops sets their width w and restarts the calendar at the last
  // pop; then two owners wait beyond its reach, at 5.5 w and 7.5 w. The scan for the next
  // bucket takes the first in after two empty buckets and the second after four: both sit
  // further ahead than one calendar's length of empty buckets from where the scan began.
  EventQueue queue(3);
  const auto current = [](const Event&) { return true; };
  constexpr int pops = 4 + 64;  // as many as it takes the calendar to time its buckets
  for (int k = 1; k <= pops; ++k) {
    queue.push({1e-3 * k, 0, 0, 0, EventKind::side_wall});
    REQUIRE(queue.top(current) != nullptr);
    queue.pop();
  }
  const double origin_s = 1e-3 * pops, width_s = 4.0 * (origin_s - 1e-3) / pops;
  const Event first{origin_s + 5.5 * width_s, 1, 0, 0, EventKind::top_cap};
  const Event second{origin_s + 7.5 * width_s, 2, 0, 0, EventKind::top_cap};
  queue.push(second);
  queue.push(first);
  for (const Event& expected : {first, second}) {
    const Event* top = queue.top(current);
    REQUIRE(top != nullptr);
    CHECK(top->t_s == expected.t_s);
    CHECK(top->i == expected.i);
    queue.pop();
  }
  CHECK(queue.top(current) == nullptr);
}
