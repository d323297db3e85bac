#include "pdamp/rom/response_curve.hpp"

#include <charconv>
#include <cmath>
#include <optional>
#include <sstream>

#include "pdamp/errors.hpp"

namespace pdamp::rom {
namespace {

constexpr int most_frequencies = 100'000;

std::string text(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

bool compatible(const Solution& a, const Solution& b) {
  return a.crossing == b.crossing || a.crossing == 0 || b.crossing == 0;
}

/// Which solution of `previous` each solution of `current` continues: the order-preserving
/// matching of solutions that cross the residual the same way with the most pairs and then the
/// least total |Δ ln A| (solutions of one frequency never cross; a turning point removes or
/// adds two neighbours).
std::vector<std::optional<std::size_t>> match(const std::vector<Solution>& previous,
                                              const std::vector<Solution>& current) {
  struct Score {
    int pairs = 0;
    double cost = 0.0;
    bool better_than(const Score& o) const { return pairs != o.pairs ? pairs > o.pairs : cost < o.cost; }
  };
  enum Step : char { skip_previous, skip_current, pair };
  const std::size_t n = previous.size(), m = current.size();
  std::vector<std::vector<Score>> best(n + 1, std::vector<Score>(m + 1));
  std::vector<std::vector<Step>> step(n + 1, std::vector<Step>(m + 1, skip_previous));
  for (std::size_t j = 1; j <= m; ++j) step[0][j] = skip_current;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      best[i][j] = best[i - 1][j];
      if (best[i][j - 1].better_than(best[i][j])) {
        best[i][j] = best[i][j - 1];
        step[i][j] = skip_current;
      }
      if (compatible(previous[i - 1], current[j - 1])) {
        const Score paired{
            best[i - 1][j - 1].pairs + 1,
            best[i - 1][j - 1].cost + std::abs(std::log(current[j - 1].amplitude_m / previous[i - 1].amplitude_m))};
        if (paired.better_than(best[i][j])) {
          best[i][j] = paired;
          step[i][j] = pair;
        }
      }
    }
  }
  std::vector<std::optional<std::size_t>> continues(m);
  for (std::size_t i = n, j = m; i > 0 && j > 0;) {
    if (step[i][j] == pair)
      continues[--j] = --i;
    else if (step[i][j] == skip_current)
      --j;
    else
      --i;
  }
  return continues;
}

void join_branches(std::vector<FrequencyResponse>& points) {
  int next_branch = 1;
  for (std::size_t k = 0; k < points.size(); ++k) {
    auto& current = points[k].solutions;
    std::vector<std::optional<std::size_t>> continues(current.size());
    if (k > 0) continues = match(points[k - 1].solutions, current);
    for (std::size_t j = 0; j < current.size(); ++j) {
      current[j].branch = continues[j] ? points[k - 1].solutions[*continues[j]].branch : next_branch++;
    }
  }
}

/// The stable solution a stepped sine holds at this frequency: the one on the branch it was on,
/// else the stable solution nearest in ln A to where it was, else (at the start) the smallest.
Solution* hold(std::vector<Solution>& solutions, std::optional<int> branch, std::optional<double> amplitude_m) {
  Solution* nearest = nullptr;
  for (Solution& s : solutions) {
    if (s.stability != Stability::stable) continue;
    if (branch && s.branch == *branch) return &s;
    const auto distance = [&](const Solution& x) { return std::abs(std::log(x.amplitude_m / *amplitude_m)); };
    if (!nearest || (amplitude_m && distance(s) < distance(*nearest))) nearest = &s;
  }
  return nearest;
}

std::vector<Jump> sweep(std::vector<FrequencyResponse>& points, bool up) {
  std::vector<Jump> jumps;
  std::optional<int> branch;
  std::optional<double> amplitude_m;
  const Solution* previous = nullptr;
  double previous_hz = 0.0;
  for (std::size_t n = 0; n < points.size(); ++n) {
    FrequencyResponse& point = points[up ? n : points.size() - 1 - n];
    Solution* held = hold(point.solutions, branch, amplitude_m);
    if (held) {
      (up ? held->on_sweep_up : held->on_sweep_down) = true;
      if (previous && previous->branch != held->branch) {
        jumps.push_back({previous_hz, point.frequency_hz, previous->amplitude_m, held->amplitude_m, previous->branch,
                         held->branch});
      }
      branch = held->branch;
      amplitude_m = held->amplitude_m;
    }
    previous = held;
    previous_hz = point.frequency_hz;
  }
  return jumps;
}

}  // namespace

FrequencyRange parse_frequency_range(const std::string& text_in, Spacing spacing, const std::string& option) {
  const auto bad = [&](const std::string& why) {
    return InputError(option + " '" + text_in + "': " + why + " (write START:STOP:COUNT, e.g. 10:30:200)");
  };
  // Every field, empty ones too: "15:20:5:" has four (getline would drop the last).
  std::vector<std::string> parts;
  for (std::size_t start = 0;;) {
    const std::size_t colon = text_in.find(':', start);
    parts.push_back(text_in.substr(start, colon - start));
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  if (parts.size() != 3) throw bad("expected three fields separated by ':', not " + std::to_string(parts.size()));
  FrequencyRange range;
  range.spacing = spacing;
  double* bounds[] = {&range.start_hz, &range.stop_hz};
  for (int i = 0; i < 2; ++i) {
    const std::string& p = parts[static_cast<std::size_t>(i)];
    const auto [end, ec] = std::from_chars(p.data(), p.data() + p.size(), *bounds[i]);
    if (ec != std::errc() || end != p.data() + p.size()) throw bad("'" + p + "' is not a number of Hz");
  }
  const auto [end, ec] = std::from_chars(parts[2].data(), parts[2].data() + parts[2].size(), range.count);
  if (ec != std::errc() || end != parts[2].data() + parts[2].size()) {
    throw bad("'" + parts[2] + "' is not a whole number of frequencies");
  }
  return range;
}

std::vector<double> frequencies_of(const FrequencyRange& range) {
  if (!(std::isfinite(range.start_hz) && std::isfinite(range.stop_hz) && range.start_hz > 0 &&
        range.start_hz < range.stop_hz)) {
    throw InputError("frequency range " + text(range.start_hz) + " to " + text(range.stop_hz) +
                     " Hz: needs 0 < start < stop");
  }
  if (range.count < 2 || range.count > most_frequencies) {
    throw InputError("frequency count " + std::to_string(range.count) + ": must be 2 to " +
                     std::to_string(most_frequencies));
  }
  std::vector<double> f(static_cast<std::size_t>(range.count));
  const double last = range.count - 1;
  for (std::size_t k = 0; k < f.size(); ++k) {
    const double x = static_cast<double>(k) / last;
    f[k] = range.spacing == Spacing::linear ? range.start_hz + x * (range.stop_hz - range.start_hz)
                                            : range.start_hz * std::exp(x * std::log(range.stop_hz / range.start_hz));
  }
  f.back() = range.stop_hz;
  return f;
}

ResponseCurve predict_response(const TableInterpolator& table, const HostSdof& host, const Excitation& excitation,
                               const std::vector<double>& frequencies_hz) {
  validate_host(host, excitation);
  for (const double f : frequencies_hz) {
    if (!(f >= table.lowest_frequency_hz() && f <= table.highest_frequency_hz())) {
      throw InputError("frequency " + text(f) + " Hz is outside the table's frequencies, " +
                       text(table.lowest_frequency_hz()) + " to " + text(table.highest_frequency_hz()) +
                       " Hz: the model does not extrapolate; choose frequencies within them");
    }
  }
  ResponseCurve curve;
  for (const double f : frequencies_hz) curve.points.push_back(solve_frequency(table.profile(f), host, excitation));
  join_branches(curve.points);
  curve.jumps_up = sweep(curve.points, true);
  curve.jumps_down = sweep(curve.points, false);
  return curve;
}

bool covers_something(const ResponseCurve& curve) {
  for (const auto& p : curve.points) {
    if (!p.solutions.empty()) return true;
  }
  return false;
}

std::string coverage_summary(const ResponseCurve& curve) {
  int below = 0, above = 0, uncovered = 0;
  double lowest = HUGE_VAL, highest = 0.0;
  for (const auto& p : curve.points) {
    below += p.solution_below;
    above += p.solution_above;
    uncovered += p.not_covered;
    if (!p.not_covered) {
      lowest = std::min(lowest, p.lowest_amplitude_m);
      highest = std::max(highest, p.highest_amplitude_m);
    }
  }
  const std::string of = " of " + std::to_string(curve.points.size()) + " frequencies";
  std::ostringstream out;
  out << "no frequency has a response inside the characterised amplitudes";
  if (below) out << "; at " << below << of << " a response lies below them (smallest " << text(lowest) << " m)";
  if (above) out << "; at " << above << of << " a response lies above them (largest " << text(highest) << " m)";
  if (uncovered) out << "; at " << uncovered << of << " the neighbouring frequency columns share no value of Gamma";
  return out.str();
}

}  // namespace pdamp::rom
