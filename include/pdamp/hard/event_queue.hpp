#pragma once
/// The hard-sphere engine's future: every predicted event, earliest first, in a
/// Boost.Heap d-ary heap. Events are never removed when a prediction goes out of date;
/// instead each carries the trajectory counters it was predicted with, and is dropped as
/// stale when it reaches the top and a counter has moved on (`HardEngine::is_current`).

#include <boost/heap/d_ary_heap.hpp>
#include <cstdint>

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
  std::int32_t i;          ///< the particle (unused for bed_release)
  std::int32_t j;          ///< the partner particle, or the crossed face
  std::uint32_t count_i;   ///< i's trajectory counter when predicted
  std::uint32_t count_j;   ///< j's counter (sphere_sphere), i's host stamp (caps, rider, host_margin) or the host epoch (bed_release)
  EventKind kind;
};

/// Min-heap on time; ties broken by kind and particles so the order never depends on
/// the heap's internals (determinism).
struct LaterEvent {
  bool operator()(const Event& a, const Event& b) const {
    if (a.t_s != b.t_s) return a.t_s > b.t_s;
    if (a.kind != b.kind) return a.kind > b.kind;
    if (a.i != b.i) return a.i > b.i;
    return a.j > b.j;
  }
};

using EventQueue = boost::heap::d_ary_heap<Event, boost::heap::arity<4>, boost::heap::compare<LaterEvent>>;

}  // namespace pdamp::hard
