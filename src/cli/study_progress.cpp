#include "study_progress.hpp"

#include <algorithm>
#include <cmath>

namespace pdamp {
namespace {

/// Points count towards the time estimate once they have done this much work here: before,
/// start-up dominates.
constexpr double estimate_after_fraction = 0.02;

}  // namespace

StudyProgress::StudyProgress(std::ostream& out, bool terminal, std::string study, int total, int done, int jobs,
                             Progress::Clock clock)
    : progress_(out, terminal, clock),
      clock_(std::move(clock)),
      study_(std::move(study)),
      total_(total),
      done_(done),
      jobs_(jobs) {}

void StudyProgress::started(int point) { running_[point] = Running{clock_()}; }

void StudyProgress::progressed(int point, double fraction, std::string_view phase) {
  const auto it = running_.find(point);
  if (it == running_.end()) return;
  it->second.fraction = std::clamp(fraction, 0.0, 1.0);
  it->second.phase = phase;
  if (!it->second.origin) it->second.origin.emplace(clock_(), it->second.fraction);
}

void StudyProgress::ended(int point, bool completed) {
  const auto it = running_.find(point);
  if (it == running_.end()) return;
  if (completed) {
    const auto [since, from] = it->second.origin.value_or(std::pair(it->second.started, 0.0));
    completed_wall_s_ += std::chrono::duration<double>(clock_() - since).count();
    completed_work_ += 1.0 - from;
    ++done_;
  } else {
    ++not_completed_;
  }
  running_.erase(it);
}

std::string StudyProgress::time_left(int queued) const {
  double mean_s = 0.0;
  if (completed_work_ >= estimate_after_fraction) {
    mean_s = completed_wall_s_ / completed_work_;
  } else {
    // No point has finished here yet: extrapolate the running ones that have made headway.
    int estimates = 0;
    for (const auto& [point, r] : running_) {
      if (!r.origin || r.fraction - r.origin->second < estimate_after_fraction) continue;
      mean_s += std::chrono::duration<double>(clock_() - r.origin->first).count() / (r.fraction - r.origin->second);
      ++estimates;
    }
    if (estimates == 0) return "";
    mean_s /= estimates;
  }
  double points_left = queued;
  for (const auto& [point, r] : running_) points_left += 1.0 - r.fraction;
  const int parallel = std::max(1, std::min(jobs_, queued + static_cast<int>(running_.size())));
  return format_duration(std::chrono::seconds(std::llround(points_left * mean_s / parallel))) + " left";
}

std::string StudyProgress::line(int queued) const {
  std::string text = "study " + study_ + ": " + std::to_string(done_) + "/" + std::to_string(total_) + " done";
  if (not_completed_ > 0) text += ", " + std::to_string(not_completed_) + " not completed";
  if (!running_.empty()) {
    text += "; running";
    for (const auto& [point, r] : running_) {
      text += (point == running_.begin()->first ? " " : ", ") + std::to_string(point) + " (" + r.phase;
      if (r.phase != "settling" && r.phase != "starting") {
        text += " " + std::to_string(static_cast<int>(100.0 * r.fraction)) + " %";
      }
      text += ")";
    }
  }
  const std::string left = time_left(queued);
  if (!left.empty()) text += "; " + left;
  return text;
}

void StudyProgress::message(std::string_view line) { progress_.message(line); }

void StudyProgress::update(int queued) { progress_.show(line(queued)); }

void StudyProgress::finish() { progress_.end(); }

}  // namespace pdamp
