#include "pdamp/store/shard_merge.hpp"

#include <array>
#include <charconv>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <vector>

#include "pdamp/errors.hpp"
#include "store_file.hpp"

namespace pdamp {
namespace {

/// The tables of a run's own rows, keyed by run_id and copied as they are.
constexpr std::array<std::string_view, 6> run_tables{"samples",      "cycles",        "run_statistics",
                                                     "calibrations", "run_snapshots", "run_checkpoints"};

constexpr std::array<std::string_view, 19> merged{"initial_states",
                                                  "initial_particles",
                                                  "runs",
                                                  "samples",
                                                  "cycles",
                                                  "run_statistics",
                                                  "calibrations",
                                                  "run_snapshots",
                                                  "run_checkpoints",
                                                  "comparisons",
                                                  "comparison_psi_bins",
                                                  "comparison_energy",
                                                  "study_point_runs",
                                                  "study_point_metrics",
                                                  "study_frf_metrics",
                                                  "study_characterise_metrics",
                                                  "study_point_states",
                                                  "study_points",
                                                  "study_tasks"};
// The points' places on their curves are the study's definition, which the store holds.
// A shard's comparisons are its points' (study_point_runs), never a `pdamp compare` under way.
constexpr std::array<std::string_view, 7> unmerged{
    "studies",          "study_point_values",       "study_jobs", "comparison_runs", "sqlite_sequence",
    "study_frf_points", "study_characterise_points"};

/// A shard's ids and their new ids in the store.
using IdMap = std::map<std::int64_t, std::int64_t>;

std::string quoted(const std::filesystem::path& file) { return "'" + file.string() + "'"; }

std::int64_t integer(sqlite::Database& db, const std::string& sql) {
  sqlite::Statement q(db, sql);
  q.step();
  return q.column_int(0);
}

/// Copies rows of one table from the shard into the store, column for column, bit for bit:
/// the rows whose `key` column has a value (and that meet `also`, an SQL condition), with the
/// columns in `remap` mapped to the store's ids. With `own_id`, that column is left for the
/// store to number, and the map from the shard's ids to the store's is filled.
class RowCopier {
 public:
  RowCopier(sqlite::Database& shard, sqlite::Database& store, std::string_view table, std::string_view key,
            std::map<std::string, const IdMap*> remap, std::string_view own_id = {}, std::string_view also = {})
      : store_(&store), table_(table), remap_(std::move(remap)) {
    std::string names, slots;
    sqlite::Statement columns(store, "SELECT name FROM pragma_table_info(?) ORDER BY cid");
    columns.bind(1, table);
    while (columns.step()) {
      const std::string name = columns.column_text(0);
      if (name == own_id) continue;
      names += (names.empty() ? "" : ", ") + name;
      slots += slots.empty() ? "?" : ", ?";
      columns_.push_back(name);
    }
    select_ = std::make_unique<sqlite::Statement>(
        shard, "SELECT " + (own_id.empty() ? std::string("NULL") : std::string(own_id)) + ", " + names + " FROM " +
                   std::string(table) + " WHERE " + std::string(key) + " = ?" +
                   (also.empty() ? std::string() : " AND " + std::string(also)));
    insert_ = std::make_unique<sqlite::Statement>(
        store, "INSERT INTO " + std::string(table) + " (" + names + ") VALUES (" + slots + ")");
  }

  /// The next copies write `text` into `column` instead of the shard's value.
  void set(const std::string& column, std::string text) { set_[column] = std::move(text); }

  /// Copies the rows whose key is `key_value`; returns how many.
  int copy(std::int64_t key_value, IdMap* own_ids = nullptr) {
    select_->bind(1, key_value);
    int rows = 0;
    while (select_->step()) {
      for (std::size_t c = 0; c < columns_.size(); ++c) bind(static_cast<int>(c));
      insert_->run();
      if (own_ids) (*own_ids)[select_->column_int(0)] = store_->last_insert_rowid();
      ++rows;
    }
    select_->reset();
    return rows;
  }

 private:
  void bind(int c) {
    const int column = c + 1;  // after the own id
    if (const auto text = set_.find(columns_[static_cast<std::size_t>(c)]); text != set_.end()) {
      insert_->bind(c + 1, text->second);
      return;
    }
    const auto it = remap_.find(columns_[static_cast<std::size_t>(c)]);
    if (it == remap_.end() || select_->is_null(column)) {
      insert_->bind_column(c + 1, *select_, column);
      return;
    }
    const auto id = it->second->find(select_->column_int(column));
    if (id == it->second->end()) {
      throw RuntimeFailure("a row of " + table_ + " refers to " + it->first + " " +
                           std::to_string(select_->column_int(column)) + ", which was not merged");
    }
    insert_->bind(c + 1, id->second);
  }

  sqlite::Database* store_;
  std::string table_;
  std::map<std::string, const IdMap*> remap_;
  std::map<std::string, std::string> set_;
  std::vector<std::string> columns_;
  std::unique_ptr<sqlite::Statement> select_, insert_;
};

/// The shard file, opened read-only without locks (nobody writes a finished shard, and
/// cluster file systems lock unreliably), checked to be a store of the store's schema.
class Shard {
 public:
  Shard(const std::filesystem::path& file, sqlite::Database& store) : file_(file) {
    try {
      db_ = std::make_unique<sqlite::Database>(file, sqlite::Access::snapshot);
      check_schema(store);
    } catch (const sqlite::Damaged& e) {
      throw InputError("shard " + quoted(file) + " is not a pdamp store or is damaged: " + e.what());
    }
  }
  sqlite::Database& db() { return *db_; }
  const std::filesystem::path& file() const { return file_; }

  /// The shard's study, which must be `study`.
  void check_study(const StudyRecord& study) {
    const auto studies = StudyStore(*db_).studies();
    if (studies.size() != 1) {
      throw InputError("shard " + quoted(file_) + " holds " + std::to_string(studies.size()) +
                       " studies, not one: it was not written by 'pdamp study task'");
    }
    const StudyRecord& s = studies.front();
    if (s.study_id != study.study_id || s.name != study.name || s.models != study.models ||
        s.study_text != study.study_text || s.scenario_text != study.scenario_text ||
        s.created_at != study.created_at) {
      throw InputError("shard " + quoted(file_) + " belongs to study " + std::to_string(s.study_id) + " '" + s.name +
                       "' created " + s.created_at + ", not to study " + std::to_string(study.study_id) + " '" +
                       study.name + "' created " + study.created_at + "; nothing was added from it");
    }
  }

  /// The shard's own task.
  StudyTask task(std::int64_t study_id) {
    auto tasks = StudyStore(*db_).tasks(study_id);
    if (tasks.size() != 1) {
      throw InputError("shard " + quoted(file_) + " holds " + std::to_string(tasks.size()) +
                       " task records, not one: it was not written by 'pdamp study task'");
    }
    return tasks.front();
  }

 private:
  void check_schema(sqlite::Database& store) {
    if (integer(*db_, "PRAGMA application_id") != store_file::pdamp_application_id) {
      throw InputError("shard " + quoted(file_) + " is not a pdamp store");
    }
    const std::int64_t version = integer(*db_, "PRAGMA user_version");
    if (version != RunStore::schema_version()) {
      throw InputError("shard " + quoted(file_) + " has schema version " + std::to_string(version) + ", the store " +
                       std::to_string(RunStore::schema_version()) +
                       ": it was written by another version of pdamp; collect it with the pdamp that ran the task");
    }
    const std::string schema =
        "SELECT group_concat(type || ' ' || name || ' ' || coalesce(sql, ''), char(10)) FROM "
        "(SELECT * FROM sqlite_schema ORDER BY type, name)";
    sqlite::Statement ours(store, schema), theirs(*db_, schema);
    ours.step();
    theirs.step();
    if (!ours.same_value(0, theirs, 0)) {
      throw InputError("shard " + quoted(file_) + " has schema version " + std::to_string(version) +
                       " but other tables than the store's: it was written by another build of pdamp");
    }
    if (sqlite::Statement check(*db_, "PRAGMA quick_check(1)"); check.step() && check.column_text(0) != "ok") {
      throw InputError("shard " + quoted(file_) + " is damaged (SQLite's quick_check: " + check.column_text(0) + ")");
    }
  }

  std::filesystem::path file_;
  std::unique_ptr<sqlite::Database> db_;
};

/// One shard's merge, inside the store's write transaction.
class Merger {
 public:
  Merger(Shard& shard, sqlite::Database& store, std::int64_t study_id, ShardMerge& result)
      : shard_(&shard), store_(&store), study_id_(study_id), result_(&result) {}

  void run() {
    const StudyTask& task = result_->task;
    sqlite::Statement collected(*store_,
                                "SELECT collected_at IS NOT NULL, point FROM study_tasks "
                                "WHERE study_id = ? AND job_id = ? AND task = ?");
    collected.bind(1, study_id_).bind(2, task.job_id).bind(3, task.task);
    if (collected.step()) {
      if (collected.column_int(1) != task.point) {
        throw InputError("shard " + quoted(shard_->file()) + " ran point " + std::to_string(task.point) + " as task " +
                         std::to_string(task.task) + " of job " + std::to_string(task.job_id) +
                         ", which was submitted to run point " + std::to_string(collected.column_int(1)));
      }
      if (collected.column_int(0) != 0) {
        result_->already_collected = true;
        return;
      }
    }
    const std::vector<int> points = task_points();
    for (std::size_t i = 0; i < points.size(); ++i) {
      const std::string not_added = merge_point(points[i]);
      if (not_added.empty()) continue;
      result_->not_added =
          not_added + (i + 1 < points.size() ? "; nor the rest of its curve, which continues from it" : "");
      break;
    }
    record_task();
  }

 private:
  /// The points the task ran: its point, then (a curve's task) each point continuing from
  /// the one before, up to one that did not run in the task: still pending, or completed
  /// without runs of its own (a final state the task started from, copied from the store).
  std::vector<int> task_points() {
    const int first = result_->task.point;
    std::vector<int> points;
    StudyStore shard(shard_->db());
    sqlite::Statement runs(shard_->db(), "SELECT count(*) FROM study_point_runs WHERE point = ?");
    for (const int point : shard.curve_from(study_id_, first)) {
      const auto state = shard.point(study_id_, point);
      if (!state) break;
      runs.bind(1, point);
      runs.step();
      const bool own_runs = runs.column_int(0) > 0;
      runs.reset();
      if (point != first && (state->status == PointStatus::pending || !own_runs)) break;
      points.push_back(point);
    }
    return points;
  }

  /// Adds the point's results if the store wants them; else returns why not.
  std::string merge_point(int point_number) {
    const auto ours = StudyStore(*store_).point(study_id_, point_number);
    const auto theirs = StudyStore(shard_->db()).point(study_id_, point_number);
    if (!ours || !theirs) {
      throw InputError("shard " + quoted(shard_->file()) + ": its point " + std::to_string(point_number) +
                       " is not a point of study " + std::to_string(study_id_) + " in both stores");
    }
    const std::string point = "point " + std::to_string(point_number);
    if (theirs->status == PointStatus::pending || theirs->status == PointStatus::running) {
      return point + " did not end in its task";
    }
    if (ours->status == PointStatus::completed) {
      return point + " was completed already; the shard's results for it are not added";
    }
    if (ours->status == PointStatus::running) {
      return point + " is running in " +
             (ours->lease ? "process " + std::to_string(ours->lease->pid) + " on " + ours->lease->host
                          : std::string("another process")) +
             "; the shard's results for it are not added";
    }
    add_results(point_number, ours->attempt, theirs->attempt);
    result_->results_added = true;
    ++result_->points;
    return "";
  }

  /// The point's runs (every attempt's), their beds, comparison and metrics, numbered
  /// after the store's attempts, its final state (a curve's point), and its status.
  void add_results(int point, int attempts_before, int shard_attempts) {
    IdMap attempts;
    for (int a = 1; a <= shard_attempts; ++a) attempts[a] = attempts_before + a;
    std::vector<std::int64_t> runs;
    // Runs under attempt 0 are the store's, which the task was given to continue
    // (copy_end_states): added only once an attempt of the task took them over.
    sqlite::Statement links(shard_->db(),
                            "SELECT run_id FROM study_point_runs WHERE point = ? AND attempt > 0 ORDER BY run_id");
    links.bind(1, point);
    while (links.step()) runs.push_back(links.column_int(0));
    sqlite::Statement comparison(shard_->db(), "SELECT comparison_id FROM study_points WHERE point = ?");
    comparison.bind(1, point);
    comparison.step();
    const std::optional<std::int64_t> comparison_id =
        comparison.is_null(0) ? std::nullopt : std::optional(comparison.column_int(0));

    add_beds(runs, comparison_id);
    RowCopier run_rows(shard_->db(), *store_, "runs", "run_id", {{"initial_state_id", &beds_}}, "run_id");
    for (const std::int64_t run : runs) run_rows.copy(run, &runs_);
    for (const std::string_view table : run_tables) {
      RowCopier rows(shard_->db(), *store_, table, "run_id", {{"run_id", &runs_}});
      for (const std::int64_t run : runs) rows.copy(run);
    }
    IdMap comparisons;
    if (comparison_id) {
      RowCopier(shard_->db(), *store_, "comparisons", "comparison_id",
                {{"soft_run_id", &runs_}, {"hard_run_id", &runs_}, {"initial_state_id", &beds_}}, "comparison_id")
          .copy(*comparison_id, &comparisons);
      for (const std::string_view table : {"comparison_psi_bins", "comparison_energy"}) {
        RowCopier(shard_->db(), *store_, table, "comparison_id", {{"comparison_id", &comparisons}})
            .copy(*comparison_id);
      }
    }
    RowCopier(shard_->db(), *store_, "study_point_runs", "point", {{"run_id", &runs_}, {"attempt", &attempts}}, {},
              "attempt > 0")
        .copy(point);
    sqlite::Statement stale(*store_, "DELETE FROM study_point_metrics WHERE study_id = ? AND point = ?");
    stale.bind(1, study_id_).bind(2, point).run();
    RowCopier(shard_->db(), *store_, "study_point_metrics", "point", {{"run_id", &runs_}}).copy(point);
    for (const std::string_view table : {"study_frf_metrics", "study_characterise_metrics"}) {
      RowCopier(shard_->db(), *store_, table, "point", {{"run_id", &runs_}}).copy(point);
    }
    add_end_state(point);
    update_point(point, attempts_before, comparison_id ? std::optional(comparisons.at(*comparison_id)) : std::nullopt);
    result_->runs += static_cast<int>(runs.size());
  }

  /// A curve's point's final state: its spheres as a new bed, labelled by the store's id of
  /// the run that ended there (the label names the run, so it differs in the store), which
  /// the next point's run starts from.
  void add_end_state(int point) {
    sqlite::Statement end(shard_->db(),
                          "SELECT s.state_id, s.run_id, i.settle_key FROM study_point_states s "
                          "JOIN initial_states i ON i.state_id = s.state_id WHERE s.point = ?");
    end.bind(1, point);
    if (!end.step()) return;
    const std::int64_t state = end.column_int(0), run = end.column_int(1);
    const std::string label = end.column_text(2), suffix = "run " + std::to_string(run);
    if (!label.ends_with(suffix)) {
      throw RuntimeFailure("shard " + quoted(shard_->file()) + ": the final state of point " + std::to_string(point) +
                           " is labelled '" + label + "', not by its run " + std::to_string(run));
    }
    RowCopier state_row(shard_->db(), *store_, "initial_states", "state_id", {}, "state_id");
    state_row.set("settle_key", label.substr(0, label.size() - suffix.size()) + "run " + std::to_string(runs_.at(run)));
    state_row.copy(state, &beds_);
    RowCopier(shard_->db(), *store_, "initial_particles", "state_id", {{"state_id", &beds_}}).copy(state);
    RowCopier(shard_->db(), *store_, "study_point_states", "point", {{"run_id", &runs_}, {"state_id", &beds_}})
        .copy(point);
    ++result_->beds_added;
  }

  /// The beds the runs and the comparison started from: the store's bed of the same
  /// settings if it has one (which must be the same bits), else a copy.
  void add_beds(const std::vector<std::int64_t>& runs, std::optional<std::int64_t> comparison_id) {
    std::vector<std::int64_t> states;
    sqlite::Statement run_bed(shard_->db(), "SELECT initial_state_id FROM runs WHERE run_id = ?");
    for (const std::int64_t run : runs) {
      run_bed.bind(1, run);
      if (run_bed.step() && !run_bed.is_null(0)) states.push_back(run_bed.column_int(0));
      run_bed.reset();
    }
    if (comparison_id) {
      sqlite::Statement bed(shard_->db(), "SELECT initial_state_id FROM comparisons WHERE comparison_id = ?");
      bed.bind(1, *comparison_id);
      if (bed.step() && !bed.is_null(0)) states.push_back(bed.column_int(0));
    }
    RowCopier state_rows(shard_->db(), *store_, "initial_states", "state_id", {}, "state_id");
    RowCopier particle_rows(shard_->db(), *store_, "initial_particles", "state_id", {{"state_id", &beds_}});
    sqlite::Statement key(shard_->db(), "SELECT settle_key FROM initial_states WHERE state_id = ?");
    sqlite::Statement existing(*store_, "SELECT state_id FROM initial_states WHERE settle_key = ?");
    for (const std::int64_t state : states) {
      if (beds_.contains(state)) continue;
      key.bind(1, state);
      if (!key.step())
        throw RuntimeFailure("shard " + quoted(shard_->file()) + " lacks its bed " + std::to_string(state));
      const std::string label = store_label(key.column_text(0));
      existing.bind(1, label);
      if (existing.step()) {
        check_same_bed(state, existing.column_int(0));
        beds_[state] = existing.column_int(0);
        ++result_->beds_shared;
      } else {
        state_rows.set("settle_key", label);
        state_rows.copy(state, &beds_);
        particle_rows.copy(state);
        ++result_->beds_added;
      }
      key.reset();
      existing.reset();
    }
  }

  /// A bed's label in the store: a continued point's predicted start (start = predict)
  /// names the run it was predicted from, which, if this shard ran it, has another id in
  /// the store. (A run the folder's study carried has the store's id already.)
  std::string store_label(const std::string& label) const {
    static constexpr std::string_view from = " predicted from run ";
    const auto at = label.rfind(from);
    if (at == std::string::npos) return label;
    const char *first = label.data() + at + from.size(), *last = label.data() + label.size();
    std::int64_t run = 0;
    if (auto [end, error] = std::from_chars(first, last, run); error != std::errc() || end != last) return label;
    const auto merged_run = runs_.find(run);
    return merged_run == runs_.end() ? label : label.substr(0, at + from.size()) + std::to_string(merged_run->second);
  }

  /// A bed settled from the same settings in the shard and in the store must be the same
  /// bits (settling is deterministic); runs from it would otherwise be filed under a bed
  /// they did not start from.
  void check_same_bed(std::int64_t shard_state, std::int64_t store_state) {
    // The bed's own columns, then every sphere's but the bed's id.
    const std::pair<const char*, int> parts[] = {
        {"SELECT n_particles, settle_time_s, kinetic_J FROM initial_states WHERE state_id = ?", 0},
        {"SELECT * FROM initial_particles WHERE state_id = ? ORDER BY particle", 1}};
    for (const auto& [sql, first_column] : parts) {
      sqlite::Statement a(shard_->db(), sql), b(*store_, sql);
      a.bind(1, shard_state);
      b.bind(1, store_state);
      for (;;) {
        const bool more_a = a.step(), more_b = b.step();
        if (!more_a && !more_b) break;
        bool same = more_a == more_b;
        for (int c = first_column; same && c < a.column_count(); ++c) same = a.same_value(c, b, c);
        if (!same) {
          throw InputError("shard " + quoted(shard_->file()) + ": its settled bed differs from the store's bed " +
                           std::to_string(store_state) +
                           " of the same settings (settling is deterministic: the two were settled by different "
                           "builds of pdamp); nothing was added from it");
        }
      }
    }
  }

  void update_point(int point, int attempts_before, std::optional<std::int64_t> comparison_id) {
    sqlite::Statement theirs(shard_->db(),
                             "SELECT status, attempt, message, started_at, ended_at FROM study_points WHERE point = ?");
    theirs.bind(1, point);
    theirs.step();
    sqlite::Statement update(*store_,
                             "UPDATE study_points SET status = ?, attempt = ?, message = ?, started_at = ?, "
                             "ended_at = ?, comparison_id = ?, lease_host = NULL, lease_pid = NULL, lease_start = NULL "
                             "WHERE study_id = ? AND point = ?");
    update.bind_column(1, theirs, 0).bind(2, attempts_before + static_cast<int>(theirs.column_int(1)));
    update.bind_column(3, theirs, 2).bind_column(4, theirs, 3).bind_column(5, theirs, 4);
    update.bind(6, comparison_id).bind(7, study_id_).bind(8, point).run();
  }

  /// The task's row as the shard tells, marked collected.
  void record_task() {
    const StudyTask& t = result_->task;
    sqlite::Statement upsert(
        *store_,
        "INSERT INTO study_tasks (study_id, job_id, task, point, host, started_at, ended_at, outcome, message, "
        "shard_file, collected_at) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, "
        "strftime('%Y-%m-%dT%H:%M:%fZ', 'now')) ON CONFLICT (study_id, job_id, task) DO UPDATE SET "
        "host = ?5, started_at = ?6, ended_at = ?7, outcome = ?8, message = ?9, shard_file = ?10, "
        "collected_at = strftime('%Y-%m-%dT%H:%M:%fZ', 'now')");
    upsert.bind(1, study_id_).bind(2, t.job_id).bind(3, t.task).bind(4, t.point).bind(5, t.host);
    upsert.bind(6, t.started_at).bind(7, t.ended_at);
    if (t.outcome) {
      upsert.bind(8, to_string(*t.outcome));
    } else {
      upsert.bind_null(8);
    }
    upsert.bind(
        9, result_->not_added.empty() ? t.message : t.message + (t.message.empty() ? "" : "; ") + result_->not_added);
    upsert.bind(10, std::filesystem::absolute(shard_->file()).string()).run();
  }

  Shard* shard_;
  sqlite::Database* store_;
  std::int64_t study_id_;
  ShardMerge* result_;
  IdMap beds_, runs_;
};

}  // namespace

StoreFileStudies read_store_studies(const std::filesystem::path& file) {
  sqlite::Database db(file, sqlite::Access::snapshot);
  return {static_cast<int>(integer(db, "PRAGMA user_version")), StudyStore(db).studies()};
}

std::span<const std::string_view> merged_tables() { return merged; }
std::span<const std::string_view> unmerged_tables() { return unmerged; }

void copy_end_states(RunStore& store, std::int64_t study_id, const std::vector<int>& points, RunStore& target) {
  sqlite::Database &from = store.database(), &to = target.database();
  const std::string this_study = "study_id = " + std::to_string(study_id);
  sqlite::write_transaction(to, [&] {
    RowCopier point_row(from, to, "study_points", "point", {}, {}, this_study);
    RowCopier end_row(from, to, "study_point_states", "point", {}, {}, this_study);
    // A start = predict point is predicted from the previous point's metrics as well.
    RowCopier metrics_row(from, to, "study_frf_metrics", "point", {}, {}, this_study);
    RowCopier run_row(from, to, "runs", "run_id", {});
    RowCopier state_row(from, to, "initial_states", "state_id", {});
    RowCopier particle_rows(from, to, "initial_particles", "state_id", {});
    std::set<std::int64_t> copied;  // beds: a run may start from another point's final state
    const auto copy_bed = [&](const sqlite::Statement& q, int column) {
      if (q.is_null(column) || !copied.insert(q.column_int(column)).second) return;
      state_row.copy(q.column_int(column));
      particle_rows.copy(q.column_int(column));
    };
    sqlite::Statement beds(from,
                           "SELECT s.run_id, s.state_id, r.initial_state_id FROM study_point_states s "
                           "JOIN runs r ON r.run_id = s.run_id WHERE s.study_id = ? AND s.point = ?");
    for (const int point : points) {
      beds.bind(1, study_id).bind(2, point);
      if (!beds.step()) {
        throw RuntimeFailure("study " + std::to_string(study_id) + " point " + std::to_string(point) +
                             " has no final state to continue from");
      }
      copy_bed(beds, 1);
      copy_bed(beds, 2);
      run_row.copy(beds.column_int(0));
      point_row.copy(point);
      end_row.copy(point);
      metrics_row.copy(point);
      beds.reset();
    }

    // An interrupted point a task starts from (from the bed, or after a completed point)
    // with the runs of its latest attempt, under attempt 0: the task's first attempt takes
    // them over and continues them from their checkpoints (merge_shard adds them then).
    StudyStore studies(from);
    const std::map<int, int> previous = studies.previous_points(study_id);
    const auto completed = [&](int p) {
      const auto state = studies.point(study_id, p);
      return state && state->status == PointStatus::completed;
    };
    sqlite::Statement runs(from,
                           "SELECT l.run_id, r.initial_state_id FROM study_point_runs l JOIN runs r USING (run_id) "
                           "JOIN study_points p ON p.study_id = l.study_id AND p.point = l.point AND "
                           "p.attempt = l.attempt WHERE l.study_id = ? AND l.point = ? ORDER BY l.run_id");
    for (const auto& p : studies.points(study_id)) {
      const auto before = previous.find(p.point);
      if (p.status != PointStatus::interrupted || (before != previous.end() && !completed(before->second))) continue;
      runs.bind(1, study_id).bind(2, p.point);
      std::vector<std::int64_t> run_ids;
      while (runs.step()) {
        copy_bed(runs, 1);
        run_ids.push_back(runs.column_int(0));
      }
      runs.reset();
      if (run_ids.empty()) continue;
      for (const std::int64_t run : run_ids) run_row.copy(run);
      for (const std::string_view table : run_tables) {
        RowCopier rows(from, to, table, "run_id", {});
        for (const std::int64_t run : run_ids) rows.copy(run);
      }
      point_row.copy(p.point);
      RowCopier(from, to, "study_point_runs", "point", {}, {},
                this_study + " AND attempt = " + std::to_string(p.attempt))
          .copy(p.point);
      for (const char* table : {"study_points", "study_point_runs"}) {
        sqlite::Statement first(to,
                                std::string("UPDATE ") + table + " SET attempt = 0 WHERE study_id = ? AND point = ?");
        first.bind(1, study_id).bind(2, p.point).run();
      }
    }
  });
}

ShardMerge merge_shard(RunStore& store, const StudyRecord& study, const std::filesystem::path& file) {
  Shard shard(file, store.database());
  shard.check_study(study);
  const StudyTask task = shard.task(study.study_id);
  ShardMerge result;
  sqlite::write_transaction(store.database(), [&] {
    result = ShardMerge();  // afresh on a retry
    result.task = task;
    Merger(shard, store.database(), study.study_id, result).run();
  });
  return result;
}

}  // namespace pdamp
