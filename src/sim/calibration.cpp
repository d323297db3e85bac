#include "pdamp/sim/calibration.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <numbers>

#include "pdamp/errors.hpp"
#include "pdamp/soft/soft_engine.hpp"
#include "pdamp/soft/time_step.hpp"

namespace pdamp {
namespace {

constexpr double slowest_impact_m_s = 1e-3;
constexpr double steps_per_contact = 200.0;
constexpr double steps_per_tangential_period = 40.0;
constexpr double sticking_fraction_of_mu = 0.05;

/// One isolated collision, integrated by the soft engine with the host held still.
class Collision {
 public:
  Collision(const Scenario& scenario, bool against_wall, double normal_speed_m_s, double tangential_speed_m_s)
      : wall_(against_wall), normal_speed_(normal_speed_m_s), tangential_speed_(tangential_speed_m_s) {
    const auto& p = scenario.particles;
    radius_ = 0.25 * (p.diameter_min_m + p.diameter_max_m);
    mass_ = p.density_kg_m3 * 4.0 / 3.0 * std::numbers::pi * radius_ * radius_ * radius_;
    const SoftContactLaw& law = against_wall ? scenario.soft_wall : scenario.soft_particle;
    const double effective_mass = against_wall ? mass_ : 0.5 * mass_;
    contact_time_s_ = hertz_contact_time_s(effective_mass, law.kn_N_m1_5, normal_speed_m_s);

    setting_ = scenario;
    setting_.gravity_m_s2.setZero();
    setting_.excitation = ExcitationSettings{};
    setting_.host.z0_m = setting_.host.v0_m_s = 0.0;
    setting_.cavity = {12.0 * radius_, 12.0 * radius_};  // nothing else within reach
    setting_.run.dt_s = std::min(contact_time_s_ / steps_per_contact,
                                 soft::shortest_tangential_period_s(setting_) / steps_per_tangential_period);
  }

  /// Runs the collision to its end and returns the contact point's velocity of the
  /// (first) sphere relative to the wall or the other sphere, and the contact normal.
  std::pair<Eigen::Vector3d, Eigen::Vector3d> outgoing() const {
    const double gap = 2.0 * normal_speed_ * *setting_.run.dt_s;
    const double mid = 0.5 * setting_.cavity.height_m;
    Particles p(wall_ ? 1 : 2);
    p.radius_m.setConstant(radius_);
    p.mass_kg.setConstant(mass_);
    if (wall_) {
      p.position_m.col(0) << 0.0, 0.0, radius_ + gap;
      p.velocity_m_s.col(0) << tangential_speed_, 0.0, -normal_speed_;
    } else {
      p.position_m.col(0) << -(radius_ + 0.5 * gap), 0.0, mid;
      p.position_m.col(1) << radius_ + 0.5 * gap, 0.0, mid;
      p.velocity_m_s.col(0) << 0.5 * normal_speed_, 0.5 * tangential_speed_, 0.0;
      p.velocity_m_s.col(1) = -p.velocity_m_s.col(0);
    }
    soft::SoftEngineOptions options;
    options.hold_host = true;
    const std::unique_ptr<Engine> engine = soft::make_soft_engine(setting_, p, options);
    const double dt = engine->time_step_s();
    bool touched = false;
    for (double t = dt; t < 50.0 * contact_time_s_ + 100.0 * dt; t += dt) {
      try {
        engine->advance_to(t);
      } catch (const RuntimeFailure& e) {
        // The soft law has no restitution to give at this speed (e.g. it cannot stop the impact).
        throw RuntimeFailure("calibrating the hard model's restitution from the soft law, an isolated " +
                             std::string(wall_ ? "sphere-wall" : "sphere-sphere") + " impact at " +
                             std::to_string(normal_speed_) + " m/s failed: " + e.what() +
                             "; use [hard] restitution = constant for this scenario");
      }
      const bool touching = engine->observe().counters.contacts.value_or(0) > 0;
      touched |= touching;
      if (touched && !touching) {
        const Particles out = engine->state().particles;
        if (wall_) {
          const Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
          return {out.velocity_m_s.col(0) - radius_ * out.angular_velocity_rad_s.col(0).cross(n), n};
        }
        const Eigen::Vector3d n = (out.position_m.col(0) - out.position_m.col(1)).normalized();
        const Eigen::Vector3d spin = radius_ * (out.angular_velocity_rad_s.col(0) + out.angular_velocity_rad_s.col(1));
        return {out.velocity_m_s.col(0) - out.velocity_m_s.col(1) - spin.cross(n), n};
      }
    }
    throw RuntimeFailure("calibration: an isolated soft collision at " + std::to_string(normal_speed_) +
                         " m/s did not end");
  }

 private:
  Scenario setting_;
  bool wall_;
  double normal_speed_, tangential_speed_;
  double radius_ = 0.0, mass_ = 0.0, contact_time_s_ = 0.0;
};

RestitutionCurve calibrate(const Scenario& scenario, bool against_wall, int speeds) {
  const SoftContactLaw& law = against_wall ? scenario.soft_wall : scenario.soft_particle;
  const double fastest = std::max(soft::max_impact_speed_m_s(scenario), 10.0 * slowest_impact_m_s);
  RestitutionCurve curve;
  for (int k = 0; k < speeds; ++k) {
    const double v = slowest_impact_m_s * std::pow(fastest / slowest_impact_m_s, k / (speeds - 1.0));
    const auto [head_on, n] = Collision(scenario, against_wall, v, 0.0).outgoing();
    const double tangential = sticking_fraction_of_mu * (law.mu > 0.0 ? law.mu : 1.0) * v;
    const auto [oblique, m] = Collision(scenario, against_wall, v, tangential).outgoing();
    const Eigen::Vector3d slip = oblique - oblique.dot(m) * m;
    const Eigen::Vector3d initial_direction = against_wall ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    curve.impact_speed_m_s.push_back(v);
    curve.en.push_back(head_on.dot(n) / v);
    curve.beta0.push_back(-slip.dot(initial_direction) / tangential);
  }
  return curve;
}

}  // namespace

RestitutionTable calibrate_restitution(const Scenario& scenario, int speeds) {
  return {calibrate(scenario, false, speeds), calibrate(scenario, true, speeds)};
}

}  // namespace pdamp
