/// The grammar of a sweep key's values (study_file.hpp): a comma-separated list whose
/// items are values or ranges `start:stop:count[:lin|log]`.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/study/study_file.hpp"

namespace pdamp::study {
namespace {

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t") - first + 1);
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string::size_type start = 0;
  for (auto at = text.find(separator); at != std::string::npos; at = text.find(separator, start)) {
    parts.push_back(trim(text.substr(start, at - start)));
    start = at + 1;
  }
  parts.push_back(trim(text.substr(start)));
  return parts;
}

class RangeParser {
 public:
  RangeParser(const std::string& item, const std::string& what) : item_(item), what_(what) {}

  std::vector<std::string> values() const {
    const auto fields = split(item_, ':');
    if (fields.size() != 3 && fields.size() != 4) fail("a range is start:stop:count or start:stop:count:log");
    const double start = number(fields[0], "start"), stop = number(fields[1], "stop");
    const long count = whole(fields[2]);
    const bool log = fields.size() == 4 && spacing(fields[3]);
    if (start == stop) fail("the range is empty (start = stop); give a single value without ':' for one point");
    if (start > stop) fail("the range is reversed (start > stop): a range runs from the smaller value up");
    if (log && start <= 0.0) fail("a log range needs start > 0");
    std::vector<std::string> values{fields[0]};
    for (long i = 1; i + 1 < count; ++i) {
      const double f = static_cast<double>(i) / static_cast<double>(count - 1);
      const double x =
          log ? std::exp(std::log(start) + f * (std::log(stop) - std::log(start))) : start + f * (stop - start);
      char text[32];
      std::snprintf(text, sizeof text, "%.15g", x);
      values.emplace_back(text);
    }
    values.push_back(fields[1]);
    return values;
  }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    throw InputError(what_ + ": '" + item_ + "': " + why + "; e.g. 0.001:0.01:10 or 1e-4:1e-2:5:log");
  }

  double number(const std::string& text, const char* name) const {
    double x = 0.0;
    const char* end = text.data() + text.size();
    if (auto [ptr, ec] = std::from_chars(text.data(), end, x); ec != std::errc() || ptr != end || !std::isfinite(x)) {
      fail(std::string("the ") + name + " '" + text + "' is not a finite number");
    }
    return x;
  }

  long whole(const std::string& text) const {
    long count = 0;
    const char* end = text.data() + text.size();
    if (auto [ptr, ec] = std::from_chars(text.data(), end, count); ec != std::errc() || ptr != end) {
      fail("the count '" + text + "' is not a whole number");
    }
    if (count < 2) fail("the count must be at least 2 (a range of " + text + " values has no step)");
    if (count > max_range_count) fail("the count must be at most " + std::to_string(max_range_count));
    return count;
  }

  bool spacing(const std::string& text) const {
    if (text == "log") return true;
    if (text != "lin") fail("the spacing '" + text + "' must be lin (the default) or log");
    return false;
  }

  std::string item_, what_;
};

}  // namespace

std::vector<std::string> parse_sweep_values(const std::string& text, const std::string& what) {
  if (trim(text).empty()) {
    throw InputError(what + " has no values: give a value, a list 'a, b, c' or a range start:stop:count");
  }
  std::vector<std::string> values;
  for (const auto& item : split(text, ',')) {
    if (item.empty()) throw InputError(what + " = '" + text + "': an empty value in the list (two commas in a row?)");
    if (item.find(':') == std::string::npos) {
      values.push_back(item);
      continue;
    }
    for (auto& v : RangeParser(item, what).values()) values.push_back(std::move(v));
    if (values.size() > static_cast<std::size_t>(max_range_count)) {
      throw InputError(what + " has more than " + std::to_string(max_range_count) + " values");
    }
  }
  return values;
}

}  // namespace pdamp::study
