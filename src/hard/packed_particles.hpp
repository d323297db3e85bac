#pragma once
/// The hard engine's spheres, laid out for prediction. Every prediction reads, for each
/// of ~15 neighbours, its position and velocity, the time they refer to and its radius:
/// those live together in one 64-byte record per sphere, so a neighbour costs one cache
/// line, not four. Strided Eigen maps over the records give the same names and
/// interface as Particles.

#include <Eigen/Core>
#include <vector>

#include "pdamp/model/particles.hpp"

namespace pdamp::hard {

/// One sphere's free flight: position and velocity at time t_ref, and its radius.
struct alignas(64) FlightRecord {
  double x_m, y_m, z_m, t_ref_s;
  double vx_m_s, vy_m_s, vz_m_s, radius_m;
};

class PackedParticles {
  static constexpr int record_doubles = sizeof(FlightRecord) / sizeof(double);
  using Columns = Eigen::Map<Eigen::Matrix3Xd, Eigen::Unaligned, Eigen::OuterStride<record_doubles>>;
  using Field = Eigen::Map<Eigen::VectorXd, Eigen::Unaligned, Eigen::InnerStride<record_doubles>>;

 public:
  explicit PackedParticles(const Particles& particles)
      : records_(static_cast<std::size_t>(particles.size())),
        position_m(&records_.data()->x_m, 3, particles.size()),
        velocity_m_s(&records_.data()->vx_m_s, 3, particles.size()),
        radius_m(&records_.data()->radius_m, particles.size()),
        t_ref_s(&records_.data()->t_ref_s, particles.size()) {
    assign(particles);
  }
  // The maps point into this object's own records.
  PackedParticles(const PackedParticles&) = delete;
  PackedParticles& operator=(const PackedParticles&) = delete;

  /// Takes over every field of `particles` (same size); every t_ref becomes 0.
  void assign(const Particles& particles) {
    position_m = particles.position_m;
    velocity_m_s = particles.velocity_m_s;
    radius_m = particles.radius_m;
    t_ref_s.setZero();
    angular_velocity_rad_s = particles.angular_velocity_rad_s;
    mass_kg = particles.mass_kg;
  }
  Particles unpacked() const {
    Particles p(size());
    p.position_m = position_m;
    p.velocity_m_s = velocity_m_s;
    p.angular_velocity_rad_s = angular_velocity_rad_s;
    p.radius_m = radius_m;
    p.mass_kg = mass_kg;
    return p;
  }

  Eigen::Index size() const { return static_cast<Eigen::Index>(records_.size()); }
  double moment_of_inertia(Eigen::Index i) const { return 0.4 * mass_kg[i] * radius_m[i] * radius_m[i]; }
  const FlightRecord& record(int i) const { return records_[static_cast<std::size_t>(i)]; }

  /// Its state verbatim (hard_checkpoint.cpp).
  void save(CheckpointWriter& out) const { transfer(*this, out); }
  void restore(CheckpointReader& in) { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);
  std::vector<FlightRecord> records_;

 public:
  Columns position_m;
  Columns velocity_m_s;
  Field radius_m;
  Field t_ref_s;  ///< the time each free sphere's position and velocity refer to
  Eigen::Matrix3Xd angular_velocity_rad_s;
  Eigen::VectorXd mass_kg;
};

}  // namespace pdamp::hard
