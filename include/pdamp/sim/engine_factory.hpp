#pragma once
/// Chooses the engine for a model name.

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "pdamp/model/engine.hpp"
#include "pdamp/model/restitution.hpp"
#include "pdamp/scenario/scenario.hpp"

namespace pdamp {

enum class Model { soft, hard };

/// An engine kind with its settings that follow from the scenario alone, made once per run
/// by prepare_engine and given to make_engine and restore_engine.
struct EngineSetup {
  // A constructor rather than an aggregate: `{Model::soft}` leaves the rest default
  // without -Wmissing-field-initializers.
  EngineSetup(Model model_, std::optional<RestitutionTable> calibration_ = std::nullopt, bool diagnose_events_ = false)
      : model(model_), calibration(std::move(calibration_)), diagnose_events(diagnose_events_) {}

  Model model;
  /// The hard model's restitution e_n(v), β0(v), when the scenario asks for calibrated
  /// restitution (sim/calibration.hpp); the other engines ignore it.
  std::optional<RestitutionTable> calibration;
  /// The hard engine counts where its collisions come from into its statistics
  /// (HardEngine::diagnose_events); the results are the same bits. Others ignore it.
  bool diagnose_events = false;
};

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
  std::unique_ptr<Engine> (*make)(const EngineSetup& setup, const Scenario& scenario, const Particles& initial);
};

/// Every engine, soft first.
std::span<const EngineKind> engine_kinds();
const EngineKind& engine_kind(Model model);

std::string_view to_string(Model model);
/// Throws InputError for a name not in engine_kinds(), naming the valid ones.
Model parse_model(std::string_view text);

/// --simd: the instruction set of both engines' kernels, "sse2", "avx2" or "avx512", for
/// the engines this process makes from now on (pdamp/simd/simd_path.hpp), with the same
/// bits on each. Throws InputError naming `option` for a set this build or CPU cannot run.
void set_instruction_set(std::string_view text, std::string_view option);

/// Checks that `model` can run the scenario (the soft engine's time
/// step, the run's budget: run_budget.hpp), before any work is done. Throws InputError
/// naming the offending key.
void check_model_can_run(Model model, const Scenario& scenario);

/// The setup of `model` for the scenario: checks that the model can run it
/// (check_model_can_run) and calibrates the hard model's restitution if the scenario asks
/// for it (which runs the soft engine on isolated collisions). Throws InputError for a
/// scenario the model cannot run or a calibration that fails, naming the key.
EngineSetup prepare_engine(Model model, const Scenario& scenario, bool diagnose_events = false);

/// The engine of `setup` for the scenario, starting from `initial` (a placement or a
/// settled bed) with the host in its initial condition. A scenario without particles
/// runs the host alone on its exact solution, whatever the model. Throws InputError for
/// a scenario the engine cannot run.
std::unique_ptr<Engine> make_engine(const EngineSetup& setup, const Scenario& scenario, const Particles& initial);

/// The engine of a run restored from its checkpoint: built as make_engine built the run's
/// (the same arguments), then given the state saved in `checkpoint` (after the run loop's
/// part, read_run_loop_state), which must then be read to its end. Throws RuntimeFailure
/// if the checkpoint does not fit the engine.
std::unique_ptr<Engine> restore_engine(const EngineSetup& setup, const Scenario& scenario, const Particles& initial,
                                       CheckpointReader& checkpoint);

}  // namespace pdamp
