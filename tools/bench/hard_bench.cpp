/// pdamp_bench: throughput of the hard-sphere engine on the benchmark gas.
///
///   pdamp_bench [--particles N] [--collisions C] [--host fixed|free] [--packing PHI]
///
/// N elastic, frictionless spheres of 1 mm (e_n = 1, μ = 0) at random velocities
/// (Gaussian components, 1 m/s rms speed), no gravity, in a closed cylinder (D = H) sized
/// for the solid fraction PHI (default 0.3). The host is fixed (prescribed, zero
/// amplitude) or free (mass 10x the spheres', 20 Hz, undamped), which makes every cap
/// collision an impulse on the host and shows what those cost as N grows. After a
/// warm-up of N collisions it times C collisions (default 20 N, at least 10^6) and prints
/// one line: collisions/s, events/s, the host-impulse counters, memory per sphere, the
/// relative change of the stored energy (for the fixed host: the conservation error), the
/// ledger's balance error (for the free host, spheres that come to rest on an
/// accelerating cap lose energy, which the ledger books), and what the run was given of
/// its core: the clock and the share of the core's issue slots (median and lowest; see
/// core_probe.hpp).
#include <sys/resource.h>

#include <algorithm>
#include <boost/program_options.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "benchmark_gas.hpp"
#include "core_probe.hpp"
#include "hard/hard_engine_class.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/model/placement.hpp"

using namespace pdamp;

namespace {

long peak_rss_kB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

std::int64_t statistic(const Engine& engine, const std::string& name) {
  for (const auto& [key, value] : engine.statistics()) {
    if (key == name) return value;
  }
  return 0;
}

double total_energy(const Engine& engine) { return engine.observe().energy.stored_J(); }

double median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

struct Options {
  int n = 1000;
  long collisions = 0;  ///< 0: 20 N, at least 10^6
  bool free_host = false;
  double packing = 0.3;
};

/// The options, or an exit with status 2 and a message naming the option, the value and
/// what is valid.
Options parse_options(int argc, char** argv) {
  namespace po = boost::program_options;
  Options o;
  std::string host = "fixed";
  po::options_description options("pdamp_bench");
  options.add_options()("help", "this text")("particles", po::value(&o.n)->default_value(o.n), "spheres, 2 to 10^7")(
      "collisions", po::value(&o.collisions), "collisions timed, >= 1 (default 20 N, at least 10^6)")(
      "host", po::value(&host)->default_value(host), "fixed or free")(
      "packing", po::value(&o.packing)->default_value(o.packing, "0.3"), "solid fraction, above 0 and below 0.74");
  const auto refuse = [&](const std::string& why) {
    std::fprintf(stderr, "pdamp_bench: %s\n", why.c_str());
    std::exit(2);
  };
  try {
    po::variables_map vm;
    po::store(po::parse_command_line(argc, argv, options), vm);
    po::notify(vm);
    if (vm.count("help")) {
      std::ostringstream text;
      text << options;
      std::fputs(text.str().c_str(), stdout);
      std::exit(0);
    }
    if (vm.count("collisions") && o.collisions < 1) {
      refuse("--collisions " + std::to_string(o.collisions) + ": must be at least 1");
    }
  } catch (const po::error& e) {
    refuse(std::string(e.what()) + " (pdamp_bench --help lists the options)");
  }
  if (o.n < 2 || o.n > 10'000'000) refuse("--particles " + std::to_string(o.n) + ": must be from 2 to 10000000");
  if (host != "fixed" && host != "free") refuse("--host '" + host + "': must be fixed or free");
  // Densest packing: π / √18. (The placement says so if it cannot place them that densely.)
  if (!(o.packing > 0.0 && o.packing < 0.74)) {
    refuse("--packing " + std::to_string(o.packing) + ": must be above 0 and below 0.74");
  }
  o.free_host = host == "free";
  if (o.collisions == 0) o.collisions = std::max(20L * o.n, 1000000L);
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  const auto [n, collisions, free_host, packing] = parse_options(argc, argv);

  try {
    const Scenario scenario = bench::benchmark_gas(n, packing, free_host);
    Particles spheres = place_particles(scenario.particles, scenario.cavity, 0.0);
    std::mt19937_64 rng(1);
    std::normal_distribution<double> component(0.0, 1.0 / std::sqrt(3.0));
    for (int i = 0; i < n; ++i) {
      spheres.velocity_m_s.col(i) = Eigen::Vector3d(component(rng), component(rng), component(rng));
    }
    const long rss_before = peak_rss_kB();
    hard::HardEngine engine(scenario, spheres);
    const double e0 = total_energy(engine);
    // Chunks of simulated time that hold about N/4 collisions each.
    const double mean_free_time = bench::gas_sphere_diameter_m / (6 * std::sqrt(2.0) * packing * 1.0);
    const double chunk = 0.5 * mean_free_time;
    double t = 0.0;
    while (engine.collisions() < n) engine.advance_to(t += chunk);
    const std::int64_t start_collisions = engine.collisions();
    const EngineStatistics start_stats = engine.statistics();
    std::int64_t start_events = 0;
    for (const auto& [name, value] : start_stats) {
      if (name.rfind("events_", 0) == 0) start_events += value;
    }
    // Timed in 200 slices, with what the run is given of its core (core_probe.hpp) probed
    // before, between and after them, outside the timed intervals. Always 201 probes:
    // `tools/bench-hard.sh --counts` subtracts two runs' instructions, theirs with them.
    constexpr int slices = 200;
    std::vector<double> clock_GHz, core_share;
    const auto probe = [&] {
      const bench::CoreProbe now = bench::probe_core();
      clock_GHz.push_back(now.clock_GHz);
      core_share.push_back(now.share);
    };
    probe();
    double wall = 0.0;
    for (int slice = 1; slice <= slices; ++slice) {
      const std::int64_t until = start_collisions + collisions * slice / slices;
      const auto slice_start = std::chrono::steady_clock::now();
      while (engine.collisions() < until) engine.advance_to(t += chunk);
      wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - slice_start).count();
      probe();
    }
    std::int64_t events = -start_events;
    for (const auto& [name, value] : engine.statistics()) {
      if (name.rfind("events_", 0) == 0) events += value;
    }
    const double done = static_cast<double>(engine.collisions() - start_collisions);
    const long rss_after = peak_rss_kB();
    const double impulses = static_cast<double>(statistic(engine, "host_impulses"));
    double repredictions = 0;  // of host-dependent events, in every tier
    for (const auto& [name, value] : engine.statistics()) {
      if (name.ends_with("_repredictions")) repredictions += static_cast<double>(value);
    }
    std::printf(
        "particles %7d  host %-5s  cavity D=H=%.4f m  collisions %10.0f  wall %8.3f s  collisions/s %.3e  "
        "events/s %.3e  stale/event %.2f  host impulses %.0f  re-predictions per impulse %.2f  near sweeps %lld  "
        "bytes/sphere %.0f  energy change %.1e  balance error %.1e  clock %.2f GHz  "
        "core share %.2f (lowest %.2f)\n",
        n, free_host ? "free" : "fixed", scenario.cavity.diameter_m, done, wall, done / wall,
        static_cast<double>(events) / wall,
        static_cast<double>(statistic(engine, "events_stale")) / static_cast<double>(events + start_events), impulses,
        impulses > 0 ? repredictions / impulses : 0.0, static_cast<long long>(statistic(engine, "near_sweeps")),
        1024.0 * static_cast<double>(rss_after - rss_before) / n, std::abs(total_energy(engine) - e0) / e0,
        engine.observe().energy.balance_relative_error(e0), median(clock_GHz), median(core_share),
        *std::min_element(core_share.begin(), core_share.end()));
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pdamp_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
