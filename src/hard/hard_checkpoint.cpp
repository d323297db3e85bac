/// The hard engine's checkpoint (docs/checkpoints.md): its state verbatim, part by part,
/// so that a restored engine pops the same events in the same order and handles them with
/// the same bits. The event queue is kept as it stands, its owners' lists in their order
/// and its calendar and heaps as they are, not predicted anew: predictions made again
/// from the spheres' records round differently, and the queue's choice among events of
/// one instant follows its lists.
///
/// Left out, as nothing reads them before writing them: the prediction's scratch (the
/// neighbours and their screen), the riders an exact search saw; and what the engine
/// derives from the scenario and the bed (grid, cavity, laws, tolerances), which the
/// engine it is restored into has already.
#include <type_traits>

#include "hard/hard_engine_class.hpp"

namespace pdamp::hard {

/// Explicit instantiations of a part's transfer for the writer and the reader. `Part` names
/// a class (Part::transfer), which parentheses would not parse.
// NOLINTBEGIN(bugprone-macro-parentheses)
#define PDAMP_CHECKPOINT_PART(Part)                             \
  template void Part::transfer(const Part&, CheckpointWriter&); \
  template void Part::transfer(Part&, CheckpointReader&)
// NOLINTEND(bugprone-macro-parentheses)

template <class Self, class Archive>
void EventQueue::transfer(Self& q, Archive& a) {
  a.section("event queue");
  for (auto& list : q.lists_) a.io(list);
  a.io(q.top_);
  a.io(q.keyed_);
  a.io(q.links_);
  a.io(q.dirty_);
  a.io(q.fresh_filled_);
  a.io(q.buckets_);
  // A heap as its array: pushed back in that order, each entry stays where it was (none
  // comes before its parent), so the array is the same.
  for (auto* heap : {&q.current_, &q.beyond_}) {
    std::vector<Entry> entries;
    if constexpr (std::is_const_v<Self>) entries.assign(heap->begin(), heap->end());
    a.io(entries);
    if constexpr (!std::is_const_v<Self>) {
      heap->clear();
      for (const Entry& e : entries) heap->push(e);
    }
  }
  for (auto* value : {&q.origin_s_, &q.width_s_, &q.buckets_per_s_, &q.t_first_pop_s_, &q.t_last_pop_s_}) a.io(*value);
  a.io(q.current_bucket_);
  a.io(q.pops_);
}
PDAMP_CHECKPOINT_PART(EventQueue);

template <class Self, class Archive>
void CellMembers::transfer(Self& c, Archive& a) {
  a.io(c.cells_);
  a.io(c.overflow_);
  a.io(c.next_);
  a.io(c.prev_);
  a.io(c.cell_);
}
PDAMP_CHECKPOINT_PART(CellMembers);

template <class Self, class Archive>
void ParticleSet::transfer(Self& set, Archive& a) {
  a.io(set.state_);
  a.io(set.list_);
  a.io(set.sweeping_);
}
PDAMP_CHECKPOINT_PART(ParticleSet);

template <class Self, class Archive>
void PackedParticles::transfer(Self& p, Archive& a) {
  a.io(std::span(p.records_), "the spheres' flights");
  a.io(p.angular_velocity_rad_s);
  a.io(p.mass_kg);
}
PDAMP_CHECKPOINT_PART(PackedParticles);

template <class Self, class Archive>
void FreeFlight::transfer(Self& f, Archive& a) {
  a.section("free flight");
  a.part(f.particles_);
  a.io(std::span(f.sphere_), "the spheres' states");
  a.io(std::span(f.trajectory_counter_), "the trajectory counters");
  a.part(f.free_cells_);
  a.part(f.queue_);
}
PDAMP_CHECKPOINT_PART(FreeFlight);

template <class Self, class Archive>
void HostCoupling::transfer(Self& h, Archive& a) {
  a.section("host coupling");
  a.part(h.trajectory_);
  a.io(h.epoch_);
  a.io(h.now_);
  for (auto* value : {&h.speed_envelope_m_s_, &h.trajectory_riding_mass_kg_, &h.riding_mass_kg_, &h.bed_depth_bound_m_})
    a.io(*value);
  a.io(h.riding_count_);
  a.io(h.bed_side_);
  a.part(h.rider_cells_);
  for (auto& tier : h.tiers_) {
    a.part(tier.members);
    for (auto* value : {&tier.margin_m, &tier.horizon_s, &tier.budget_m, &tier.t_last_sweep_s}) a.io(*value);
  }
  a.part(h.touching_);
  a.io(std::span(h.touching_bound_), "the touching bounds");
  a.io(std::span(h.searched_), "the search boxes");
}
PDAMP_CHECKPOINT_PART(HostCoupling);

template <class Self, class Archive>
void JamResolver::transfer(Self& j, Archive& a) {
  a.section("jams");
  a.io(j.t_s_);
  a.io(j.count_);
  for (auto& partners : j.partners_) a.io(partners);
  a.io(j.hold_);
  a.io(j.involved_);
  a.io(j.first_);
  a.io(j.in_cluster_);
}
PDAMP_CHECKPOINT_PART(JamResolver);

template <class Self, class Archive>
void RigidClusters::transfer(Self& c, Archive& a) {
  a.section("rigid clusters");
  a.io(c.cluster_);
  a.io(c.place_);
  // The clusters' count first: the engine restored into has none yet.
  auto clusters = static_cast<std::uint64_t>(c.members_.size());
  a.io(clusters);
  if constexpr (!std::is_const_v<Self>) c.members_.resize(clusters);
  for (auto& members : c.members_) a.io(members);
  a.io(c.unused_);
  for (auto* count : {&c.joins_, &c.joined_spheres_, &c.departures_}) a.io(*count);
}
PDAMP_CHECKPOINT_PART(RigidClusters);

template <class Self, class Archive>
void HardLedger::transfer(Self& l, Archive& a) {
  a.section("hard ledger");
  for (auto* value : {&l.impact_J, &l.friction_J, &l.viscous_J, &l.excitation_J, &l.t_host_booked_s_}) a.io(*value);
  a.io(l.by_sphere.impact_J);
  a.io(l.by_sphere.friction_J);
  a.io(l.load);
  a.io(l.counts);
}
PDAMP_CHECKPOINT_PART(HardLedger);

template <class Self, class Archive>
void EventDiagnosis::transfer(Self& d, Archive& a) {
  a.io(d.sphere_kn_N_m1_5_);
  a.io(d.wall_kn_N_m1_5_);
  a.io(d.counts_);
}
PDAMP_CHECKPOINT_PART(EventDiagnosis);

template <class Self, class Archive>
void HardEngine::transfer(Self& e, Archive& a) {
  a.section("hard engine");
  a.part(e.flight_);
  a.part(e.books_);
  a.part(e.host_);
  a.part(e.jams_);
  // Only where they are on, so that a run without them keeps its checkpoint's layout.
  if (e.clusters_.enabled()) a.part(e.clusters_);
  a.io(e.t_s_);
  a.io(e.events_at_this_instant_);
  a.io(e.events_);
  a.io(e.next_poll_);
  if (e.diagnosis_) a.part(*e.diagnosis_);
}

void HardEngine::save(CheckpointWriter& out) const {
  out.put(static_cast<std::uint8_t>(diagnosis_ != nullptr));
  transfer(*this, out);
}

void HardEngine::restore(CheckpointReader& in) {
  // A run that counted where its collisions come from goes on counting them.
  if (in.get<std::uint8_t>() != 0) {
    if (!diagnosis_) diagnosis_ = std::make_unique<EventDiagnosis>(0.0, 0.0);  // its stiffnesses restored below
  } else {
    diagnosis_.reset();
  }
  transfer(*this, in);
}

}  // namespace pdamp::hard
