#include "hard/jam_resolution.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>

#include "hard/collision_rules.hpp"

namespace pdamp::hard {

JamResolver::JamResolver(int particle_count)
    : count_(particle_count, 0), partners_(particle_count), hold_(particle_count, 0), in_cluster_(particle_count, 0) {}

bool JamResolver::note_collision(int i, int j, double t_s, std::uint8_t hold) {
  // The instant's first collision is only set aside, and entered in the spheres' records
  // when a second one comes at the same instant.
  if (t_s_ != t_s) {
    for (const int k : involved_) {
      count_[k] = 0;
      partners_[k].clear();
      hold_[k] = 0;
    }
    involved_.clear();
    t_s_ = t_s;
    first_ = {i, j, hold, true};
    return false;
  }
  if (first_.pending) {
    first_.pending = false;
    record_collision(first_.i, first_.j, first_.hold);
  }
  return record_collision(i, j, hold);
}

bool JamResolver::record_collision(int i, int j, std::uint8_t hold) {
  const auto count = [this](int k) {
    if (count_[k]++ == 0) involved_.push_back(k);
  };
  count(i);
  if (j < 0) {
    hold_[i] |= hold;
    return count_[i] > repeats;
  }
  count(j);
  std::vector<int>& of_i = partners_[i];
  if (std::find(of_i.begin(), of_i.end(), j) == of_i.end()) {
    of_i.push_back(j);
    partners_[j].push_back(i);
  }
  return count_[i] > repeats || count_[j] > repeats;
}

void JamResolver::merge_rigidly(const Cluster& cluster, PackedParticles& particles, HardLedger& ledger) const {
  // The loss is split as the contacts' relative motion was: its normal part is impact,
  // its sliding and rolling part friction.
  const std::vector<int>& members = cluster.members;
  ContactMotion motion;
  for (const int k : members) {
    for (const int j : partners_[k]) {
      if (j < k || !std::binary_search(members.begin(), members.end(), j)) continue;
      motion.add(k, j, particles);
    }
  }
  merge_into_rigid_body(members, motion.impact_share(), particles, ledger);
}

void ContactMotion::add(int k, int j, const PackedParticles& particles) {
  const Eigen::Vector3d n = (particles.position_m.col(j) - particles.position_m.col(k)).normalized();
  const Eigen::Vector3d u = particles.velocity_m_s.col(k) - particles.velocity_m_s.col(j) +
                            (particles.radius_m[k] * particles.angular_velocity_rad_s.col(k) +
                             particles.radius_m[j] * particles.angular_velocity_rad_s.col(j))
                                .cross(n);
  const double reduced = particles.mass_kg[k] * particles.mass_kg[j] / (particles.mass_kg[k] + particles.mass_kg[j]);
  normal_ += reduced * u.dot(n) * u.dot(n);
  total_ += reduced * u.squaredNorm();
}

void merge_into_rigid_body(std::span<const int> members, double impact_share, PackedParticles& particles,
                           HardLedger& ledger) {
  // A rigid motion flown ballistically never brings two of its spheres closer, so no
  // collision among them is left; the energy of the relative motion removed is the loss
  // (≥ 0: the rigid motion is the kinetic-energy projection of the old one).
  double mass = 0.0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), momentum = Eigen::Vector3d::Zero();
  for (const int k : members) {
    const double m = particles.mass_kg[k];
    mass += m;
    centre += m * particles.position_m.col(k);
    momentum += m * particles.velocity_m_s.col(k);
  }
  centre /= mass;
  const Eigen::Vector3d velocity = momentum / mass;
  Eigen::Vector3d angular_momentum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (const int k : members) {
    const double m = particles.mass_kg[k], moment = particles.moment_of_inertia(k);
    const Eigen::Vector3d r = particles.position_m.col(k) - centre;
    angular_momentum +=
        m * r.cross(particles.velocity_m_s.col(k) - velocity) + moment * particles.angular_velocity_rad_s.col(k);
    inertia += (moment + m * r.squaredNorm()) * Eigen::Matrix3d::Identity() - m * r * r.transpose();
  }
  const Eigen::Vector3d spin = inertia.llt().solve(angular_momentum);
  double loss = 0.0;
  for (const int k : members) {
    // Each sphere's part of the loss is the energy of its own motion removed.
    const Eigen::Vector3d v = velocity + spin.cross(particles.position_m.col(k) - centre);
    const double sphere_loss =
        0.5 * particles.mass_kg[k] * (particles.velocity_m_s.col(k) - v).squaredNorm() +
        0.5 * particles.moment_of_inertia(k) * (particles.angular_velocity_rad_s.col(k) - spin).squaredNorm();
    loss += sphere_loss;
    ledger.book_sphere(k, impact_share * sphere_loss, (1.0 - impact_share) * sphere_loss);
    particles.velocity_m_s.col(k) = v;
    particles.angular_velocity_rad_s.col(k) = spin;
  }
  ledger.impact_J += impact_share * loss;
  ledger.friction_J += (1.0 - impact_share) * loss;
}

VerticalSticking JamResolver::stick_to_host(const Cluster& cluster, const HostState& host, bool prescribed,
                                            double carried_mass_kg, PackedParticles& particles,
                                            HardLedger& ledger) const {
  const std::vector<int>& members = cluster.members;
  double mass = 0.0;
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();
  for (const int k : members) {
    mass += particles.mass_kg[k];
    momentum += particles.mass_kg[k] * particles.velocity_m_s.col(k);
  }
  const Eigen::Vector3d velocity = momentum / mass;
  double spin_J = 0.0;
  for (const int k : members) {
    spin_J += 0.5 * particles.mass_kg[k] * (particles.velocity_m_s.col(k) - velocity).squaredNorm() +
              0.5 * particles.moment_of_inertia(k) * particles.angular_velocity_rad_s.col(k).squaredNorm();
  }
  const double horizontal_J = 0.5 * mass * velocity.head<2>().squaredNorm();
  const VerticalSticking vertical = stick_vertically(mass, velocity.z(), host.v_m_s, prescribed, carried_mass_kg);
  if (prescribed) ledger.excitation_J += vertical.host_work_J;
  const bool side = cluster.hold & held_by_side_wall, cap = cluster.hold & held_by_cap_or_bed;
  ledger.impact_J += (side ? horizontal_J : 0.0) + (cap ? vertical.loss_J : 0.0);
  ledger.friction_J += spin_J + (side ? 0.0 : horizontal_J) + (cap ? 0.0 : vertical.loss_J);
  for (const int k : members) {
    // Each sphere's part: its own spin and motion relative to the body, and its mass's
    // share of the body's.
    const double m = particles.mass_kg[k], share = m / mass;
    const double sphere_spin_J =
        0.5 * m * (particles.velocity_m_s.col(k) - velocity).squaredNorm() +
        0.5 * particles.moment_of_inertia(k) * particles.angular_velocity_rad_s.col(k).squaredNorm();
    ledger.book_sphere(k, share * ((side ? horizontal_J : 0.0) + (cap ? vertical.loss_J : 0.0)),
                       sphere_spin_J + share * ((side ? 0.0 : horizontal_J) + (cap ? 0.0 : vertical.loss_J)));
    particles.velocity_m_s.col(k) = vertical.host_v_m_s * Eigen::Vector3d::UnitZ();
    particles.angular_velocity_rad_s.col(k).setZero();
  }
  return vertical;
}

}  // namespace pdamp::hard
