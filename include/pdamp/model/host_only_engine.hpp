#pragma once
/// The host without particles, advanced on its exact solution. Both models run it when
/// a scenario has no particles; it is the reference the engines' host coupling is
/// tested against.

#include "pdamp/model/engine.hpp"
#include "pdamp/model/host.hpp"

namespace pdamp {

class HostOnlyEngine final : public Engine {
 public:
  explicit HostOnlyEngine(const Scenario& scenario);

  void advance_to(double t_s) override;
  Observation observe() const override;
  State state() const override;
  SphereDissipation dissipation_by_sphere() const override { return {}; }
  double time_step_s() const override { return 0.0; }
  void save(CheckpointWriter& out) const override { transfer(*this, out); }
  void restore(CheckpointReader& in) override { transfer(*this, in); }

 private:
  template <class Self, class Archive>
  static void transfer(Self& self, Archive& archive);

  HostModel model_;
  HostTrajectory trajectory_;
  double t_s_ = 0.0;
  double viscous_J_ = 0.0;
  double excitation_J_ = 0.0;
  HostLoadBooks load_;
};

}  // namespace pdamp
