#include "hard/free_flight.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <tuple>

namespace pdamp::hard {

namespace {

/// Cells a little wider than the largest sphere, so that round-off at a face can never
/// hide a contact between spheres two cells apart.
constexpr double cell_margin = 1.0 + 1e-6;
/// Root finders stop this close to contact, relative to the smallest radius.
constexpr double relative_contact_tolerance = 1e-10;

/// Whether `bytes` of randomly read data outgrow half of this processor's L2 cache (1 MB
/// if the system does not say).
bool outgrows_l2_cache(std::size_t bytes) {
  const long l2_bytes = sysconf(_SC_LEVEL2_CACHE_SIZE);
  return bytes > static_cast<std::size_t>(l2_bytes > 0 ? l2_bytes : 1L << 20) / 2;
}

}  // namespace

FreeFlight::FreeFlight(const Scenario& scenario, const Particles& initial)
    : gravity_m_s2_(scenario.gravity_m_s2),
      cavity_(scenario.cavity),
      particles_(initial),
      sphere_(initial.size()),
      trajectory_counter_(initial.size(), 0),
      grid_(scenario.cavity.radius_m(), scenario.cavity.height_m, 2.0 * initial.max_radius_m() * cell_margin),
      free_cells_(grid_.cell_count() + 1, static_cast<int>(initial.size())),  // + around's empty stand-in
      queue_(static_cast<int>(initial.size())),
      neighbours_(initial.size() + std::max(CellMembers::copy_width, screen_width)),
      screen_result_(static_cast<int>(initial.size())),
      contact_tolerance_m_(relative_contact_tolerance * initial.radius_m.minCoeff()),
      max_radius_m_(initial.max_radius_m()),
      prefetch_records_(outgrows_l2_cache(static_cast<std::size_t>(initial.size()) * sizeof(FlightRecord))),
      prefetch_cells_(outgrows_l2_cache(free_cells_.cells_bytes())) {}

void FreeFlight::start(const Particles& spheres) {
  particles_.assign(spheres);
  for (int i = 0; i < size(); ++i) enter_cell(i, grid_.coord_of(particles_.position_m.col(i)));
}

FreeFlight::Layer FreeFlight::cross_face(int i, Face face) {
  CellCoord c = sphere_[i].cell;
  const int step = face % 2 == 1 ? 1 : -1;
  switch (face / 2) {
    case 0:
      c.ix += step;
      break;
    case 1:
      c.iy += step;
      break;
    default:
      c.iz += step;
      break;
  }
  free_cells_.remove(i);
  enter_cell(i, c);
  const Around cells = around(i);
  constexpr std::array<int, 3> stride{1, 3, 9};  // in Around, of x, y and z
  const int axis = face / 2, beyond = (face % 2 == 1 ? 2 : 0) * stride[axis];
  const int u_stride = stride[(axis + 1) % 3], w_stride = stride[(axis + 2) % 3];
  Layer entered{};
  for (int u = 0; u < 3; ++u) {
    for (int w = 0; w < 3; ++w) entered[3 * u + w] = cells[beyond + u * u_stride + w * w_stride];
  }
  return entered;
}

}  // namespace pdamp::hard
