#pragma once
/// Progress of the long phases (settling a bed, running a model) on stderr. On a terminal
/// one line is redrawn in place, with the percentage and the time left when the phase's
/// end is known; in a log (not a terminal) a line every log_interval. Warnings and notes
/// go through it too, so that they never land inside the progress line.

#include <chrono>
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>

namespace pdamp {

class Progress {
 public:
  using Clock = std::function<std::chrono::steady_clock::time_point()>;
  static constexpr std::chrono::seconds log_interval{30};
  static constexpr std::chrono::milliseconds redraw_interval{250};

  /// `terminal`: whether `out` is one.
  Progress(std::ostream& out, bool terminal, Clock clock = &std::chrono::steady_clock::now);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// A new phase, e.g. "soft model", lasting `total_s` of simulated time (none: unknown).
  void begin(std::string phase, std::optional<double> total_s = std::nullopt);
  /// The phase has reached simulated time `t_s`; `detail` follows it on the line.
  void update(double t_s, std::string_view detail = {});
  /// Shows `status` as the progress line, as update() would its own (for progress that is
  /// not simulated time, such as a study's points).
  void show(std::string_view status);
  /// A line of its own, e.g. "pdamp: warning: ...".
  void message(std::string_view line);
  /// Ends the phase: its last progress line stays, and what follows starts on a new line.
  void end();

 private:
  std::string status(double t_s, std::string_view detail, std::chrono::steady_clock::time_point now) const;
  /// Whether a line is due at `now` (a redraw interval on a terminal, a log interval
  /// otherwise, since the last); if so, counts it as shown.
  bool due(std::chrono::steady_clock::time_point now);
  void draw(std::string_view status);
  void clear_line();

  std::ostream& out_;
  bool terminal_;
  Clock clock_;
  std::string phase_;
  std::optional<double> total_s_;
  std::chrono::steady_clock::time_point last_shown_;
  /// The phase's first update, from which the time left is estimated.
  std::optional<std::pair<std::chrono::steady_clock::time_point, double>> origin_;
  std::string line_;  ///< the progress line on the terminal now, if any
};

/// "45 s", "3 min 05 s", "2 h 10 min".
std::string format_duration(std::chrono::seconds duration);

}  // namespace pdamp
