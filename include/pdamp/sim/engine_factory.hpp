#pragma once
/// Chooses the engine for a model name.

#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "pdamp/model/engine.hpp"
#include "pdamp/model/restitution.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

enum class Model { soft, hard };

/// One engine in the table of engines (engine_kinds()), the one place that names them:
/// its model name, what it is, the scenario sections it reads beyond the shared ones,
/// what `pdamp check` says of it for a scenario, and its factory.
struct EngineKind {
  Model model;
  std::string_view name;         ///< --model
  std::string_view description;  ///< in words, for --model's help and errors
  std::string_view scenario_sections;
  /// What `pdamp check` prints of the engine for a scenario with spheres (e.g. its step).
  std::string (*describe)(const Scenario& scenario);
  std::unique_ptr<Engine> (*make)(const Scenario& scenario, const Particles& initial,
                                  const RestitutionTable* calibration, bool diagnose_events);
};

/// Every engine, soft first.
std::span<const EngineKind> engine_kinds();
const EngineKind& engine_kind(Model model);

std::string_view to_string(Model model);
/// Throws InputError for a name not in engine_kinds(), naming the valid ones.
Model parse_model(std::string_view text);

/// --simd: the instruction set of the engines' kernels, "sse2", "avx2" or "avx512", for
/// this process (the soft engine's passes; the hard engine's neighbour screen takes the
/// widest the CPU runs, with the same bits). Throws InputError naming `option` for a set
/// this build or CPU cannot run.
void set_instruction_set(std::string_view text, std::string_view option);

/// Checks that `model` can run the scenario (the soft engine's time
/// step, the run's budget: run_budget.hpp), before any work is done. Throws InputError
/// naming the offending key.
void check_model_can_run(Model model, const Scenario& scenario);

/// The engine of `model` for the scenario, starting from `initial` (a placement or a
/// settled bed) with the host in its initial condition. A scenario without particles
/// runs the host alone on its exact solution, whatever the model. The hard model takes
/// `calibration` when the scenario asks for calibrated restitution, and counts where its
/// collisions come from if asked to (`diagnose_events`, HardEngine::diagnose_events).
/// Throws InputError for a scenario the engine cannot run.
std::unique_ptr<Engine> make_engine(Model model, const Scenario& scenario, const Particles& initial,
                                    const RestitutionTable* calibration = nullptr, bool diagnose_events = false);

/// The engine of a run restored from its checkpoint: built as make_engine built the run's
/// (the same arguments), then given the state saved in `checkpoint` (after the run loop's
/// part, read_run_loop_state), which must then be read to its end. Throws RuntimeFailure
/// if the checkpoint does not fit the engine.
std::unique_ptr<Engine> restore_engine(Model model, const Scenario& scenario, const Particles& initial,
                                       const RestitutionTable* calibration, bool diagnose_events,
                                       CheckpointReader& checkpoint);

}  // namespace pdamp
