/// The hard engine's event queue against a brute-force reference: whatever the time
/// scales (bursts of events a femtosecond apart, then gaps of seconds), it hands out the
/// earliest current event every time.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "pdamp/hard/event_queue.hpp"

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
