#include "pdamp/study/point_runner.hpp"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <vector>

#include "pdamp/compare/comparison.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/model/host.hpp"
#include "pdamp/sim/frf_point.hpp"
#include "pdamp/sim/initial_bed.hpp"
#include "pdamp/sim/stored_run.hpp"
#include "pdamp/store/process_lease.hpp"

namespace pdamp::study {
namespace {

/// Why a point could not be claimed, from its stored state.
std::string not_claimed(StudyStore& studies, std::int64_t study_id, int point) {
  const auto p = studies.point(study_id, point);
  if (!p) throw InputError("study " + std::to_string(study_id) + " has no point " + std::to_string(point));
  if (p->status == PointStatus::running && p->lease) {
    return "point " + std::to_string(point) + " is running in process " + std::to_string(p->lease->pid) + " on " +
           p->lease->host;
  }
  return "point " + std::to_string(point) + " is " + std::string(to_string(p->status));
}

/// The point's runs: their ids, the run that ended it if it did not complete, and the
/// comparison of a `both` point.
struct PointRuns {
  std::vector<StoredRun> runs;
  std::optional<std::int64_t> comparison_id;
  std::optional<FrfPointResult> frf;                    ///< a completed frequency-response point's
  std::optional<CharacterisePointResult> characterise;  ///< a completed characterisation point's
  Particles end_spheres;                                ///< and its spheres at the end
};

double kinetic_energy_J(const Particles& p) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < p.size(); ++i) sum += 0.5 * p.mass_kg[i] * p.velocity_m_s.col(i).squaredNorm();
  return sum;
}

class PointExecution {
 public:
  PointExecution(RunStore& store, std::int64_t study_id, const Study& study, int point, int attempt,
                 const PointRunControl& control)
      : store_(&store),
        studies_(store),
        study_id_(study_id),
        study_(&study),
        point_(point),
        attempt_(attempt),
        control_(&control) {}

  PointRuns run() {
    const StudyPoint& point = study_->points.at(static_cast<std::size_t>(point_ - 1));
    if (point.characterise) return run_characterise(point);
    return point.frf ? run_frf(point) : run_sweep(point);
  }

 private:
  PointRuns run_sweep(const StudyPoint& point) {
    const Scenario scenario = point_scenario(*study_, point);
    std::vector<RunPlan> plans;
    if (study_->file.models != StudyModels::hard) plans.push_back(plan_run(Model::soft, scenario, control_->snapshots));
    if (study_->file.models != StudyModels::soft) plans.push_back(plan_run(Model::hard, scenario, control_->snapshots));
    // Settled (or taken from the store) when the first run needs it, after that run's row.
    std::optional<InitialBed> bed;
    const BedSource bed_source = [&]() -> const InitialBed& { return settled_bed(scenario, bed); };
    PointRuns result;
    for (std::size_t m = 0; m < plans.size(); ++m) {
      const std::string_view model = to_string(plans[m].engine.model);
      const RunControl run_control = run_control_for([&, m, duration = scenario.run.duration_s](double t) {
        report((static_cast<double>(m) + t / duration) / static_cast<double>(plans.size()), model);
      });
      std::optional<StoredRun> run = continue_earlier_run(model, run_control, {}, true);
      if (!run) {
        run = run_and_store(*store_, plans[m], bed_source, run_control, control_->warn, [&](std::int64_t run_id) {
          studies_.link_run(study_id_, point_, attempt_, model, run_id);
        });
      }
      result.runs.push_back(*run);
      if (run->outcome.status != RunStatus::completed) return result;
    }
    if (plans.size() == 2) {
      result.comparison_id =
          store_comparison(*store_, scenario, bed_source().state_id, result.runs[0].run_id, result.runs[1].run_id)
              .first;
    }
    return result;
  }

  /// The final state a point continues from (nothing: the settled bed).
  std::optional<FrfEndState> start_state(int previous) {
    if (previous == 0) return std::nullopt;
    auto from = studies_.end_state(study_id_, previous);
    if (!from) {
      throw RuntimeFailure("point " + std::to_string(point_) + " continues from point " + std::to_string(previous) +
                           ", which is not completed; run that point first");
    }
    return from;
  }

  /// The settled bed (settled now, or taken from the store).
  const InitialBed& settled_bed(const Scenario& scenario, std::optional<InitialBed>& bed) {
    if (!bed) {
      report(0.0, "settling");
      bed = prepare_initial_bed(scenario, *store_, control_->stop, [this](double, double) { report(0.0, "settling"); });
    }
    return *bed;
  }

  /// The spheres a continued point starts from: the previous point's final ones, moved by
  /// `shift` with the host (start = predict), which the run records beside the state.
  InitialBed continued_bed(const FrfEndState& from, const std::optional<HostState>& shift) {
    Particles spheres = store_->load_initial_particles(from.state_id);
    if (shift) spheres = moved_with_host(std::move(spheres), *shift);
    return {std::move(spheres), from.state_id, true, from.t_s, shift};
  }

  /// The control of a run of this point: its stop, checkpoints and `progress`.
  RunControl run_control_for(std::function<void(double t_s)> progress) const {
    RunControl run_control;
    run_control.stop = control_->stop;
    run_control.checkpoint_interval = control_->checkpoint_interval;
    run_control.progress = std::move(progress);
    return run_control;
  }

  /// This point's run of `model` that an earlier attempt left, taken over by this attempt:
  /// as it is if it completed and `keep_completed`, or resumed from its checkpoint (with
  /// `body` if it is not the run loop's) to its end. Nothing if there is none, or if it
  /// cannot be resumed: then the reason is reported and the model runs from its start.
  std::optional<StoredRun> continue_earlier_run(std::string_view model, const RunControl& run_control,
                                                const ResumedBody& body, bool keep_completed) {
    const std::optional<std::int64_t> run_id = studies_.earlier_run(study_id_, point_, attempt_, model);
    if (!run_id) return std::nullopt;
    const auto take_over = [&] { studies_.move_run(study_id_, point_, attempt_, *run_id); };
    const std::string run = "run " + std::to_string(*run_id) + " (" + std::string(model) + ")";
    if (keep_completed && store_->summary(*run_id)->status == to_string(RunStatus::completed)) {
      take_over();
      return StoredRun{*run_id, {}};
    }
    try {
      return resume_and_store(*store_, *run_id, std::nullopt, run_control, control_->warn, body, take_over);
    } catch (const Interrupted&) {
      throw;
    } catch (const std::exception& e) {
      if (control_->warn) control_->warn(run + " of an earlier attempt is run again from its start: " + e.what());
      return std::nullopt;
    }
  }

  /// A cycle-by-cycle point's snapshots, at its cycle boundaries (cycle_frames): a new
  /// run's, or those of the run an earlier attempt left, continued from its checkpoint.
  struct CycleSnapshots {
    double period_s;
    std::optional<std::int64_t> earlier;  ///< the run an earlier attempt left, if any
    std::optional<SnapshotWriter> frames;
  };

  /// A point run cycle by cycle (`plan.body` set, observing with `snapshots`; `resumed`,
  /// the same from a checkpoint), from the previous point's final state `from` (moved by
  /// `shift`) or from the settled bed, into the store linked to the point; or the run an
  /// earlier attempt left, resumed. Its snapshots, if any, are recorded with it.
  StoredRun run_cycles(const Scenario& scenario, Model model, const RunPlan& plan, const ResumedBody& resumed,
                       CycleSnapshots& snapshots, const std::optional<FrfEndState>& from,
                       const std::optional<HostState>& shift = {}) {
    std::optional<InitialBed> bed;
    const BedSource bed_source = [&]() -> const InitialBed& {
      if (!bed && from) bed = continued_bed(*from, shift);
      return settled_bed(scenario, bed);
    };
    const std::string_view name = to_string(model);
    const RunControl run_control =
        run_control_for([&, duration = scenario.run.duration_s](double t) { report(t / duration, name); });
    std::optional<StoredRun> run = continue_earlier_run(name, run_control, resumed, false);
    if (!run) {
      run = run_and_store(*store_, plan, bed_source, run_control, control_->warn, [&](std::int64_t run_id) {
        studies_.link_run(study_id_, point_, attempt_, name, run_id);
        start_snapshots(snapshots, scenario, run_id);
      });
    }
    if (snapshots.frames) record_snapshots(run->run_id, *snapshots.frames);
    return *run;
  }

  /// A frequency-response point: from the previous point's final state (continuation) or
  /// from the settled bed, its model's run to steady state, and its own final state kept
  /// for the next point.
  PointRuns run_frf(const StudyPoint& point) {
    const FrfPoint& frf = *point.frf;
    const std::optional<FrfEndState> from = start_state(frf.previous);
    const std::optional<HostState> shift = from ? predicted_start_shift(point) : std::nullopt;
    std::optional<HostState> host;
    if (from) host = shift ? HostState{from->host.z_m + shift->z_m, from->host.v_m_s + shift->v_m_s} : from->host;
    const Scenario scenario = point_scenario(*study_, point, host);
    RunPlan plan = plan_run(frf.model, scenario);
    FrfRun frf_run;
    CycleSnapshots snapshots = cycle_snapshots(scenario, frf.model);
    const auto [body, resumed] = cycle_bodies([&, criterion = point_criterion(*study_, point)](
                                                  Engine& engine, const Scenario& s, RunRecorder& recorder,
                                                  const RunControl& c, const CycleLoopState* resume) {
      return run_frf_simulation(engine, s, recorder, observing(snapshots, c, s, resume), criterion, frf_run, resume);
    });
    plan.body = body;
    PointRuns result;
    result.runs.push_back(run_cycles(scenario, frf.model, plan, resumed, snapshots, from, shift));
    const StoredRun& run = result.runs.back();
    if (run.outcome.status != RunStatus::completed) return result;
    const State& end = frf_run.final_state;
    result.frf = FrfPointResult{run.run_id,
                                frf_run.point.metrics,
                                frf_run.point.cycles_run,
                                end.particles.total_mass_kg(),
                                run.outcome.wall_time_s,
                                {run.run_id, 0, end.observation.t_s, end.observation.host}};
    result.end_spheres = end.particles;
    return result;
  }

  CycleSnapshots cycle_snapshots(const Scenario& scenario, Model model) {
    return {cycle_period_s(scenario), studies_.earlier_run(study_id_, point_, attempt_, to_string(model)), {}};
  }

  /// `control`, writing the frames at the cycle boundaries: a run resumed from `resume`
  /// continues those its earlier attempt recorded.
  RunControl observing(CycleSnapshots& snapshots, const RunControl& control, const Scenario& scenario,
                       const CycleLoopState* resume) {
    const auto recorded = resume && snapshots.earlier ? store_->snapshots(*snapshots.earlier) : std::nullopt;
    if (recorded) {
      snapshots.frames.emplace(SnapshotFiles{recorded->folder, recorded->collection}, scenario,
                               cycle_frames(recorded->interval_s, snapshots.period_s), resume->outcome.samples - 1);
    }
    RunControl observed = control;
    if (snapshots.frames) {
      observed.at_observation = [&frames = snapshots.frames](const Engine& e, const ObservationStep& step) {
        frames->at_observation(e, step);
      };
    }
    return observed;
  }

  /// The frames of the new run `run_id`, if asked for, recorded in the store as it starts.
  void start_snapshots(CycleSnapshots& snapshots, const Scenario& scenario, std::int64_t run_id) {
    if (!control_->snapshots) return;
    snapshots.frames.emplace(*control_->snapshots, scenario, run_id,
                             cycle_frames(control_->snapshots->interval_s, snapshots.period_s));
    record_snapshots(run_id, *snapshots.frames);
  }

  /// Where run `run_id`'s snapshots are, their interval and how many frames there are.
  void record_snapshots(std::int64_t run_id, const SnapshotWriter& frames) {
    const SnapshotFiles& files = frames.files();
    store_->save_snapshots(
        run_id, {files.folder.string(), files.collection.string(), frames.frame_grid().interval_s(), frames.frames()});
  }

  /// With start = predict, how far a continued point moves the host and its bed from the
  /// previous point's end (predicted_shift, from that point's stored metrics).
  std::optional<HostState> predicted_start_shift(const StudyPoint& point) {
    if (study_->file.frfs.at(point.frf->section).start != FrfStart::prediction) return std::nullopt;
    const int previous = point.frf->previous;
    const auto stored = studies_.frf_metrics(study_id_, previous);
    if (!stored) {
      throw RuntimeFailure("point " + std::to_string(point_) + " is predicted from point " + std::to_string(previous) +
                           ", whose metrics are not stored");
    }
    const StudyPoint& before = study_->points.at(static_cast<std::size_t>(previous - 1));
    const double previous_omega_rad_s = point_scenario(*study_, before).excitation.angular_frequency_rad_s();
    return predicted_shift(stored->metrics, previous_omega_rad_s, HostModel(point_scenario(*study_, point)));
  }

  /// A characterisation point: the container's prescribed motion (time restarts at 0 on
  /// the previous point's final spheres: the container is at z = 0 there, only its
  /// velocity amplitude changes), its run to steady state, and its final state.
  PointRuns run_characterise(const StudyPoint& point) {
    const CharacterisePoint& c = *point.characterise;
    const std::optional<FrfEndState> from = start_state(c.previous);
    const Scenario scenario = point_scenario(*study_, point);
    RunPlan plan = plan_run(c.model, scenario);
    CharacterisationRun characterisation;
    CycleSnapshots snapshots = cycle_snapshots(scenario, c.model);
    const auto [body, resumed] = cycle_bodies(
        [&, criterion = point_criterion(*study_, point)](Engine& engine, const Scenario& s, RunRecorder& recorder,
                                                         const RunControl& rc, const CycleLoopState* resume) {
          return run_characterisation_simulation(engine, s, recorder, observing(snapshots, rc, s, resume), criterion,
                                                 characterisation, resume);
        });
    plan.body = body;
    PointRuns result;
    result.runs.push_back(run_cycles(scenario, c.model, plan, resumed, snapshots, from));
    const StoredRun& run = result.runs.back();
    if (run.outcome.status != RunStatus::completed) return result;
    std::optional<InitialBed> settled;
    const double free_height_m = free_height(scenario, settled_bed(scenario, settled).particles);
    const State& end = characterisation.final_state;
    result.characterise = CharacterisePointResult{run.run_id,
                                                  characterisation.point.metrics,
                                                  characterisation.point.cycles_run,
                                                  end.particles.total_mass_kg(),
                                                  scenario.gravity_m_s2.norm(),
                                                  free_height_m,
                                                  run.outcome.wall_time_s,
                                                  {run.run_id, 0, end.observation.t_s, end.observation.host}};
    result.end_spheres = end.particles;
    return result;
  }

  /// A cycle-by-cycle point's body (`run` from its start) and the same resumed from a
  /// checkpoint (`run` from the loop state the checkpoint holds).
  using CycleBody =
      std::function<RunOutcome(Engine&, const Scenario&, RunRecorder&, const RunControl&, const CycleLoopState*)>;
  static std::pair<RunBody, ResumedBody> cycle_bodies(const CycleBody& run) {
    const RunBody from_start = [run](Engine& e, const Scenario& s, RunRecorder& r, const RunControl& c) {
      return run(e, s, r, c, nullptr);
    };
    const ResumedBody resumed = [run](CheckpointReader& checkpoint) -> RunBody {
      auto loop = std::make_shared<const CycleLoopState>(read_cycle_loop_state(checkpoint));
      return [run, loop](Engine& e, const Scenario& s, RunRecorder& r, const RunControl& c) {
        return run(e, s, r, c, loop.get());
      };
    };
    return {from_start, resumed};
  }

  /// L: the cavity's height above the settled bed's top (the bed settled with the host at
  /// its initial position); the whole height without particles.
  static double free_height(const Scenario& scenario, const Particles& bed) {
    const double floor_m = HostModel(scenario).initial_state().z_m;
    double top_m = floor_m;
    for (Eigen::Index i = 0; i < bed.size(); ++i) top_m = std::max(top_m, bed.position_m(2, i) + bed.radius_m[i]);
    return scenario.cavity.height_m - (top_m - floor_m);
  }

  void report(double fraction, std::string_view phase) const {
    if (control_->progress) control_->progress(fraction, phase);
  }

  RunStore* store_;
  StudyStore studies_;
  std::int64_t study_id_;
  const Study* study_;
  int point_, attempt_;
  const PointRunControl* control_;
};

PointResult finish(StudyStore& studies, std::int64_t study_id, int point, int attempt, const PointRuns& result) {
  std::vector<std::int64_t> run_ids;
  for (const auto& run : result.runs) {
    if (run.outcome.status != RunStatus::completed) {
      const PointStatus status =
          run.outcome.status == RunStatus::interrupted ? PointStatus::interrupted : PointStatus::failed;
      const std::string message = "run " + std::to_string(run.run_id) + ": " + run.outcome.message;
      studies.end_point(study_id, point, attempt, status, message);
      return {status, attempt, message};
    }
    run_ids.push_back(run.run_id);
  }
  if (result.frf) {
    studies.complete_frf_point(study_id, point, attempt, *result.frf, result.end_spheres,
                               kinetic_energy_J(result.end_spheres));
    return {PointStatus::completed, attempt, ""};
  }
  if (result.characterise) {
    studies.complete_characterise_point(study_id, point, attempt, *result.characterise, result.end_spheres,
                                        kinetic_energy_J(result.end_spheres));
    return {PointStatus::completed, attempt, ""};
  }
  studies.complete_point(study_id, point, attempt, run_ids, result.comparison_id);
  return {PointStatus::completed, attempt, ""};
}

}  // namespace

std::string progress_line(double fraction, std::string_view phase) {
  char text[32];
  std::snprintf(text, sizeof text, "progress %.4f ", fraction);
  return text + std::string(phase) + "\n";
}

Study stored_study(const StudyRecord& record) {
  return make_study({record.study_file, record.study_text, record.scenario_file, record.scenario_text}, true);
}

PointResult run_study_point(RunStore& store, std::int64_t study_id, const Study& study, int point,
                            const PointRunControl& control) {
  if (point < 1 || static_cast<std::size_t>(point) > study.points.size()) {
    throw InputError("study " + std::to_string(study_id) + " has points 1 to " + std::to_string(study.points.size()) +
                     ", not " + std::to_string(point));
  }
  StudyStore studies(store);
  const auto attempt = studies.claim_point(study_id, point, this_process_lease());
  if (!attempt) return {PointStatus::pending, 0, not_claimed(studies, study_id, point)};
  try {
    return finish(studies, study_id, point, *attempt,
                  PointExecution(store, study_id, study, point, *attempt, control).run());
  } catch (const Interrupted& e) {
    studies.end_point(study_id, point, *attempt, PointStatus::interrupted, e.what());
    return {PointStatus::interrupted, *attempt, e.what()};
  } catch (const std::exception& e) {
    studies.end_point(study_id, point, *attempt, PointStatus::failed, e.what());
    return {PointStatus::failed, *attempt, e.what()};
  }
}

}  // namespace pdamp::study
