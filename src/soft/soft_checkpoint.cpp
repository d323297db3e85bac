/// The soft engine's checkpoint (docs/checkpoints.md): its state verbatim, so that a
/// restored engine takes the same steps with the same bits. The neighbour list and the
/// contact tables are kept as they stand, not rebuilt: the spheres' order, the pairs'
/// order and the rebuild schedule decide the order of every sum.
///
/// Left out, as no step reads them before writing them: the reactions and chunk totals
/// of the last force computation (spent within it), the rebuild's scratch (kept
/// contacts, the spare contact tables, the release order) and the threads' scratch.
#include <span>

#include "soft/soft_engine_class.hpp"

namespace pdamp::soft {
namespace {

/// A padded per-sphere array as its doubles (`per_sphere` of them a sphere).
template <class Array>
auto doubles(Array& field, int per_sphere) {
  return std::span(field.data(), static_cast<std::size_t>(per_sphere * (field.size() + SphereScalars::padding)));
}

}  // namespace

template <class Self, class Archive>
void ContactTable::transfer(Self& table, Archive& a) {
  a.io(table.entries_);
  a.io(table.free_);
}
template void ContactTable::transfer(const ContactTable&, CheckpointWriter&);
template void ContactTable::transfer(ContactTable&, CheckpointReader&);

template <class Self, class Archive>
void NeighbourList::transfer(Self& list, Archive& a) {
  a.section("neighbour list");
  a.io(list.cell_first_);
  a.io(list.order_);
  a.io(list.first_);
  a.io(list.pairs_);
  a.io(list.contact_);
  a.io(list.rebuilds_);
}
template void NeighbourList::transfer(const NeighbourList&, CheckpointWriter&);
template void NeighbourList::transfer(NeighbourList&, CheckpointReader&);

template <class Self, class Archive>
void SoftEngine::transfer(Self& e, Archive& a) {
  a.section("soft engine");
  a.io(e.t_s_);
  a.io(e.end_of_advance_s_);
  a.section("spheres");
  a.io(doubles(e.balls_, 4), "the spheres' positions");
  a.io(doubles(e.v_, 4), "the spheres' velocities");
  a.io(doubles(e.w_, 4), "the spheres' spins");
  for (auto* vectors : {&e.force_, &e.torque_, &e.x_at_rebuild_}) {
    for (auto* component : {&vectors->x, &vectors->y, &vectors->z}) a.io(doubles(*component, 1), "a sphere vector");
  }
  for (auto* scalars : {&e.mass_, &e.impact_J_, &e.friction_J_}) a.io(doubles(*scalars, 1), "a sphere number");
  a.io(std::span(e.original_index_), "the spheres' order");
  a.part(e.neighbours_);
  a.section("contacts");
  for (auto& table : e.contact_tables_) a.part(table);
  for (auto& at_wall : e.wall_contacts_) a.io(std::span(at_wall), "the wall contacts");
  a.io(e.most_pairs_in_a_chunk_);
  a.io(std::span(e.farthest_partner_), "the chunks' farthest partners");
  a.io(e.needs_rebuild_);
  a.io(e.host_z_at_rebuild_);
  a.section("host and books");
  a.io(e.host_);
  a.io(e.host_particle_force_N_);
  a.io(e.host_other_force_N_);
  a.io(e.previous_host_forces_);
  a.io(e.host_load_);
  a.io(e.ledger_);
  a.io(e.contact_elastic_J_);
  a.io(e.steps_);
  a.io(e.contacts_);
  a.io(e.max_overlap_ratio_);
  a.io(e.max_overlap_time_s_);
}

void SoftEngine::save(CheckpointWriter& out) const {
  out.put(dt_s_);
  transfer(*this, out);
}

void SoftEngine::restore(CheckpointReader& in) {
  in.expect(dt_s_, "the time step");
  transfer(*this, in);
}

}  // namespace pdamp::soft
