#pragma once
/// The interface both engines implement. A scenario (and an initial particle state)
/// goes in; observations and state snapshots come out.

#include <memory>
#include <string_view>

#include "pdamp/model/state.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

enum class Model { soft, hard };

std::string_view to_string(Model model);
/// Throws InputError for anything but "soft" or "hard".
Model parse_model(std::string_view text);

class Engine {
 public:
  virtual ~Engine() = default;
  Engine() = default;
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  /// Simulates up to `t_s` (never beyond it: the state at t_s is exact for the engine).
  virtual void advance_to(double t_s) = 0;
  virtual Observation observe() const = 0;
  virtual State state() const = 0;
  /// The time step the engine uses (s), or 0 for an event-driven engine.
  virtual double time_step_s() const = 0;
};

/// The engine of `model` for the scenario, starting from `initial` (a placement or a
/// settled bed) with the host in its initial condition. A scenario without particles
/// runs the host alone on its exact solution, whatever the model.
std::unique_ptr<Engine> make_engine(Model model, const Scenario& scenario, const Particles& initial);

}  // namespace pdamp
