#pragma once
/// The interface both engines implement. A scenario and an initial particle state go in;
/// the same observations, state snapshots and statistics come out of either engine.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pdamp/errors.hpp"
#include "pdamp/model/checkpoint.hpp"
#include "pdamp/model/state.hpp"

namespace pdamp {

/// Named totals an engine keeps (events by type, neighbour-list rebuilds, ...), stored
/// with the run in the `run_statistics` table.
using EngineStatistics = std::vector<std::pair<std::string, std::int64_t>>;

class Engine {
 public:
  virtual ~Engine() = default;
  Engine() = default;
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  /// Simulates up to `t_s` and stops exactly there.
  virtual void advance_to(double t_s) = 0;
  virtual Observation observe() const = 0;
  virtual State state() const = 0;
  /// Each sphere's share of the ledger's impact and friction losses so far (with state(),
  /// what a picture of the bed shows).
  virtual SphereDissipation dissipation_by_sphere() const = 0;
  /// The time step the engine uses (s), or 0 for an event-driven engine.
  virtual double time_step_s() const = 0;
  virtual EngineStatistics statistics() const { return {}; }
  /// Things the user should know about the run (e.g. contacts overlapping more than the
  /// model is good for); printed on stderr and kept in the run's message.
  virtual std::vector<std::string> warnings() const { return {}; }

  /// Writes the engine's complete state verbatim (docs/checkpoints.md): everything
  /// advance_to reads, so that an engine restored from it continues with the same bits.
  /// Const: saving never changes the run.
  virtual void save(CheckpointWriter& out) const = 0;
  /// Takes the state `save` wrote, into an engine built for the same run (the same
  /// scenario, bed and settings: make_engine's arguments); restore_engine does both.
  /// Throws RuntimeFailure if the checkpoint does not fit this engine.
  virtual void restore(CheckpointReader& in) = 0;

  /// The flag advance_to looks at as it goes (every step, or every few thousand events):
  /// a stop request (SIGINT, SIGTERM) reaches the engines' inner loops through it. Once it
  /// is true, advance_to goes on for at most `grace` of wall time, so that a run loop
  /// that checkpoints at its observations gets to the next one and the run resumes from
  /// where it stopped; past the grace advance_to throws Interrupted, and the engine's
  /// state is not to be used.
  void set_stop_request(const std::atomic<bool>* stop, std::chrono::milliseconds grace = {}) {
    stop_ = stop;
    stop_grace_ = grace;
    stop_seen_.reset();
  }

 protected:
  void throw_if_stop_requested() const {
    if (stop_ && stop_->load(std::memory_order_relaxed)) [[unlikely]]
      stop_requested();
  }

 private:
  void stop_requested() const {
    const auto now = std::chrono::steady_clock::now();
    if (!stop_seen_) stop_seen_ = now;
    if (now - *stop_seen_ >= stop_grace_) throw Interrupted("stopped by a signal");
  }

  const std::atomic<bool>* stop_ = nullptr;
  std::chrono::milliseconds stop_grace_{0};
  mutable std::optional<std::chrono::steady_clock::time_point> stop_seen_;
};

}  // namespace pdamp
