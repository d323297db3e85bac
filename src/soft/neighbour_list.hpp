#pragma once
/// Verlet neighbour list with a skin, built on the shared cell grid. Every pair closer
/// than r_i + r_j + skin is listed (half list: i < j), so no contact
/// can be missed until some sphere has moved more than skin/2 relative to the host since
/// the build — the engine rebuilds before that.
///
/// Before each build the spheres are put in cell order (sort_by_cell), so that a sphere's
/// partners lie near it in memory: cells are ranked along x fastest, then z, then y, and
/// each row of cells along x holds a run of consecutive spheres. A sphere's partners of
/// higher index are then in five runs: the rest of its own row from itself on, and the
/// rows after its own among the eight around it.
///
/// The spheres are taken in groups of 64 (the engine's chunks), and a listed pair keeps
/// its partner and its owner's place in the owner's group in one int (partner × 64 +
/// place). Each listed pair carries the index of its open contact in the owner's
/// ContactTable (ContactTable::none if it has none), which the engine hands over from one
/// build to the next.

#include <algorithm>
#include <cstddef>
#include <vector>

#include "pdamp/model/cell_grid.hpp"
#include "simd/lanes.hpp"
#include "soft/contact_table.hpp"
#include "soft/sphere_arrays.hpp"

namespace pdamp::soft {

// The kernels are written over the lanes both engines share.
using namespace simd;

class NeighbourList {
 public:
  /// The pair arrays run this far past the last pair (with valid sphere indices and no
  /// contact), so that SIMD lanes may read a whole register's worth from any pair.
  static constexpr int padding = 8;
  static constexpr int group_bits = 6, group_size = 1 << group_bits;
  /// The most spheres a list can hold (its partners fit with their owners' places in an int).
  static constexpr int max_spheres = (1 << (31 - group_bits)) - 1;

  NeighbourList(const CellGrid& grid, double skin_m);

  double skin_m() const { return skin_m_; }

  /// The spheres' order by cell at `positions`: order[new index] = current index
  /// (a stable sort: spheres in one cell keep their order).
  const std::vector<int>& sort_by_cell(const SphereBalls& balls);
  /// Lists the pairs within reach, in `parts` parts (of about as many spheres) that may be
  /// built side by side: start_build, build_part for each part, finish_build. The spheres
  /// must be in the order sort_by_cell gave. Every pair starts without a contact.
  void start_build(int parts);
  /// Real: see lanes.hpp (the engine runs this in its instruction set).
  template <class Real>
  void build_part(int part, const SphereBalls& balls);
  void finish_build();

  int size() const { return static_cast<int>(pairs_.size()) - padding; }
  /// Pairs of sphere i are [first(i), first(i + 1)).
  int first(int i) const { return first_[i]; }
  /// Pair k's owner, given the first sphere of its owner's group; and its partner.
  int owner(int k, int group_first) const { return owner_of(pairs_[k], group_first); }
  int partner(int k) const { return partner_of(pairs_[k]); }
  /// The pairs as they are kept, one int each, and how to read one.
  const int* pairs() const { return pairs_.data(); }
  static int owner_of(int pair, int group_first) { return group_first + (pair & (group_size - 1)); }
  static int partner_of(int pair) { return pair >> group_bits; }
  /// The open contact of pair k, or ContactTable::none.
  int& contact(int k) { return contact_[k]; }
  int contact(int k) const { return contact_[k]; }
  const int* contacts() const { return contact_.data(); }
  long long rebuilds() const { return rebuilds_; }

  /// The pairs, their contacts and the cells' spheres as they stand (soft_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  int rank(int ix, int iy, int iz) const { return (iy * grid_.nz() + iz) * grid_.nx() + ix; }
  int rank_of(double x, double y, double z) const;
  /// Appends to out[count...] the spheres j of [begin, end) within reach of sphere i.
  template <class Real>
  [[gnu::always_inline]] inline void list_partners(int i, int begin, int end, const SphereBalls& balls,
                                                   std::vector<int>& out, int& count);

  CellGrid grid_;
  double skin_m_;
  std::vector<int> cell_first_;  ///< spheres of the cell ranked r: [cell_first_[r], cell_first_[r + 1])
  std::vector<int> order_;
  std::vector<int> first_, pairs_, contact_;
  /// During a build: the cells of each part, [part_cell_[p], part_cell_[p + 1]) by rank;
  /// the partners each part lists (part 0's in pairs_, those of part p in more_partners_[p − 1]).
  std::vector<int> part_cell_, part_pairs_;
  std::vector<std::vector<int>> more_partners_;
  long long rebuilds_ = 0;
};

template <class Real>
void NeighbourList::list_partners(int i, int begin, int end, const SphereBalls& balls, std::vector<int>& out,
                                  int& count) {
  constexpr int lanes = lane_count<Real>;
  // Room for every candidate and a register's worth more; grown by a quarter, not
  // doubled: the list is much of the engine's memory.
  const std::size_t room = count + (end - begin) + lanes;
  if (out.size() < room) out.resize(std::max(room, out.size() + out.size() / 4));
  const Ball& ball = balls[i];
  // Registers may read past `end` (the balls are padded); those lanes are not counted.
  for (int j = begin; j < end; j += lanes) {
    const Fields4<Real> other = load_records<Real>([&](int l) { return balls.data() + std::ptrdiff_t{4} * (j + l); });
    const Real dx = ball.x - other.a, dy = ball.y - other.b, dz = ball.z - other.c;
    const Real reach = ball.radius + other.d + skin_m_;
    unsigned within = lane_bits(dx * dx + dy * dy + dz * dz < reach * reach);
    if (end - j < lanes) within &= (1u << (end - j)) - 1;
    append_lanes<Real>(j, within, out.data(), count);
  }
}

template <class Real>
void NeighbourList::build_part(int part, const SphereBalls& balls) {
  const int nx = grid_.nx(), ny = grid_.ny(), nz = grid_.nz();
  std::vector<int>& out = part == 0 ? pairs_ : more_partners_[part - 1];
  int pairs = 0;
  // The cells in rank order, so that their spheres come in index order.
  for (int cell = part_cell_[part]; cell < part_cell_[part + 1]; ++cell) {
    if (cell_first_[cell] == cell_first_[cell + 1]) continue;
    const int ix = cell % nx, iz = cell / nx % nz, iy = cell / (nx * nz);
    const int row_west = std::max(ix - 1, 0), row_east = std::min(ix + 1, nx - 1);
    // The runs of later rows: [run_begin[r], run_end[r]); five at most, where both
    // neighbouring layers wrap round to later rows.
    int run_begin[5], run_end[5], runs = 0;
    auto add_row = [&](int row_y, int row_z) {
      run_begin[runs] = cell_first_[rank(row_west, row_y, row_z)];
      run_end[runs] = cell_first_[rank(row_east, row_y, row_z) + 1];
      ++runs;
    };
    for (const int dz : {-1, 1}) {
      const int row_z = (iz + dz + nz) % nz;
      if (row_z > iz) add_row(iy, row_z);
    }
    if (iy + 1 < ny) {
      for (const int dz : {-1, 0, 1}) add_row(iy + 1, (iz + dz + nz) % nz);
    }
    const int own_row_end = cell_first_[rank(row_east, iy, iz) + 1];
    for (int i = cell_first_[cell]; i < cell_first_[cell + 1]; ++i) {
      first_[i] = pairs;  // within the part, until finish_build
      list_partners<Real>(i, i + 1, own_row_end, balls, out, pairs);
      for (int r = 0; r < runs; ++r) list_partners<Real>(i, run_begin[r], run_end[r], balls, out, pairs);
    }
  }
  part_pairs_[part] = pairs;
}

}  // namespace pdamp::soft
