#include "progress.hpp"

#include <cmath>
#include <cstdio>

namespace pdamp {
namespace {

/// Erases from the cursor to the end of the terminal line (ANSI "EL").
constexpr std::string_view erase_to_end = "\033[K";

/// Time left is shown once the phase has run this long: earlier it is mostly start-up.
constexpr std::chrono::seconds estimate_after{2};

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

}  // namespace

std::string format_duration(std::chrono::seconds duration) {
  const auto s = duration.count();
  auto two_digits = [](long long v) { return (v < 10 ? "0" : "") + std::to_string(v); };
  if (s < 60) return std::to_string(s) + " s";
  if (s < 3600) return std::to_string(s / 60) + " min " + two_digits(s % 60) + " s";
  return std::to_string(s / 3600) + " h " + two_digits(s / 60 % 60) + " min";
}

Progress::Progress(std::ostream& out, bool terminal, Clock clock)
    : out_(out), terminal_(terminal), clock_(std::move(clock)) {}

Progress::~Progress() { end(); }

void Progress::begin(std::string phase, std::optional<double> total_s) {
  end();
  phase_ = std::move(phase);
  total_s_ = total_s;
  last_shown_ = clock_();
  origin_.reset();
}

std::string Progress::status(double t_s, std::string_view detail, std::chrono::steady_clock::time_point now) const {
  std::string text = phase_ + ": t = " + fixed(t_s, 4);
  if (total_s_ && *total_s_ > 0) {
    text += " of " + fixed(*total_s_, 4) + " s, " + fixed(100.0 * t_s / *total_s_, 1) + " %";
    if (origin_ && now - origin_->first >= estimate_after && t_s > origin_->second) {
      const double wall_s = std::chrono::duration<double>(now - origin_->first).count();
      const double left_s = wall_s * (*total_s_ - t_s) / (t_s - origin_->second);
      text += ", " + format_duration(std::chrono::seconds(std::llround(std::max(left_s, 0.0)))) + " left";
    }
  } else {
    text += " s";
  }
  if (!detail.empty()) text += ", " + std::string(detail);
  return text;
}

void Progress::update(double t_s, std::string_view detail) {
  const auto now = clock_();
  if (!origin_) origin_.emplace(now, t_s);
  if (due(now)) draw(status(t_s, detail, now));
}

void Progress::show(std::string_view status) {
  if (due(clock_())) draw(status);
}

bool Progress::due(std::chrono::steady_clock::time_point now) {
  const std::chrono::steady_clock::duration interval =
      terminal_ ? std::chrono::steady_clock::duration(redraw_interval) : log_interval;
  if (now - last_shown_ < interval) return false;
  last_shown_ = now;
  return true;
}

void Progress::draw(std::string_view status) {
  if (terminal_) {
    line_ = "  " + std::string(status);
    out_ << '\r' << line_ << erase_to_end << std::flush;
  } else {
    out_ << "pdamp: " << status << '\n' << std::flush;
  }
}

void Progress::clear_line() {
  if (!line_.empty()) out_ << '\r' << erase_to_end;
}

void Progress::message(std::string_view line) {
  clear_line();
  out_ << line << '\n';
  if (!line_.empty()) out_ << line_;
  out_ << std::flush;
}

void Progress::end() {
  if (!line_.empty()) out_ << '\n' << std::flush;
  line_.clear();
}

}  // namespace pdamp
