#include "pdamp/model/scenario_loader.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <ostream>
#include <set>
#include <span>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include "pdamp/errors.hpp"
#include "pdamp/input_file.hpp"
#include "pdamp/model/cell_grid.hpp"
#include "pdamp/model/host.hpp"
#include "pdamp/model/placement.hpp"
#include "pdamp/scenario/ini.hpp"

namespace pdamp {

double ExcitationSettings::angular_frequency_rad_s() const { return 2.0 * std::numbers::pi * frequency_hz; }

namespace {

/// Where a value came from and what it is, for error messages.
struct Value {
  std::string key;
  std::string text;
  std::string origin;  ///< "file.ini, line 3", "--set host.z0_m" or "default"
};

using ini::printable;

[[noreturn]] void reject(const Value& v, const std::string& why) {
  throw InputError(v.origin + ": " + v.key + " = '" + printable(v.text) + "': " + why);
}

/// For a problem of two values together.
[[noreturn]] void reject(const Value& a, const Value& b, const std::string& why) {
  throw InputError(a.origin + ": " + a.key + " = '" + printable(a.text) + "' and " + b.key + " = '" +
                   printable(b.text) + "'" + (b.origin == a.origin ? "" : " (" + b.origin + ")") + ": " + why);
}

std::vector<std::string> split_words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

/// `word` without a '+' before its digits, which from_chars does not take (it takes '-'
/// there, and either sign before an exponent). "+", "++1" and "+-1" stay as they are, refused.
std::string_view without_plus(std::string_view word) {
  if (word.size() > 1 && word[0] == '+' && (std::isdigit(static_cast<unsigned char>(word[1])) || word[1] == '.')) {
    word.remove_prefix(1);
  }
  return word;
}

/// `word` as a finite number, if it is one as people write it.
std::optional<double> finite_number(std::string_view word) {
  word = without_plus(word);
  double x = 0.0;
  const char* end = word.data() + word.size();
  const auto [ptr, ec] = std::from_chars(word.data(), end, x);
  if (ec != std::errc() || ptr != end || !std::isfinite(x)) return std::nullopt;
  return x;
}

double parse_number(const Value& v, const std::string& word) {
  const std::optional<double> x = finite_number(word);
  if (!x) reject(v, "'" + printable(word) + "' is not a finite number (write e.g. 0.0157, +2 or 1.5e-3)");
  return *x;
}

/// A numeric range and the words that explain it.
struct Range {
  double min;
  double max;
  bool min_inclusive;
  const char* text;
};
constexpr double inf = std::numeric_limits<double>::infinity();
constexpr Range positive{0.0, inf, false, "must be > 0"};
constexpr Range non_negative{0.0, inf, true, "must be >= 0"};
constexpr Range any_number{-inf, inf, true, "any finite number"};
constexpr Range unit_interval{0.0, 1.0, true, "must be in [0, 1]"};
constexpr Range signed_unit_interval{-1.0, 1.0, true, "must be in [-1, 1]"};

double parse_in_range(const Value& v, const Range& r) {
  const auto words = split_words(v.text);
  if (words.size() != 1) reject(v, "expected one number; " + std::string(r.text));
  const double x = parse_number(v, words[0]);
  const bool above_min = r.min_inclusive ? x >= r.min : x > r.min;
  if (!above_min || x > r.max) reject(v, r.text);
  return x;
}

/// A default value as `pdamp keys` prints it and a scenario file would write it.
std::string text(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

/// A bound on work: a power of ten as 1eN, as one writes it.
std::string work_limit_text(std::int64_t n) {
  int exponent = 0;
  std::int64_t rest = n;
  while (rest >= 10 && rest % 10 == 0) {
    rest /= 10;
    ++exponent;
  }
  return rest == 1 && exponent > 0 ? "1e" + std::to_string(exponent) : std::to_string(n);
}

/// The words a key of named choices accepts, in the order messages list them. Constant
/// tables: key_specs() may first run while other files' statics are initialised.
template <class Choice>
using Names = std::span<const std::pair<std::string_view, Choice>>;

template <class Choice>
Choice parse_choice(const Value& v, const Names<Choice>& names) {
  const auto it = std::find_if(names.begin(), names.end(), [&](const auto& entry) { return entry.first == v.text; });
  if (it != names.end()) return it->second;
  std::string valid;
  for (const auto& [name, choice] : names) {
    if (!valid.empty()) valid += ", ";
    valid += name;
  }
  reject(v, "must be one of " + valid);
}

template <class Choice>
std::string name_of(Choice choice, const Names<Choice>& names) {
  return std::string(
      std::find_if(names.begin(), names.end(), [&](const auto& entry) { return entry.second == choice; })->first);
}

constexpr std::array<std::pair<std::string_view, ExcitationMode>, 4> excitation_modes{
    {{"free", ExcitationMode::free_decay},
     {"base", ExcitationMode::base_motion},
     {"force", ExcitationMode::force},
     {"prescribed", ExcitationMode::prescribed_motion}}};
constexpr std::array<std::pair<std::string_view, HardRestitution>, 2> restitutions{
    {{"constant", HardRestitution::constant}, {"calibrated", HardRestitution::calibrated}}};

using Apply = std::function<void(Scenario&, const Value&)>;

/// One scenario key: its name (section.key), default text, unit and meaning. A key
/// whose default is another key's value names it in `inherits`.
struct KeySpec {
  std::string key;
  std::string default_text;
  std::string unit;
  std::string help;
  Apply apply;
  std::string inherits;
};

/// A whole number from `min` to `max`, written as digits or in exponent notation (1e9).
std::int64_t parse_whole(const Value& v, std::int64_t min, std::int64_t max) {
  const double x = parse_in_range(v, any_number);
  if (x != std::floor(x) || x < static_cast<double>(min) || x > static_cast<double>(max)) {
    reject(v, "must be a whole number from " + std::to_string(min) + " to " + std::to_string(max));
  }
  return static_cast<std::int64_t>(x);
}

/// The largest bound a run's work may be given: 2^53, where doubles still count in ones.
constexpr std::int64_t max_work_limit = std::int64_t{1} << 53;

Apply whole(std::int64_t RunSettings::*field, std::int64_t max) {
  return [field, max](Scenario& s, const Value& v) { s.run.*field = parse_whole(v, 1, max); };
}

Apply number(double& (*field)(Scenario&), Range range) {
  return [field, range](Scenario& s, const Value& v) { field(s) = parse_in_range(v, range); };
}

// NOLINTNEXTLINE(bugprone-macro-parentheses): expr is a member path; s.(expr) would not compile
#define PDAMP_FIELD(expr) [](Scenario& s) -> double& { return s.expr; }

std::vector<KeySpec> soft_law_keys(const std::string& section, SoftContactLaw Scenario::*law,
                                   const std::string& inherit_section) {
  auto field = [law](double SoftContactLaw::*member, Range range) -> Apply {
    return [law, member, range](Scenario& s, const Value& v) { s.*law.*member = parse_in_range(v, range); };
  };
  auto inherit = [&](const std::string& key) { return inherit_section.empty() ? "" : inherit_section + "." + key; };
  const SoftContactLaw d = Scenario{}.*law;
  const std::string who = inherit_section.empty() ? "sphere-sphere" : "sphere-wall";
  return {
      {section + ".kn_N_m1_5", text(d.kn_N_m1_5), "N/m^1.5", "Hertz normal stiffness k_n (" + who + ")",
       field(&SoftContactLaw::kn_N_m1_5, positive), inherit("kn_N_m1_5")},
      {section + ".cn_N_s_m", text(d.cn_N_s_m), "N s/m", "normal dashpot c_n (" + who + ")",
       field(&SoftContactLaw::cn_N_s_m, non_negative), inherit("cn_N_s_m")},
      {section + ".ks_N_m", text(d.ks_N_m), "N/m", "tangential spring k_s (" + who + ")",
       field(&SoftContactLaw::ks_N_m, non_negative), inherit("ks_N_m")},
      {section + ".cs_N_s_m", text(d.cs_N_s_m), "N s/m", "tangential dashpot c_s (" + who + ")",
       field(&SoftContactLaw::cs_N_s_m, non_negative), inherit("cs_N_s_m")},
      {section + ".mu", text(d.mu), "1", "Coulomb friction coefficient (" + who + ")",
       field(&SoftContactLaw::mu, non_negative), inherit("mu")},
  };
}

std::vector<KeySpec> hard_law_keys(const std::string& section, HardContactLaw Scenario::*law,
                                   const std::string& inherit_section) {
  auto field = [law](double HardContactLaw::*member, Range range) -> Apply {
    return [law, member, range](Scenario& s, const Value& v) { s.*law.*member = parse_in_range(v, range); };
  };
  auto inherit = [&](const std::string& key) { return inherit_section.empty() ? "" : inherit_section + "." + key; };
  const HardContactLaw d = Scenario{}.*law;
  const std::string who = inherit_section.empty() ? "sphere-sphere" : "sphere-wall";
  return {
      {section + ".en", text(d.en), "1", "normal restitution coefficient e_n (" + who + ")",
       field(&HardContactLaw::en, unit_interval), ""},
      {section + ".mu", text(d.mu), "1", "Coulomb friction coefficient (" + who + ")",
       field(&HardContactLaw::mu, non_negative), inherit("mu")},
      {section + ".beta0", text(d.beta0), "1", "tangential restitution of sticking collisions (" + who + ")",
       field(&HardContactLaw::beta0, signed_unit_interval), inherit("beta0")},
  };
}

/// Gravity as `gravity.g_m_s2` takes it: the downward magnitude, or the vector.
std::string gravity_text(const Eigen::Vector3d& g) {
  if (g.x() == 0.0 && g.y() == 0.0 && g.z() <= 0.0) return text(-g.z());
  return text(g.x()) + " " + text(g.y()) + " " + text(g.z());
}

/// The diameter as `particles.diameter_m` takes it: one, or 'dmin dmax'.
std::string diameter_text(const ParticleSettings& p) {
  return p.diameter_min_m == p.diameter_max_m ? text(p.diameter_min_m)
                                              : text(p.diameter_min_m) + " " + text(p.diameter_max_m);
}

/// Every key; the defaults are those of a default-constructed `Scenario`.
const std::vector<KeySpec>& key_specs() {
  static const std::vector<KeySpec> specs = [] {
    const Scenario d;
    std::vector<KeySpec> k{
        {"scenario.name", "", "", "name stored with each run (default: the file name without extension)",
         [](Scenario& s, const Value& v) {
           if (!v.text.empty()) s.name = v.text;
         },
         ""},
        {"host.mass_kg", text(d.host.mass_kg), "kg",
         "host mass M (for prescribed motion: the nominal mass used in psi)",
         number(PDAMP_FIELD(host.mass_kg), positive), ""},
        {"host.stiffness_N_m", text(d.host.stiffness_N_m), "N/m", "host spring K",
         number(PDAMP_FIELD(host.stiffness_N_m), positive), ""},
        {"host.damping_N_s_m", text(d.host.damping_N_s_m), "N s/m", "host viscous damper C",
         number(PDAMP_FIELD(host.damping_N_s_m), non_negative), ""},
        {"host.z0_m", text(d.host.z0_m), "m", "initial host displacement from its static equilibrium",
         number(PDAMP_FIELD(host.z0_m), any_number), ""},
        {"host.v0_m_s", text(d.host.v0_m_s), "m/s", "initial host velocity",
         number(PDAMP_FIELD(host.v0_m_s), any_number), ""},
        {"excitation.mode", name_of<ExcitationMode>(d.excitation.mode, excitation_modes), "",
         "free (decay) | base (base motion y = A sin(wt+phi) through K and C) | force (F0 sin(wt+phi) on the "
         "host) | prescribed (host moves as z = A sin(wt+phi), infinite mass)",
         [](Scenario& s, const Value& v) { s.excitation.mode = parse_choice<ExcitationMode>(v, excitation_modes); },
         ""},
        {"excitation.amplitude_m", text(d.excitation.amplitude_m), "m",
         "motion amplitude A (base and prescribed modes)", number(PDAMP_FIELD(excitation.amplitude_m), non_negative),
         ""},
        {"excitation.force_N", text(d.excitation.force_N), "N", "force amplitude F0 (force mode)",
         number(PDAMP_FIELD(excitation.force_N), non_negative), ""},
        {"excitation.frequency_hz", text(d.excitation.frequency_hz), "Hz", "excitation frequency f (w = 2 pi f)",
         number(PDAMP_FIELD(excitation.frequency_hz), non_negative), ""},
        {"excitation.phase_rad", text(d.excitation.phase_rad), "rad", "excitation phase phi",
         number(PDAMP_FIELD(excitation.phase_rad), any_number), ""},
        {"cavity.diameter_m", text(d.cavity.diameter_m), "m", "cylinder diameter D",
         number(PDAMP_FIELD(cavity.diameter_m), positive), ""},
        {"cavity.height_m", text(d.cavity.height_m), "m", "cylinder height H",
         number(PDAMP_FIELD(cavity.height_m), positive), ""},
        {"gravity.g_m_s2", gravity_text(d.gravity_m_s2), "m/s^2",
         "one number: magnitude of gravity pointing down (-z), 0 for microgravity; three numbers: the vector",
         [](Scenario& s, const Value& v) {
           const auto words = split_words(v.text);
           if (words.size() == 1) {
             const double g = parse_number(v, words[0]);
             if (g < 0)
               reject(
                   v,
                   "a single number is the downward magnitude and must be >= 0; give 'gx gy gz' for another direction");
             s.gravity_m_s2 = {0.0, 0.0, -g};
           } else if (words.size() == 3) {
             s.gravity_m_s2 = {parse_number(v, words[0]), parse_number(v, words[1]), parse_number(v, words[2])};
           } else {
             reject(v, "expected one number (downward magnitude) or three (gx gy gz)");
           }
         },
         ""},
        {"particles.count", std::to_string(d.particles.count), "", "number of spheres n (0 runs the host alone)",
         [](Scenario& s, const Value& v) {
           s.particles.count = static_cast<int>(parse_whole(v, 0, max_particle_count));
         },
         ""},
        {"particles.diameter_m", diameter_text(d.particles), "m",
         "sphere diameter d, or 'dmin dmax' for diameters uniform in a range",
         [](Scenario& s, const Value& v) {
           const auto words = split_words(v.text);
           if (words.empty() || words.size() > 2) reject(v, "expected one diameter or two ('dmin dmax')");
           const double lo = parse_number(v, words.front());
           const double hi = parse_number(v, words.back());
           if (!(lo > 0) || hi < lo) reject(v, "diameters must be > 0, and dmin <= dmax");
           s.particles.diameter_min_m = lo;
           s.particles.diameter_max_m = hi;
         },
         ""},
        {"particles.density_kg_m3", text(d.particles.density_kg_m3), "kg/m^3", "sphere material density",
         number(PDAMP_FIELD(particles.density_kg_m3), positive), ""},
        {"particles.seed", std::to_string(d.particles.seed), "",
         "random seed of the initial placement (unsigned 64-bit)",
         [](Scenario& s, const Value& v) {
           std::uint64_t seed = 0;
           const std::string_view digits = without_plus(v.text);
           const char* end = digits.data() + digits.size();
           auto [ptr, ec] = std::from_chars(digits.data(), end, seed);
           if (ec != std::errc() || ptr != end) reject(v, "must be a whole number from 0 to 18446744073709551615");
           s.particles.seed = seed;
         },
         ""},
        {"run.duration_s", text(d.run.duration_s), "s", "simulated time", number(PDAMP_FIELD(run.duration_s), positive),
         ""},
        {"run.sample_interval_s", text(d.run.sample_interval_s), "s", "interval between stored samples",
         number(PDAMP_FIELD(run.sample_interval_s), positive), ""},
        {"run.dt_s", d.run.dt_s ? text(*d.run.dt_s) : "auto", "s",
         "soft engine time step, or 'auto' (from the Hertz contact time)",
         [](Scenario& s, const Value& v) {
           constexpr Range time_step{0.0, inf, false, "must be 'auto' or a time step > 0 in seconds"};
           const auto words = split_words(v.text);
           if (v.text == "auto") {
             s.run.dt_s.reset();
             return;
           }
           if (words.size() != 1 || !finite_number(words[0])) reject(v, time_step.text);
           s.run.dt_s = parse_in_range(v, time_step);
         },
         ""},
        {"run.max_steps", work_limit_text(d.run.max_steps), "",
         "the most steps a run may take: the soft engine's time steps (the run's, and settling's up to its 5 s "
         "limit) and the run loop's observations (either model); a scenario that needs more is refused",
         whole(&RunSettings::max_steps, max_work_limit), ""},
        {"run.max_samples", work_limit_text(d.run.max_samples), "",
         "the most samples a run may store; a scenario that needs more is refused",
         whole(&RunSettings::max_samples, max_work_limit), ""},
        {"run.max_events", work_limit_text(d.run.max_events), "",
         "the most events the hard engine may handle; a run that reaches it fails",
         whole(&RunSettings::max_events, max_work_limit), ""},
    };
    for (auto& spec : soft_law_keys("soft", &Scenario::soft_particle, "")) k.push_back(spec);
    for (auto& spec : soft_law_keys("soft_wall", &Scenario::soft_wall, "soft")) k.push_back(spec);
    for (auto& spec : hard_law_keys("hard", &Scenario::hard_particle, "")) k.push_back(spec);
    k.push_back(
        {"hard.restitution", name_of<HardRestitution>(d.hard_restitution, restitutions), "",
         "constant (en and beta0 as given) | calibrated (e_n(v) and beta0(v) of the soft law, from "
         "isolated soft collisions at the impact speed)",
         [](Scenario& s, const Value& v) { s.hard_restitution = parse_choice<HardRestitution>(v, restitutions); }, ""});
    // The hard engine's resting-bed parameters (docs/hard-engine.md, "Resting beds and inelastic collapse").
    k.push_back({"hard.rest_speed_m_s", text(d.hard_resting.rest_speed_m_s), "m/s",
                 "a sphere leaving the floor, top cap or a resting sphere slower than this (relative to the host) "
                 "while the host's acceleration presses it there comes to rest and rides with the host (taken as at "
                 "least elastic_speed_m_s, below which it would bounce without end; 0: only rest_tc_window rests)",
                 number(PDAMP_FIELD(hard_resting.rest_speed_m_s), non_negative), ""});
    k.push_back({"hard.rest_tc_window", text(d.hard_resting.rest_tc_window), "t_c",
                 "a sphere that would land again on its support within this many soft contact times (Hertz, at "
                 "its leaving speed, under the host's pressing acceleration) comes to rest too, and a rider hit "
                 "that slowly stays on the bed; 0 = off (only rest_speed_m_s)",
                 number(PDAMP_FIELD(hard_resting.rest_tc_window), non_negative), ""});
    k.push_back({"hard.elastic_speed_m_s", text(d.hard_resting.elastic_speed_m_s), "m/s",
                 "collisions with a normal approach speed below this are elastic (stops inelastic collapse)",
                 number(PDAMP_FIELD(hard_resting.elastic_speed_m_s), non_negative), ""});
    k.push_back({"hard.side_wall_elastic_speed_m_s", text(d.hard_resting.side_wall_elastic_speed_m_s), "m/s",
                 "the same for collisions with the side wall, on its own (a loose bed's friction against the wall "
                 "needs the wall's inelastic law)",
                 number(PDAMP_FIELD(hard_resting.side_wall_elastic_speed_m_s), non_negative), ""});
    k.push_back({"hard.tc_window", text(d.hard_resting.tc_window), "t_c",
                 "TC model: a collision within this many soft contact times (Hertz, at its approach speed) of an "
                 "earlier collision of a sphere it involves is elastic in the normal direction; 0 = off",
                 number(PDAMP_FIELD(hard_resting.tc_window), non_negative), ""});
    k.push_back({"hard.cluster_speed_m_s", text(d.hard_resting.cluster_speed_m_s), "m/s",
                 "rigid clusters: a collision of two free spheres approaching slower than this merges them (and their "
                 "clusters) into one rigid body, which a sphere leaves when anything else changes its motion; 0 = off",
                 number(PDAMP_FIELD(hard_resting.cluster_speed_m_s), non_negative), ""});
    for (auto& spec : hard_law_keys("hard_wall", &Scenario::hard_wall, "hard")) k.push_back(spec);
    return k;
  }();
  return specs;
}

#undef PDAMP_FIELD

/// Parsed text of every key, remembering which keys the user set and where.
struct RawScenario {
  std::map<std::string, Value> given;
};

const KeySpec* find_key(std::string_view key) {
  const auto it = std::find_if(key_specs().begin(), key_specs().end(), [&](const KeySpec& k) { return k.key == key; });
  return it == key_specs().end() ? nullptr : &*it;
}

void require_known_key(const std::string& key, const std::string& where) {
  if (!find_key(key)) {
    throw InputError(where + ": unknown key '" + printable(key) + "' (run 'pdamp keys' for the list of valid keys)");
  }
}

/// Scenario-file syntax (ini.hpp): a key is section.key under a header, or written in
/// full before any. Keys the file repeats are refused.
void parse_file_text(RawScenario& raw, std::string_view text, const std::string& origin) {
  std::set<std::string> seen;
  for (const ini::Entry& entry : ini::parse(text, origin).entries) {
    const std::string key = entry.section.empty() ? entry.key : entry.section + "." + entry.key;
    require_known_key(key, entry.where);
    if (!seen.insert(key).second) throw InputError(entry.where + ": key '" + key + "' is given more than once");
    // The overrides are parsed first and win over the file.
    raw.given.try_emplace(key, Value{key, entry.value, entry.where});
  }
}

/// `--set section.key=value` (or the values a study sets, named by `origin`), each one
/// line; a key set again replaces the earlier value (the last on the command line wins).
void parse_overrides(RawScenario& raw, const ScenarioOverrides& overrides, const std::string& origin) {
  for (const auto& item : overrides) {
    const std::string where = origin + " '" + printable(item) + "'";
    if (item.find_first_of(std::string_view("\n\r\0", 3)) != std::string::npos) {
      throw InputError(where + ": a " + origin +
                       " is one section.key=value, without line breaks; give each key its own " + origin);
    }
    const auto eq = item.find('=');
    const auto dot = item.find('.');
    if (eq == std::string::npos || dot == std::string::npos || dot > eq) {
      throw InputError(where + ": expected section.key=value, e.g. " + origin + " host.z0_m=0.01");
    }
    const std::string key(ini::trim(std::string_view(item).substr(0, eq)));
    require_known_key(key, origin + " " + printable(key));
    const std::string value(ini::trim(std::string_view(item).substr(eq + 1)));
    if (value.find('#') != std::string::npos) throw InputError(where + ": " + ini::no_hash_in_values);
    raw.given.insert_or_assign(key, Value{key, value, origin + " " + key});
  }
}

/// The value of `key` as given, or its default.
Value value_of(const RawScenario& raw, const std::string& key) {
  const auto it = raw.given.find(key);
  return it != raw.given.end() ? it->second : Value{key, find_key(key)->default_text, "default"};
}

/// True if a numeric key was given a value other than its default.
bool differs_from_default(const RawScenario& raw, const std::string& key) {
  const auto it = raw.given.find(key);
  if (it == raw.given.end()) return false;
  return parse_number(it->second, it->second.text) != parse_number(it->second, find_key(key)->default_text);
}

/// Keys that the chosen excitation mode ignores must keep their defaults: a value that
/// would be silently ignored is a wrong answer waiting to happen.
void check_excitation(const Scenario& s, const RawScenario& raw) {
  const auto& e = s.excitation;
  auto forbid = [&](const std::string& key, const std::string& why) {
    if (differs_from_default(raw, key)) reject(raw.given.at(key), why);
  };
  auto require_positive = [&](const std::string& key, double value, const std::string& why) {
    if (value <= 0) reject(value_of(raw, key), why);
  };
  const std::string mode = raw.given.contains("excitation.mode") ? raw.given.at("excitation.mode").text : "free";
  const std::string in_mode = " is not used by excitation.mode = " + mode;
  switch (e.mode) {
    case ExcitationMode::free_decay:
      for (const char* key :
           {"excitation.amplitude_m", "excitation.force_N", "excitation.frequency_hz", "excitation.phase_rad"}) {
        forbid(key, std::string(key) + in_mode + "; set excitation.mode to base, force or prescribed");
      }
      break;
    case ExcitationMode::base_motion:
    case ExcitationMode::prescribed_motion:
      forbid("excitation.force_N", "excitation.force_N" + in_mode + "; use excitation.amplitude_m");
      require_positive("excitation.amplitude_m", e.amplitude_m, "base and prescribed motion need an amplitude > 0");
      require_positive("excitation.frequency_hz", e.frequency_hz, "an excitation needs a frequency > 0");
      break;
    case ExcitationMode::force:
      forbid("excitation.amplitude_m", "excitation.amplitude_m" + in_mode + "; use excitation.force_N");
      require_positive("excitation.force_N", e.force_N, "force excitation needs a force amplitude > 0");
      require_positive("excitation.frequency_hz", e.frequency_hz, "an excitation needs a frequency > 0");
      break;
  }
  if (e.mode == ExcitationMode::prescribed_motion) {
    for (const char* key : {"host.stiffness_N_m", "host.damping_N_s_m", "host.z0_m", "host.v0_m_s"}) {
      forbid(key, std::string(key) + in_mode + " (the host follows z = A sin(wt+phi) exactly)");
    }
  } else if (e.mode != ExcitationMode::free_decay && s.host.damping_N_s_m == 0.0) {
    const double w0 = HostModel(s).natural_angular_frequency_rad_s();
    if (std::abs(e.angular_frequency_rad_s() - w0) <= 1e-9 * w0) {
      reject(raw.given.at("excitation.frequency_hz"),
             "equals the natural frequency of an undamped host: the response grows without bound; "
             "give host.damping_N_s_m > 0 or another frequency");
    }
  }
}

void check_particles(const Scenario& s, const RawScenario& raw) {
  if (s.particles.count == 0) return;
  const Value diameter = value_of(raw, "particles.diameter_m");
  const double d = s.particles.diameter_max_m;
  if (d >= s.cavity.diameter_m || d >= s.cavity.height_m) {
    std::ostringstream why;
    why << "spheres of diameter " << d << " m do not fit in the cavity (D = " << s.cavity.diameter_m
        << " m, H = " << s.cavity.height_m << " m); the diameter must be smaller than both";
    reject(diameter, why.str());
  }
  for (const double diameter_m : {s.particles.diameter_min_m, s.particles.diameter_max_m}) {
    // As the placement computes them; the engines divide by both.
    const double mass_kg = s.particles.density_kg_m3 * std::numbers::pi / 6.0 * diameter_m * diameter_m * diameter_m;
    const double inertia_kg_m2 = 0.1 * mass_kg * diameter_m * diameter_m;
    if (!std::isnormal(mass_kg) || !std::isnormal(1.0 / mass_kg) || !std::isnormal(inertia_kg_m2) ||
        !std::isnormal(1.0 / inertia_kg_m2)) {
      std::ostringstream why;
      why << "spheres of diameter " << diameter_m << " m would have a mass of " << mass_kg
          << " kg and a moment of inertia of " << inertia_kg_m2
          << " kg m^2, beyond what double precision holds with their inverses";
      reject(value_of(raw, "particles.density_kg_m3"), why.str());
    }
  }
  // Every engine's cells are at least as large as the largest sphere: this many at most.
  if (const double cells = CellGrid::cell_count(s.cavity.radius_m(), s.cavity.height_m, d);
      cells > CellGrid::max_cells) {
    std::ostringstream why;
    why << "the engines find contacts on a grid of cells as large as the largest sphere (" << d
        << " m); this cavity (D = " << s.cavity.diameter_m << " m, H = " << s.cavity.height_m << " m) would need "
        << cells << " of them, more than the " << CellGrid::max_cells
        << " they may have: a smaller cavity or larger spheres";
    reject(value_of(raw, "cavity.diameter_m"), value_of(raw, "cavity.height_m"), why.str());
  }
  const int capacity = particles_that_fit(s.particles, s.cavity);
  if (s.particles.count > capacity) {
    std::ostringstream why;
    why << "at most " << capacity << " " << describe_spheres(s.particles)
        << " can be placed in this cavity (D = " << s.cavity.diameter_m << " m, H = " << s.cavity.height_m << " m)";
    reject(value_of(raw, "particles.count"), why.str());
  }
}

/// How far the host's initial state may take it from its rest, in cavity heights: a damper's
/// host moves by about its cavity's size. Far beyond, the spheres' coordinates (absolute,
/// with the host's) lose the precision their contacts need and the time step for the
/// impacts such a host gives shrinks to nothing; host.z0_m = 1e300 makes no number at all.
constexpr double max_host_reach_in_heights = 100.0;

/// The host's motion within max_host_reach_in_heights cavity heights of its rest position,
/// judged by the host alone (M, K, C): for host.z0_m and host.v0_m_s, its free amplitude
/// sqrt(z0² + (v0/ω0)²), ω0 = sqrt(K/M), or what it can travel in the run at its top speed,
/// whichever is less (a host on a soft spring); for the excitation, the amplitude A of base or
/// prescribed motion, or a force's F0 / max(K, M ω²): the host's response away from its
/// resonance, which no damping lowers. Not its response at resonance, F0 / (C ω): to keep
/// that within bounds is the damper's job, whose studies drive lightly damped hosts there.
void check_host(const Scenario& s, const RawScenario& raw) {
  const double limit_m = max_host_reach_in_heights * s.cavity.height_m;
  std::ostringstream range;
  range << max_host_reach_in_heights << " cavity heights (" << limit_m << " m)";
  const auto& e = s.excitation;
  const auto& h = s.host;
  if (e.mode == ExcitationMode::force) {
    const double w = e.angular_frequency_rad_s();
    const double stiffness = std::max(h.stiffness_N_m, h.mass_kg * w * w);
    if (!(e.force_N / stiffness <= limit_m)) {
      std::ostringstream why;
      why << "would move the host by " << e.force_N / stiffness
          << " m even without resonance (F0 / max(K, M w^2)), more than " << range.str() << "; at most "
          << limit_m * stiffness << " N";
      reject(value_of(raw, "excitation.force_N"), why.str());
    }
  } else if (e.mode != ExcitationMode::free_decay && !(e.amplitude_m <= limit_m)) {
    reject(value_of(raw, "excitation.amplitude_m"), "must be at most " + range.str());
  }
  if (e.mode == ExcitationMode::prescribed_motion) return;  // z0 and v0 are not used
  const double z0 = std::abs(h.z0_m), v0 = std::abs(h.v0_m_s), t = s.run.duration_s;
  const double w0 = std::sqrt(h.stiffness_N_m / h.mass_kg);
  if (!(z0 <= limit_m)) reject(value_of(raw, "host.z0_m"), "must be within +-" + range.str() + " of the rest position");
  const double amplitude_m = v0 == 0.0 ? z0 : std::hypot(z0, v0 / w0);
  const double travel_m = z0 + t * std::hypot(v0, w0 * z0);
  const double reach_m = std::isnan(travel_m) ? amplitude_m : std::min(amplitude_m, travel_m);
  if (reach_m <= limit_m) return;
  // The largest |v0| whose reach is within the limit, by either bound.
  const double by_amplitude = w0 * std::sqrt(limit_m * limit_m - z0 * z0);
  const double top_speed = (limit_m - z0) / t;
  const double by_travel = std::sqrt(std::max(0.0, top_speed * top_speed - w0 * w0 * z0 * z0));
  std::ostringstream why;
  why << "the host would move up to " << reach_m << " m from its rest position (its free amplitude sqrt(z0^2 + "
      << "(v0/w0)^2), or in run.duration_s at its top speed), more than " << range.str()
      << "; with host.z0_m = " << h.z0_m << " m, |v0| must be at most " << std::max(by_amplitude, by_travel) << " m/s";
  reject(value_of(raw, "host.v0_m_s"), why.str());
}

/// The byte where `text` holds a control character (C0, DEL, or C1 in UTF-8), if it does.
std::optional<std::size_t> control_character_at(std::string_view text) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    const bool c1 = byte == 0xc2 && i + 1 < text.size() && static_cast<unsigned char>(text[i + 1]) >= 0x80 &&
                    static_cast<unsigned char>(text[i + 1]) <= 0x9f;
    if (byte < 0x20 || byte == 0x7f || c1) return i;
  }
  return std::nullopt;
}

/// The name is printed in tables and on terminals, where a control character breaks the
/// line or acts as a command.
void check_name(const Scenario& s, const RawScenario& raw) {
  const auto at = control_character_at(s.name);
  if (!at) return;
  const bool given = raw.given.contains("scenario.name");
  const Value v = given ? raw.given.at("scenario.name") : Value{"scenario.name", s.name, "default (the file name)"};
  reject(v, "holds a control character at byte " + std::to_string(*at) +
                "; a name is shown in tables and on terminals: write it in printable characters" +
                (given ? "" : ", or give scenario.name"));
}

void check_run(const Scenario& s, const RawScenario& raw) {
  if (s.run.sample_interval_s > s.run.duration_s) {
    reject(value_of(raw, "run.sample_interval_s"), "must not exceed run.duration_s");
  }
}

std::string canonical_text(const std::map<std::string, std::string>& effective) {
  std::ostringstream out;
  std::string section;
  for (const auto& spec : key_specs()) {
    const auto dot = spec.key.find('.');
    const std::string sec = spec.key.substr(0, dot);
    if (sec != section) {
      out << (section.empty() ? "" : "\n") << "[" << sec << "]\n";
      section = sec;
    }
    out << spec.key.substr(dot + 1) << " = " << effective.at(spec.key) << "\n";
  }
  return out.str();
}

Scenario build(const RawScenario& raw, const std::string& default_name) {
  Scenario s;
  s.name = default_name;
  std::map<std::string, std::string> effective;
  for (const auto& spec : key_specs()) {
    Value v;
    if (const auto it = raw.given.find(spec.key); it != raw.given.end()) {
      v = it->second;
    } else if (!spec.inherits.empty()) {
      v = Value{spec.key, effective.at(spec.inherits), "default (" + spec.inherits + ")"};
    } else {
      v = Value{spec.key, spec.default_text, "default"};
    }
    spec.apply(s, v);
    effective[spec.key] = v.text;
  }
  effective["scenario.name"] = s.name;
  check_name(s, raw);
  check_excitation(s, raw);
  check_host(s, raw);
  check_particles(s, raw);
  check_run(s, raw);
  s.canonical_text = canonical_text(effective);
  return s;
}

}  // namespace

Scenario parse_scenario(const std::string& text, const std::string& name, const std::string& origin,
                        const ScenarioOverrides& overrides, const std::string& overrides_origin) {
  RawScenario raw;
  parse_overrides(raw, overrides, overrides_origin);
  parse_file_text(raw, text, origin);
  return build(raw, name);
}

Scenario load_scenario(const std::filesystem::path& file, const ScenarioOverrides& overrides) {
  const std::string text = read_input_file({file, "scenario file '" + printable(file.string()) + "'", "a scenario file",
                                            max_scenario_file_bytes, "; the paper's cases are in data/scenarios/"});
  return parse_scenario(text, file.stem().string(), file.string(), overrides);
}

std::vector<std::string> scenario_key_names() {
  std::vector<std::string> names;
  for (const auto& spec : key_specs()) names.push_back(spec.key);
  return names;
}

void describe_scenario_keys(std::ostream& out) {
  out << "Scenario keys (section.key = default [unit]: meaning). Sections are INI headers in the file;\n"
         "--set section.key=value overrides any key.\n";
  std::string section;
  for (const auto& spec : key_specs()) {
    const std::string sec = spec.key.substr(0, spec.key.find('.'));
    if (sec != section) {
      out << "\n[" << sec << "]\n";
      section = sec;
    }
    const std::string default_text = spec.inherits.empty() ? spec.default_text : "as " + spec.inherits;
    out << "  " << spec.key << " = " << (default_text.empty() ? "(none)" : default_text);
    if (!spec.unit.empty()) out << " [" << spec.unit << "]";
    out << "\n      " << spec.help << "\n";
  }
}

}  // namespace pdamp
