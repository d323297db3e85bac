#include <doctest/doctest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

#include "pdamp/errors.hpp"
#include "test_support.hpp"

using namespace pdamp;
using pdamp::test::scenario_from;

namespace {

/// The message of the InputError that loading `text` throws ("" if none).
std::string input_error(const std::string& text, const ScenarioOverrides& overrides = {}) {
  try {
    scenario_from(text, overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

/// Every key and its default as `pdamp keys` prints them ("  section.key = default [unit]";
/// "as other.key" for a default that is another key's value, "(none)" for none).
std::vector<std::pair<std::string, std::string>> documented_defaults() {
  std::ostringstream listing;
  describe_scenario_keys(listing);
  std::istringstream lines(listing.str());
  std::vector<std::pair<std::string, std::string>> keys;
  for (std::string line; std::getline(lines, line);) {
    if (!line.starts_with("  ") || line[2] == ' ') continue;  // headers and help lines
    const auto eq = line.find(" = ");
    std::string text = line.substr(eq + 3);
    if (text.ends_with(']')) text.erase(text.rfind(" ["));
    keys.emplace_back(line.substr(2, eq - 2), text == "(none)" ? "" : text);
  }
  return keys;
}

/// section.key -> value of every line of a canonical text.
std::map<std::string, std::string> canonical_values(const std::string& canonical_text) {
  std::istringstream lines(canonical_text);
  std::map<std::string, std::string> values;
  std::string section;
  for (std::string line; std::getline(lines, line);) {
    if (line.starts_with('[')) {
      section = line.substr(1, line.size() - 2);
    } else if (const auto eq = line.find(" = "); eq != std::string::npos) {
      values[section + "." + line.substr(0, eq)] = line.substr(eq + 3);
    }
  }
  return values;
}

}  // namespace

TEST_CASE("an empty scenario is the paper's Table 1 case") {
  const Scenario s = scenario_from("");
  CHECK(s.host.mass_kg == 0.0376);
  CHECK(s.host.stiffness_N_m == 470.0);
  CHECK(s.host.damping_N_s_m == 0.1);
  CHECK(s.host.z0_m == 0.0157);
  CHECK(s.cavity.diameter_m == 0.0254);
  CHECK(s.cavity.height_m == 0.00704);
  CHECK(s.particles.count == 1246);
  CHECK(s.particles.diameter_min_m == 0.00088);
  CHECK(s.soft_particle.kn_N_m1_5 == 3.6e5);
  CHECK(s.soft_wall.kn_N_m1_5 == 3.6e5);
  CHECK(s.gravity_m_s2.z() == -9.81);
  CHECK(s.excitation.mode == ExcitationMode::free_decay);
  CHECK_FALSE(s.run.dt_s.has_value());
  CHECK(s.hard_resting.rest_speed_m_s == 0.005);
  CHECK(s.hard_resting.elastic_speed_m_s == 1e-4);
  CHECK(s.hard_resting.tc_window == 0.0);          // the TC model off
  CHECK(s.hard_resting.rest_tc_window == 0.0);     // the rest window off
  CHECK(s.hard_resting.cluster_speed_m_s == 0.0);  // rigid clusters off
  // The Table 1 soft law's restitution at a 0.5 m/s impact, sphere-sphere and sphere-wall.
  CHECK(s.hard_particle.en == 0.71);
  CHECK(s.hard_wall.en == 0.80);
  CHECK(scenario_from("[hard]\nrest_speed_m_s = 0.002\n").hard_resting.rest_speed_m_s == 0.002);
  CHECK(scenario_from("[hard]\ncluster_speed_m_s = 0.01\n").hard_resting.cluster_speed_m_s == 0.01);
  CHECK(scenario_from("[hard]\nrest_tc_window = 10\n").hard_resting.rest_tc_window == 10.0);
}

TEST_CASE("every key's documented default is what a scenario without keys resolves to, and a Scenario's own") {
  const Scenario loaded = parse_scenario("", "", "no keys");
  const auto resolved = canonical_values(loaded.canonical_text);
  const auto documented = documented_defaults();
  CHECK(documented.size() == resolved.size());
  std::map<std::string, std::string> documented_value;
  for (const auto& [name, text] : documented) {
    const std::string& key = name;  // by name: clang before 16 cannot capture a structured binding
    CAPTURE(key);
    const std::string value = text.starts_with("as ") ? documented_value.at(text.substr(3)) : text;
    documented_value[key] = value;
    REQUIRE(resolved.contains(key));
    CHECK(resolved.at(key) == value);
  }
  // The C++ API's default-constructed Scenario is the same scenario, every member.
  Scenario constructed;
  constructed.canonical_text = loaded.canonical_text;
  CHECK(loaded == constructed);
}

TEST_CASE("sections, comments, overrides and inherited wall laws") {
  const Scenario s = scenario_from(
      "# a comment\n[host]\nmass_kg = 0.05   # inline comment\n[soft]\nmu = 0.3\nkn_N_m1_5 = 2e5\n"
      "[soft_wall]\nkn_N_m1_5 = 4e5\n",
      {"host.mass_kg=0.06", "run.dt_s=2.5e-6"});
  CHECK(s.host.mass_kg == 0.06);  // the command line wins over the file
  CHECK(s.soft_particle.mu == 0.3);
  CHECK(s.soft_wall.mu == 0.3);  // not given for the wall: inherits the sphere-sphere value
  CHECK(s.soft_particle.kn_N_m1_5 == 2e5);
  CHECK(s.soft_wall.kn_N_m1_5 == 4e5);
  REQUIRE(s.run.dt_s.has_value());
  CHECK(*s.run.dt_s == 2.5e-6);
}

TEST_CASE("gravity as a magnitude or a vector, diameters as a value or a range") {
  CHECK(scenario_from("[gravity]\ng_m_s2 = 0\n").gravity_m_s2.norm() == 0.0);
  const Scenario tilted = scenario_from("[gravity]\ng_m_s2 = 1 0 -9\n");
  CHECK(tilted.gravity_m_s2.x() == 1.0);
  CHECK(tilted.gravity_m_s2.z() == -9.0);
  const Scenario range = scenario_from("[particles]\ndiameter_m = 0.0008 0.001\ncount = 100\n");
  CHECK(range.particles.diameter_min_m == 0.0008);
  CHECK(range.particles.diameter_max_m == 0.001);
  // Counted by the spheres' own sizes, not all at the largest (which holds 99 here).
  CHECK(scenario_from("[cavity]\ndiameter_m = 0.012\nheight_m = 0.010\n[particles]\ndiameter_m = 0.001 0.002\n"
                      "count = 100\n")
            .particles.count == 100);
  CHECK(contains(input_error("[gravity]\ng_m_s2 = -9.81\n"), "gravity.g_m_s2"));
  CHECK(contains(input_error("[gravity]\ng_m_s2 = 1 2\n"), "three"));
  CHECK(contains(input_error("[particles]\ndiameter_m = 0.002 0.001\n"), "dmin <= dmax"));
}

TEST_CASE("bad values are rejected with the key, the value and what is valid") {
  struct Case {
    std::string text, key, value, valid;
  };
  const Case cases[] = {
      {"[host]\nmass_kg = -1\n", "host.mass_kg", "'-1'", "> 0"},
      {"[host]\nmass_kg = 0.03x\n", "host.mass_kg", "'0.03x'", "not a finite number"},
      {"[host]\nstiffness_N_m = nan\n", "host.stiffness_N_m", "'nan'", "not a finite number"},
      {"[soft]\nmu = -0.1\n", "soft.mu", "'-0.1'", ">= 0"},
      {"[hard]\nen = 1.2\n", "hard.en", "'1.2'", "[0, 1]"},
      {"[hard_wall]\nbeta0 = -2\n", "hard_wall.beta0", "'-2'", "[-1, 1]"},
      {"[hard]\nrest_speed_m_s = -0.01\n", "hard.rest_speed_m_s", "'-0.01'", ">= 0"},
      {"[hard]\nelastic_speed_m_s = fast\n", "hard.elastic_speed_m_s", "'fast'", "not a finite number"},
      {"[hard]\ntc_window = -1\n", "hard.tc_window", "'-1'", ">= 0"},
      {"[hard]\nrest_tc_window = -10\n", "hard.rest_tc_window", "'-10'", ">= 0"},
      {"[hard]\nrest_tc_window = inf\n", "hard.rest_tc_window", "'inf'", "not a finite number"},
      {"[hard]\ncluster_speed_m_s = -0.01\n", "hard.cluster_speed_m_s", "'-0.01'", ">= 0"},
      {"[particles]\ncount = 2.5\n", "particles.count", "'2.5'", "whole number"},
      {"[particles]\nseed = -3\n", "particles.seed", "'-3'", "whole number"},
      {"[run]\ndt_s = fast\n", "run.dt_s", "'fast'", "'auto'"},
      {"[run]\nsample_interval_s = 3\n", "run.sample_interval_s", "'3'", "run.duration_s"},
      {"[excitation]\nmode = shake\n", "excitation.mode", "'shake'", "free, base, force, prescribed"},
      {"[hard]\nrestitution = fitted\n", "hard.restitution", "'fitted'", "one of constant, calibrated"},
      {"[particles]\ndiameter_m = 0.03\n", "particles.diameter_m", "'0.03'", "do not fit"},
      {"[particles]\ncount = 100000\n", "particles.count", "'100000'", "at most"},
  };
  for (const auto& c : cases) {
    CAPTURE(c.text);
    const std::string message = input_error(c.text);
    CHECK(contains(message, c.key));
    CHECK(contains(message, c.value));
    CHECK(contains(message, c.valid));
  }
}

// A '+' before the digits is how many people write a positive number; the signs that make
// no number stay refused.
TEST_CASE("a number may carry a '+' before its digits and its exponent, and nothing else around it") {
  const Scenario s = scenario_from(
      "[run]\nduration_s = +0.04\nsample_interval_s = +1e-3\nmax_steps = +2e+9\n"
      "[host]\nz0_m = +.01\n[particles]\nseed = +7\ndiameter_m = +0.001 +0.0012\n"
      "[gravity]\ng_m_s2 = +1 0 -9\n",
      {"run.dt_s=+1e-6"});
  CHECK(s.run.duration_s == 0.04);
  CHECK(s.run.sample_interval_s == 1e-3);
  CHECK(s.run.max_steps == 2'000'000'000);
  CHECK(s.host.z0_m == 0.01);
  CHECK(s.particles.seed == 7);
  CHECK(s.particles.diameter_min_m == 0.001);
  CHECK(s.gravity_m_s2.x() == 1.0);
  CHECK(*s.run.dt_s == 1e-6);
  for (const std::string bad : {"+", "++1", "+-1", "-+1", "0.04x", "+0.04x", "+ 1", "1e", "1e++3", "+inf", "+nan"}) {
    CAPTURE(bad);
    CHECK(contains(input_error("[run]\nduration_s = " + bad + "\n"), "run.duration_s = '" + bad + "'"));
  }
  CHECK(contains(input_error("[particles]\nseed = +-3\n"), "whole number"));
  CHECK(contains(input_error("[run]\ndt_s = ++1e-6\n"), "'auto'"));
}

TEST_CASE("unknown, duplicated and malformed keys are rejected") {
  CHECK(contains(input_error("[host]\nmass = 1\n"), "unknown key 'host.mass'"));
  CHECK(contains(input_error("[host]\nmass_kg = 1\nmass_kg = 2\n"), "more than once"));
  CHECK(contains(input_error("", {"host.mass_kg"}), "section.key=value"));
  CHECK(contains(input_error("", {"nokey=3"}), "section.key=value"));
  CHECK(contains(input_error("", {"host.weight=3"}), "unknown key 'host.weight'"));
}

TEST_CASE("excitation keys must match the excitation mode") {
  CHECK(contains(input_error("[excitation]\namplitude_m = 0.001\n"), "excitation.amplitude_m"));
  CHECK(contains(input_error("[excitation]\nmode = base\nfrequency_hz = 20\n"), "amplitude > 0"));
  CHECK(contains(input_error("[excitation]\nmode = force\nforce_N = 1\n"), "frequency > 0"));
  CHECK(contains(input_error("[excitation]\nmode = force\nforce_N = 1\nfrequency_hz = 5\namplitude_m = 0.1\n"),
                 "use excitation.force_N"));
  CHECK(contains(input_error("[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = 50\n"
                             "[host]\nz0_m = 0.01\n"),
                 "host.z0_m"));
  CHECK(contains(input_error("[host]\ndamping_N_s_m = 0\nmass_kg = 1\nstiffness_N_m = 39.47841760435743\n"
                             "[excitation]\nmode = force\nforce_N = 1\nfrequency_hz = 1\n"),
                 "without bound"));
  const Scenario base = scenario_from("[excitation]\nmode = base\namplitude_m = 0.001\nfrequency_hz = 20\n");
  CHECK(base.excitation.mode == ExcitationMode::base_motion);
  CHECK(base.excitation.amplitude_m == 0.001);
}

TEST_CASE("white space around a value, a carriage return included, is not part of it") {
  // Found by the fuzzer: '33063.2\r  # comment' kept the '\r', and the canonical text then
  // read back without it.
  const Scenario s = scenario_from("[host]\r\nstiffness_N_m = 33063.2\r  # K\r\n[scenario]\nname =\v run 7 \f\n");
  CHECK(s.host.stiffness_N_m == 33063.2);
  CHECK(s.name == "run 7");
  CHECK(contains(s.canonical_text, "stiffness_N_m = 33063.2\n"));
  CHECK(parse_scenario(s.canonical_text, s.name, "canonical").canonical_text == s.canonical_text);
}

TEST_CASE("the canonical text reproduces the scenario") {
  const Scenario s = scenario_from("[host]\nz0_m = 0.01\n[particles]\ncount = 10\ndiameter_m = 0.001 0.0012\n");
  const Scenario again = parse_scenario(s.canonical_text, "x", "canonical");
  CHECK(again.canonical_text == s.canonical_text);
  CHECK(again.name == s.name);
  CHECK(again.host.z0_m == 0.01);
  CHECK(again.particles.diameter_max_m == 0.0012);
  CHECK(contains(s.canonical_text, "[soft_wall]\nkn_N_m1_5 = 360000"));
}

TEST_CASE("a missing scenario file is an input error naming the file") {
  try {
    load_scenario("/nonexistent/dir/none.ini");
    FAIL("expected InputError");
  } catch (const InputError& e) {
    CHECK(contains(e.what(), "/nonexistent/dir/none.ini"));
  }
}

TEST_CASE("every scenario in data/scenarios loads and validates") {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(test::source_dir() / "data" / "scenarios")) {
    if (entry.path().extension() != ".ini") continue;
    CAPTURE(entry.path().string());
    CHECK_NOTHROW(load_scenario(entry.path()));
    ++count;
  }
  CHECK(count >= 10);
}

TEST_CASE("'#' starts a comment after a space, and inside a value it is refused, never cut") {
  CHECK(scenario_from("[scenario]\nname = run 7   # the seventh\n").name == "run 7");
  CHECK(scenario_from("# [host]\n[host]\n#mass_kg = 1\nmass_kg = 0.05\t# tab before the comment\n").host.mass_kg ==
        0.05);
  const std::string glued = input_error("[scenario]\nname = run#7 final\n");
  CHECK(contains(glued, "line 2"));
  CHECK(contains(glued, "'#' directly after text"));
  CHECK(contains(input_error("[host]\nmass_kg = 0.05#kg\n"), "'#' directly after text"));
  CHECK(contains(input_error("", {"scenario.name=run#7"}), "a value cannot contain '#'"));
  CHECK(contains(input_error("", {"scenario.name=run #7"}), "a value cannot contain '#'"));
}

// The name is printed in tables and on terminals: a control character in it would break
// the line or act as a command there.
TEST_CASE("a scenario name with a control character is refused, naming the key") {
  for (const std::string name : {"run\t7", "run\x1b[2J", "run\x7f",
                                 "run\xc2\x9b"
                                 "2J"}) {
    CAPTURE(name);
    const std::string message = input_error("[scenario]\nname = " + name + "\n");
    CHECK(contains(message, "scenario.name = '"));
    CHECK(contains(message, "control character at byte 3"));
    CHECK(contains(input_error("", {"scenario.name=" + name}), "--set scenario.name"));
  }
  CHECK(scenario_from("[scenario]\nname = Kühlung ∆ 振動\n").name == "Kühlung ∆ 振動");  // UTF-8 stays
  const std::string by_file = [] {
    try {
      parse_scenario("", "bad\x1bname", "bad\x1bname.ini");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  }();
  CHECK(contains(by_file, "default (the file name): scenario.name = 'bad\\x1bname'"));
  CHECK(contains(by_file, "or give scenario.name"));
}

TEST_CASE("a --set is one line: a line break in it is refused, not read as more keys") {
  const std::string message = input_error("", {"host.z0_m=0.01\nhost.mass_kg=1"});
  CHECK(contains(message, "without line breaks"));
  CHECK(contains(message, "host.z0_m=0.01\\x0ahost.mass_kg=1"));  // shown, not broken
  CHECK(contains(input_error("", {"host.z0_m=0.01\r"}), "without line breaks"));
  CHECK(contains(input_error("", {std::string("host.z0_m=0.01\0x", 16)}), "without line breaks"));
}

TEST_CASE("a key set twice on the command line takes the last value, and a file may give a key once") {
  const Scenario s = scenario_from("[host]\nz0_m = 0.005\n", {"host.z0_m=0.01", "host.z0_m=0.02"});
  CHECK(s.host.z0_m == 0.02);
  CHECK(scenario_from("", {"run.duration_s=0.2", "run.duration_s=0.1"}).run.duration_s == 0.1);
  CHECK(contains(input_error("[host]\nz0_m = 0.01\n[host]\nz0_m = 0.02\n"),
                 "line 4: key 'host.z0_m' is given more than once"));
}

TEST_CASE("a UTF-8 byte-order mark at the start of a file is skipped, and an invisible byte elsewhere is named") {
  CHECK(scenario_from("\xEF\xBB\xBF[host]\nmass_kg = 0.05\n").host.mass_kg == 0.05);
  CHECK(contains(input_error("[host]\n\xEF\xBB\xBFmass_kg = 0.05\n"), "unknown key 'host.\\xef\\xbb\\xbfmass_kg'"));
  CHECK(contains(input_error("[host]\nmass_kg\xE2\x80\x8B = 1\n"), "unknown key 'host.mass_kg\\xe2\\x80\\x8b'"));
  CHECK(contains(input_error("[host]\nmass_kg = 0.05\xC2\xA0\n"), "'0.05\\xc2\\xa0'"));
  CHECK(contains(input_error(std::string("[host]\nmass_kg = 0.05\n\0", 23)), "a NUL byte at offset 22"));
  CHECK(contains(input_error("[host]\nmass_kg\n"), "line 2: 'mass_kg' is not a 'key = value' line"));
}

TEST_CASE("the bounds of a run are keys, whole numbers up to 2^53") {
  const Scenario s = scenario_from("[run]\nmax_steps = 2e9\nmax_samples = 5000\nmax_events = 123\n");
  CHECK(s.run.max_steps == 2'000'000'000);
  CHECK(s.run.max_samples == 5000);
  CHECK(s.run.max_events == 123);
  const Scenario defaults = scenario_from("");
  CHECK(defaults.run.max_steps == 1'000'000'000);
  CHECK(defaults.run.max_samples == 1'000'000);
  CHECK(defaults.run.max_events == 10'000'000'000);
  CHECK(contains(input_error("[run]\nmax_steps = 0\n"), "run.max_steps = '0': must be a whole number from 1 to"));
  CHECK(contains(input_error("[run]\nmax_samples = 1e300\n"), "run.max_samples"));
  CHECK(contains(input_error("[run]\nmax_events = 1.5\n"), "whole number"));
}

TEST_CASE("spheres whose mass or inertia double precision cannot hold are refused") {
  CHECK(contains(input_error("[particles]\ndensity_kg_m3 = 1e308\n"), "particles.density_kg_m3 = '1e308'"));
  CHECK(contains(input_error("[particles]\ndensity_kg_m3 = 1e-300\n"), "beyond what double precision holds"));
  CHECK(contains(input_error("[particles]\ndiameter_m = 1e-300 1e-299\n"), "particles.density_kg_m3"));
}

// A host started absurdly far from rest or absurdly fast, or driven so, once reached the
// engines as NaN time steps blamed on run.max_steps, or as a bed settling at a crawl.
TEST_CASE("the host's initial state and its excitation keep it within 100 cavity heights of rest") {
  // Table 1: H = 7.04 mm, so 0.704 m; w0 = sqrt(470 / 0.0376) = 111.8 rad/s.
  const std::string table1 = "[cavity]\nheight_m = 0.00704\n";
  CHECK(scenario_from(table1 + "[host]\nz0_m = -0.7\n").host.z0_m == -0.7);
  CHECK(scenario_from(table1 + "[host]\nz0_m = 0\nv0_m_s = 78\n").host.v0_m_s == 78);  // 0.698 m amplitude
  for (const char* z0 : {"1e300", "1e10", "-0.71"}) {
    CAPTURE(z0);
    const std::string message = input_error(table1 + "[host]\nz0_m = " + z0 + "\n");
    CHECK(contains(message, "host.z0_m = '" + std::string(z0) + "': must be within +-100 cavity heights (0.704 m)"));
  }
  for (const char* v0 : {"1e300", "-80"}) {
    CAPTURE(v0);
    const std::string message = input_error(table1 + "[host]\nz0_m = 0\nv0_m_s = " + v0 + "\n");
    CHECK(contains(message, "host.v0_m_s = '" + std::string(v0) + "': the host would move up to"));
    CHECK(contains(message, "|v0| must be at most 78.7"));
  }
  // A host on a negligible spring travels no farther than its speed takes it in the run.
  CHECK(scenario_from("[host]\nstiffness_N_m = 1e-20\nz0_m = 0\nv0_m_s = 0.05\n").host.v0_m_s == 0.05);
  CHECK(contains(input_error("[host]\nstiffness_N_m = 1e-20\nz0_m = 0\nv0_m_s = 1\n[run]\nduration_s = 1\n"),
                 "|v0| must be at most 0.704 m/s"));
  // The excitation likewise: a base's or prescribed motion's amplitude, a force's steady response.
  const std::string base = "[excitation]\nmode = base\nfrequency_hz = 20\n[host]\nz0_m = 0\n" + table1;
  CHECK(scenario_from(base + "[excitation]\namplitude_m = 0.7\n").excitation.amplitude_m == 0.7);
  CHECK(contains(input_error(base + "[excitation]\namplitude_m = 1e300\n"),
                 "excitation.amplitude_m = '1e300': must be at most 100 cavity heights (0.704 m)"));
  // At 20 Hz: max(470, 0.0376 (2 pi 20)^2) = 593.77 N/m, so at most 418.0 N.
  const std::string force = "[excitation]\nmode = force\nfrequency_hz = 20\n[host]\nz0_m = 0\n" + table1;
  CHECK(scenario_from(force + "[excitation]\nforce_N = 418\n").excitation.force_N == 418);
  CHECK(contains(input_error(force + "[excitation]\nforce_N = 419\n"),
                 "excitation.force_N = '419': would move the host by 0.7056"));
  CHECK(contains(input_error(force + "[excitation]\nforce_N = 1e300\n"), "at most 418.0"));
  // At resonance a lightly damped host alone would go far (1 N / (0.01 N s/m 111.8 rad/s) =
  // 0.89 m); the damper is what keeps it from that, so the force is not refused for it.
  CHECK(scenario_from("[excitation]\nmode = force\nfrequency_hz = 17.79\nforce_N = 1\n[host]\nz0_m = "
                      "0\ndamping_N_s_m = 0.01\n" +
                      table1)
            .excitation.force_N == 1);
  // Prescribed motion uses neither key (and refuses them if given).
  CHECK(scenario_from("[excitation]\nmode = prescribed\namplitude_m = 0.001\nfrequency_hz = 50\n").host.z0_m == 0.0157);
}

TEST_CASE("a cavity far larger than its spheres is refused at once, naming the cell grid it would need") {
  const auto start = std::chrono::steady_clock::now();
  const std::string message = input_error("[cavity]\ndiameter_m = 1e6\nheight_m = 1e6\n");
  CHECK(contains(message, "cavity.diameter_m = '1e6' and cavity.height_m = '1e6'"));
  CHECK(contains(message, "more than the 16777216"));
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(1));
  // A wide cavity whose grid fits: its capacity is counted, not listed.
  CHECK(scenario_from("[cavity]\ndiameter_m = 0.4\n").cavity.diameter_m == 0.4);
  const std::string tall =
      input_error("[cavity]\ndiameter_m = 0.002\nheight_m = 1e6\n[particles]\ndiameter_m = 0.001\n");
  CHECK(contains(tall, "cavity.diameter_m = '0.002' and cavity.height_m = '1e6'"));
}

namespace {

/// A fresh directory, removed with its contents when done.
struct ScratchDir {
  std::filesystem::path path;
  explicit ScratchDir(const std::string& name)
      : path(std::filesystem::temp_directory_path() / ("pdamp-scenario-" + name + "-" + std::to_string(getpid()))) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~ScratchDir() { std::filesystem::remove_all(path); }
};

std::string load_error(const std::filesystem::path& file) {
  try {
    load_scenario(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("only a regular file of at most 1 MiB is read as a scenario: a FIFO, a device, a directory are refused") {
  const ScratchDir dir("files");
  const auto fifo = dir.path / "scenario.fifo";
  REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
  const auto start = std::chrono::steady_clock::now();
  CHECK(contains(load_error(fifo), "is a FIFO, not a regular file"));  // nobody writes to it: it must not block
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(1));
  CHECK(contains(load_error("/dev/zero"), "is a device, not a regular file"));
  CHECK(contains(load_error(dir.path), "is a directory, not a regular file"));
  const auto large = dir.path / "large.ini";
  std::ofstream(large) << std::string(max_scenario_file_bytes, '#') << "\n";
  CHECK(contains(load_error(large), "larger than 1048576 bytes"));
  std::filesystem::resize_file(large, max_scenario_file_bytes);  // all comment: Table 1
  CHECK(load_scenario(large).particles.count == 1246);
}
