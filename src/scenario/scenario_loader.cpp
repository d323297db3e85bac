#include "pdamp/scenario/scenario_loader.hpp"

#include <algorithm>
#include <boost/program_options.hpp>
#include <charconv>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <ostream>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/model/placement.hpp"

namespace po = boost::program_options;

namespace pdamp {

double ExcitationSettings::angular_frequency_rad_s() const { return 2.0 * std::numbers::pi * frequency_hz; }

namespace {

/// Where a value came from and what it is, for error messages.
struct Value {
  std::string key;
  std::string text;
  std::string origin;  ///< "file.ini" or "--set"
};

[[noreturn]] void reject(const Value& v, const std::string& why) {
  throw InputError(v.origin + ": " + v.key + " = '" + v.text + "': " + why);
}

std::vector<std::string> split_words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

double parse_number(const Value& v, const std::string& word) {
  double x = 0.0;
  const char* end = word.data() + word.size();
  auto [ptr, ec] = std::from_chars(word.data(), end, x);
  if (ec != std::errc() || ptr != end || !std::isfinite(x)) {
    reject(v, "'" + word + "' is not a finite number (write e.g. 0.0157 or 1.5e-3)");
  }
  return x;
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

Apply number(double& (*field)(Scenario&), Range range) {
  return [field, range](Scenario& s, const Value& v) { field(s) = parse_in_range(v, range); };
}

#define PDAMP_FIELD(expr) [](Scenario& s) -> double& { return s.expr; }

ExcitationMode parse_mode(const Value& v) {
  static const std::map<std::string, ExcitationMode> modes{{"free", ExcitationMode::free_decay},
                                                           {"base", ExcitationMode::base_motion},
                                                           {"force", ExcitationMode::force},
                                                           {"prescribed", ExcitationMode::prescribed_motion}};
  const auto it = modes.find(v.text);
  if (it == modes.end()) reject(v, "must be one of free, base, force, prescribed");
  return it->second;
}

std::vector<KeySpec> soft_law_keys(const std::string& section, SoftContactLaw Scenario::*law,
                                   const std::string& inherit_section) {
  auto field = [law](double SoftContactLaw::*member, Range range) -> Apply {
    return [law, member, range](Scenario& s, const Value& v) { s.*law.*member = parse_in_range(v, range); };
  };
  auto inherit = [&](const std::string& key) { return inherit_section.empty() ? "" : inherit_section + "." + key; };
  const SoftContactLaw d;
  auto text = [](double x) {
    std::ostringstream o;
    o << x;
    return o.str();
  };
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
                                   const std::string& en_default, const std::string& inherit_section) {
  auto field = [law](double HardContactLaw::*member, Range range) -> Apply {
    return [law, member, range](Scenario& s, const Value& v) { s.*law.*member = parse_in_range(v, range); };
  };
  auto inherit = [&](const std::string& key) { return inherit_section.empty() ? "" : inherit_section + "." + key; };
  const std::string who = inherit_section.empty() ? "sphere-sphere" : "sphere-wall";
  return {
      {section + ".en", en_default, "1", "normal restitution coefficient e_n (" + who + ")",
       field(&HardContactLaw::en, unit_interval), ""},
      {section + ".mu", "0.55", "1", "Coulomb friction coefficient (" + who + ")",
       field(&HardContactLaw::mu, non_negative), inherit("mu")},
      {section + ".beta0", "0.35", "1", "tangential restitution of sticking collisions (" + who + ")",
       field(&HardContactLaw::beta0, signed_unit_interval), inherit("beta0")},
  };
}

const std::vector<KeySpec>& key_specs() {
  static const std::vector<KeySpec> specs = [] {
    std::vector<KeySpec> k{
        {"scenario.name", "", "", "name stored with each run (default: the file name without extension)",
         [](Scenario& s, const Value& v) {
           if (!v.text.empty()) s.name = v.text;
         },
         ""},
        {"host.mass_kg", "0.0376", "kg", "host mass M (for prescribed motion: the nominal mass used in psi)",
         number(PDAMP_FIELD(host.mass_kg), positive), ""},
        {"host.stiffness_N_m", "470", "N/m", "host spring K", number(PDAMP_FIELD(host.stiffness_N_m), positive), ""},
        {"host.damping_N_s_m", "0.1", "N s/m", "host viscous damper C",
         number(PDAMP_FIELD(host.damping_N_s_m), non_negative), ""},
        {"host.z0_m", "0.0157", "m", "initial host displacement from its static equilibrium",
         number(PDAMP_FIELD(host.z0_m), any_number), ""},
        {"host.v0_m_s", "0", "m/s", "initial host velocity", number(PDAMP_FIELD(host.v0_m_s), any_number), ""},
        {"excitation.mode", "free", "",
         "free (decay) | base (base motion y = A sin(wt+phi) through K and C) | force (F0 sin(wt+phi) on the "
         "host) | prescribed (host moves as z = A sin(wt+phi), infinite mass)",
         [](Scenario& s, const Value& v) { s.excitation.mode = parse_mode(v); }, ""},
        {"excitation.amplitude_m", "0", "m", "motion amplitude A (base and prescribed modes)",
         number(PDAMP_FIELD(excitation.amplitude_m), non_negative), ""},
        {"excitation.force_N", "0", "N", "force amplitude F0 (force mode)",
         number(PDAMP_FIELD(excitation.force_N), non_negative), ""},
        {"excitation.frequency_hz", "0", "Hz", "excitation frequency f (w = 2 pi f)",
         number(PDAMP_FIELD(excitation.frequency_hz), non_negative), ""},
        {"excitation.phase_rad", "0", "rad", "excitation phase phi",
         number(PDAMP_FIELD(excitation.phase_rad), any_number), ""},
        {"cavity.diameter_m", "0.0254", "m", "cylinder diameter D", number(PDAMP_FIELD(cavity.diameter_m), positive),
         ""},
        {"cavity.height_m", "0.00704", "m", "cylinder height H", number(PDAMP_FIELD(cavity.height_m), positive), ""},
        {"gravity.g_m_s2", "9.81", "m/s^2",
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
        {"particles.count", "1246", "", "number of spheres n (0 runs the host alone)",
         [](Scenario& s, const Value& v) {
           const double n = parse_in_range(v, non_negative);
           if (n != std::floor(n) || n > 10'000'000) reject(v, "must be a whole number from 0 to 10000000");
           s.particles.count = static_cast<int>(n);
         },
         ""},
        {"particles.diameter_m", "0.00088", "m", "sphere diameter d, or 'dmin dmax' for diameters uniform in a range",
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
        {"particles.density_kg_m3", "9000", "kg/m^3", "sphere material density",
         number(PDAMP_FIELD(particles.density_kg_m3), positive), ""},
        {"particles.seed", "1", "", "random seed of the initial placement (unsigned 64-bit)",
         [](Scenario& s, const Value& v) {
           std::uint64_t seed = 0;
           const char* end = v.text.data() + v.text.size();
           auto [ptr, ec] = std::from_chars(v.text.data(), end, seed);
           if (ec != std::errc() || ptr != end) reject(v, "must be a whole number from 0 to 18446744073709551615");
           s.particles.seed = seed;
         },
         ""},
        {"run.duration_s", "1.5", "s", "simulated time", number(PDAMP_FIELD(run.duration_s), positive), ""},
        {"run.sample_interval_s", "0.001", "s", "interval between stored samples",
         number(PDAMP_FIELD(run.sample_interval_s), positive), ""},
        {"run.dt_s", "auto", "s", "soft engine time step, or 'auto' (from the Hertz contact time)",
         [](Scenario& s, const Value& v) {
           constexpr Range time_step{0.0, inf, false, "must be 'auto' or a time step > 0 in seconds"};
           const auto words = split_words(v.text);
           double dt = 0.0;
           if (v.text == "auto") {
             s.run.dt_s.reset();
             return;
           }
           if (words.size() != 1 || std::from_chars(words[0].data(), words[0].data() + words[0].size(), dt).ptr !=
                                        words[0].data() + words[0].size()) {
             reject(v, time_step.text);
           }
           s.run.dt_s = parse_in_range(v, time_step);
         },
         ""},
    };
    for (auto& spec : soft_law_keys("soft", &Scenario::soft_particle, "")) k.push_back(spec);
    for (auto& spec : soft_law_keys("soft_wall", &Scenario::soft_wall, "soft")) k.push_back(spec);
    for (auto& spec : hard_law_keys("hard", &Scenario::hard_particle, "0.71", "")) k.push_back(spec);
    k.push_back({"hard.restitution", "constant", "",
                 "constant (en and beta0 as given) | calibrated (e_n(v) and beta0(v) of the soft law, from "
                 "isolated soft collisions at the impact speed)",
                 [](Scenario& s, const Value& v) {
                   if (v.text == "constant")
                     s.hard_restitution = HardRestitution::constant;
                   else if (v.text == "calibrated")
                     s.hard_restitution = HardRestitution::calibrated;
                   else
                     reject(v, "must be constant or calibrated");
                 },
                 ""});
    // The hard engine's resting-bed parameters (docs/hard-engine.md, "Resting beds and inelastic collapse").
    k.push_back({"hard.rest_speed_m_s", "0.005", "m/s",
                 "a sphere leaving the floor, top cap or a resting sphere slower than this (relative to the host) "
                 "while the host's acceleration presses it there comes to rest and rides with the host",
                 number(PDAMP_FIELD(hard_resting.rest_speed_m_s), non_negative), ""});
    k.push_back({"hard.elastic_speed_m_s", "0.0001", "m/s",
                 "collisions with a normal approach speed below this are elastic (stops inelastic collapse)",
                 number(PDAMP_FIELD(hard_resting.elastic_speed_m_s), non_negative), ""});
    for (auto& spec : hard_law_keys("hard_wall", &Scenario::hard_wall, "0.80", "hard")) k.push_back(spec);
    return k;
  }();
  return specs;
}

#undef PDAMP_FIELD

/// Parsed text of every key, remembering which keys the user set and where.
struct RawScenario {
  std::map<std::string, Value> given;
};

po::options_description options_for_parsing() {
  po::options_description desc;
  for (const auto& spec : key_specs()) desc.add_options()(spec.key.c_str(), po::value<std::string>());
  return desc;
}

void parse_into(RawScenario& raw, std::istream& in, const std::string& origin) {
  po::variables_map vm;
  try {
    po::store(po::parse_config_file(in, options_for_parsing(), /*allow_unregistered=*/false), vm);
  } catch (const po::unknown_option& e) {
    throw InputError(origin + ": unknown key '" + e.get_option_name() +
                     "' (run 'pdamp keys' for the list of valid keys)");
  } catch (const po::multiple_occurrences& e) {
    throw InputError(origin + ": key '" + e.get_option_name() + "' is given more than once");
  } catch (const po::error& e) {
    throw InputError(origin + ": " + e.what() + " (expected 'key = value' lines under [section] headers)");
  }
  for (const auto& [key, value] : vm) {
    // Overrides are parsed first and win over the file.
    raw.given.try_emplace(key, Value{key, value.as<std::string>(), origin});
  }
}

void parse_overrides(RawScenario& raw, const ScenarioOverrides& overrides) {
  for (const auto& item : overrides) {
    const auto eq = item.find('=');
    const auto dot = item.find('.');
    if (eq == std::string::npos || dot == std::string::npos || dot > eq) {
      throw InputError("--set '" + item + "': expected section.key=value, e.g. --set host.z0_m=0.01");
    }
    std::istringstream line(item + "\n");
    parse_into(raw, line, "--set " + item.substr(0, eq));
  }
}

/// True if a numeric key was given a value other than its default.
bool differs_from_default(const RawScenario& raw, const std::string& key) {
  const auto it = raw.given.find(key);
  if (it == raw.given.end()) return false;
  const auto spec =
      std::find_if(key_specs().begin(), key_specs().end(), [&](const KeySpec& k) { return k.key == key; });
  return parse_number(it->second, it->second.text) != parse_number(it->second, spec->default_text);
}

/// Keys that the chosen excitation mode ignores must keep their defaults: a value that
/// would be silently ignored is a wrong answer waiting to happen.
void check_excitation(const Scenario& s, const RawScenario& raw) {
  const auto& e = s.excitation;
  auto forbid = [&](const std::string& key, const std::string& why) {
    if (differs_from_default(raw, key)) reject(raw.given.at(key), why);
  };
  auto require_positive = [&](const std::string& key, double value, const std::string& why) {
    if (value > 0) return;
    const auto it = raw.given.find(key);
    reject(it != raw.given.end() ? it->second : Value{key, "0", "default"}, why);
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
    const double w0 = std::sqrt(s.host.stiffness_N_m / s.host.mass_kg);
    if (std::abs(e.angular_frequency_rad_s() - w0) <= 1e-9 * w0) {
      reject(raw.given.at("excitation.frequency_hz"),
             "equals the natural frequency of an undamped host: the response grows without bound; "
             "give host.damping_N_s_m > 0 or another frequency");
    }
  }
}

void check_particles(const Scenario& s, const RawScenario& raw) {
  if (s.particles.count == 0) return;
  auto value_of = [&](const std::string& key, const std::string& fallback) {
    const auto it = raw.given.find(key);
    return it != raw.given.end() ? it->second : Value{key, fallback, "default"};
  };
  const Value diameter = value_of("particles.diameter_m", "0.00088");
  const double d = s.particles.diameter_max_m;
  if (d >= s.cavity.diameter_m || d >= s.cavity.height_m) {
    std::ostringstream why;
    why << "spheres of diameter " << d << " m do not fit in the cavity (D = " << s.cavity.diameter_m
        << " m, H = " << s.cavity.height_m << " m); the diameter must be smaller than both";
    reject(diameter, why.str());
  }
  const int capacity = max_particles_that_fit(s.cavity, d);
  if (s.particles.count > capacity) {
    std::ostringstream why;
    why << "at most " << capacity << " spheres of diameter " << d
        << " m can be placed in this cavity (D = " << s.cavity.diameter_m << " m, H = " << s.cavity.height_m << " m)";
    reject(value_of("particles.count", "1246"), why.str());
  }
}

void check_run(const Scenario& s, const RawScenario& raw) {
  if (s.run.sample_interval_s > s.run.duration_s) {
    const auto it = raw.given.find("run.sample_interval_s");
    reject(it != raw.given.end() ? it->second : Value{"run.sample_interval_s", "0.001", "default"},
           "must not exceed run.duration_s");
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
  check_excitation(s, raw);
  check_particles(s, raw);
  check_run(s, raw);
  s.canonical_text = canonical_text(effective);
  return s;
}

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t\r\n") - first + 1);
}

}  // namespace

Scenario parse_scenario(const std::string& text, const std::string& name, const std::string& origin,
                        const ScenarioOverrides& overrides) {
  RawScenario raw;
  parse_overrides(raw, overrides);
  std::istringstream in(text);
  parse_into(raw, in, origin);
  for (auto& [key, value] : raw.given) value.text = trim(value.text);
  return build(raw, name);
}

Scenario load_scenario(const std::filesystem::path& file, const ScenarioOverrides& overrides) {
  std::ifstream in(file);
  if (!in) {
    throw InputError("scenario file '" + file.string() + "' cannot be read (" +
                     (std::filesystem::exists(file) ? "permission denied" : "no such file") +
                     "); the paper's cases are in data/scenarios/");
  }
  std::ostringstream text;
  text << in.rdbuf();
  return parse_scenario(text.str(), file.stem().string(), file.string(), overrides);
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
    const std::string default_text = spec.inherits.empty() ? spec.default_text : "= " + spec.inherits;
    out << "  " << spec.key << " = " << (default_text.empty() ? "(none)" : default_text);
    if (!spec.unit.empty()) out << " [" << spec.unit << "]";
    out << "\n      " << spec.help << "\n";
  }
}

}  // namespace pdamp
