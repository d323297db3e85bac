/// The reduced-order model: the damper table, its files, its interpolation, the harmonic
/// balance with its stability, branches and sweeps (docs/rom.md).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <numbers>
#include <sstream>

#include "pdamp/errors.hpp"
#include "pdamp/rom/prediction_files.hpp"
#include "pdamp/rom/table_files.hpp"
#include "pdamp/store/sqlite.hpp"
#include "test_support.hpp"

using namespace pdamp;
using namespace pdamp::rom;

namespace {

constexpr double pi = std::numbers::pi;

/// A table whose every point is `point(A, f)`.
DamperTable table_of(const std::vector<double>& amplitudes_m, const std::vector<double>& frequencies_hz,
                     const std::function<TablePoint(double, double)>& point, double gravity_m_s2 = 9.81) {
  DamperTable t;
  t.source = "test";
  t.bed_mass_kg = 0.01;
  t.gravity_m_s2 = gravity_m_s2;
  t.rows = amplitudes_m;
  t.frequencies_hz = frequencies_hz;
  for (const double f : frequencies_hz) {
    for (const double a : amplitudes_m) t.points.push_back(point(a, f));
  }
  return t;
}

/// A table of Γ rows whose every point is `point(Γ, f)`.
DamperTable gamma_table_of(const std::vector<double>& gammas, const std::vector<double>& frequencies_hz,
                           const std::function<TablePoint(double, double)>& point) {
  DamperTable t = table_of(gammas, frequencies_hz, point);
  t.row_axis = RowAxis::gamma;
  return t;
}

std::vector<double> geometric(double first, double last, int n) {
  std::vector<double> v;
  v.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) v.push_back(first * std::pow(last / first, static_cast<double>(i) / (n - 1)));
  return v;
}

DamperTable constant_table(double m_kg, double c_N_s_m, double gravity_m_s2 = 9.81) {
  return table_of(
      geometric(1e-9, 10.0, 7), {2.0, 5.0, 11.0, 30.0, 60.0},
      [&](double, double) {
        return TablePoint{m_kg, c_N_s_m, 0.0, 0.0, true};
      },
      gravity_m_s2);
}

/// The Table 1 host with the experiment's damping, and the synthetic lift-off bed's table.
const HostSdof table1_host{0.0376, 470.0, 0.01};
TableInterpolator liftoff_table() {
  const auto file = test::source_dir() / "data" / "rom" / "synthetic_liftoff.csv";
  return TableInterpolator(read_damper_table(file), file.string());
}

std::complex<double> dynamic_stiffness(const HostSdof& h, double m, double c, double omega) {
  return {h.stiffness_N_m - omega * omega * (h.mass_kg + m), omega * (h.damping_N_s_m + c)};
}

/// A|Z(A)| − |R| from the interpolator's point values: independent of the profile and root finder.
double residual(const TableInterpolator& t, const HostSdof& h, double force_N, double a, double f) {
  const auto v = t.at(a, f);
  REQUIRE(v);
  return a * std::abs(dynamic_stiffness(h, v->m_app_kg, v->c_eq_N_s_m, 2 * pi * f)) - force_N;
}

/// The residual sampled densely in ln A over the amplitudes the table covers at f.
struct Samples {
  std::vector<double> amplitude_m, residual;
};
Samples sample(const TableInterpolator& t, const HostSdof& h, double force_N, double f, int n) {
  const AmplitudeProfile p = t.profile(f);
  Samples s;
  for (int i = 0; i <= n; ++i) {
    const double a =
        std::exp(p.log_amplitude.front() +
                 (p.log_amplitude.back() - p.log_amplitude.front()) * i / static_cast<double>(n) * (1 - 1e-12) + 1e-13);
    s.amplitude_m.push_back(a);
    s.residual.push_back(residual(t, h, force_N, a, f));
  }
  return s;
}

std::vector<std::size_t> sign_changes(const Samples& s) {
  std::vector<std::size_t> at;
  for (std::size_t i = 0; i + 1 < s.residual.size(); ++i) {
    if ((s.residual[i] < 0) != (s.residual[i + 1] < 0)) at.push_back(i);
  }
  return at;
}

}  // namespace

TEST_CASE("rom: a constant table reproduces the linear SDOF closed form, force and base excitation") {
  const double m = 0.004, c = 0.03;
  for (const double g : {9.81, 0.0}) {
    const TableInterpolator table(constant_table(m, c, g));
    for (const auto kind : {ExcitationKind::force, ExcitationKind::base}) {
      const Excitation e{kind, kind == ExcitationKind::force ? 0.05 : 1e-4};
      for (const auto spacing : {Spacing::linear, Spacing::log}) {
        CAPTURE(g);
        CAPTURE(static_cast<int>(kind));
        const auto f = frequencies_of({2.0, 60.0, 577, spacing});
        const ResponseCurve curve = predict_response(table, table1_host, e, f);
        REQUIRE(curve.points.size() == f.size());
        for (const FrequencyResponse& p : curve.points) {
          CAPTURE(p.frequency_hz);
          const double omega = 2 * pi * p.frequency_hz;
          const std::complex<double> z = dynamic_stiffness(table1_host, m, c, omega);
          const std::complex<double> reference = kind == ExcitationKind::force
                                                     ? std::complex<double>(table1_host.stiffness_N_m, 0)
                                                     : std::complex<double>(table1_host.stiffness_N_m, omega * 0.01);
          const std::complex<double> ratio = reference / z;
          const double amplitude =
              std::abs(ratio) * (kind == ExcitationKind::force ? e.amplitude / 470.0 : e.amplitude);
          REQUIRE(p.solutions.size() == 1);
          const Solution& s = p.solutions[0];
          CHECK(std::abs(s.amplitude_m - amplitude) <= 1e-12 * amplitude);
          CHECK(std::abs(s.ratio - ratio) <= 1e-12 * std::abs(ratio));
          CHECK(s.stability == Stability::stable);
          CHECK(!p.solution_below);
          CHECK(!p.solution_above);
          CHECK(!s.unsettled);
          CHECK(s.on_sweep_up);
          CHECK(s.on_sweep_down);
          CHECK(s.branch == 1);
        }
        CHECK(curve.jumps_up.empty());
        CHECK(curve.jumps_down.empty());
      }
    }
  }
}

TEST_CASE("rom: the table's interpolation is exact on its nodes and linear in ln A along a column") {
  const auto amplitudes = geometric(1e-4, 2e-2, 6);
  const std::vector<double> frequencies{10, 14, 20, 31};
  const DamperTable t = table_of(amplitudes, frequencies, [](double a, double f) {
    return TablePoint{std::sin(1e3 * a + f), std::cos(a * f), a * f, 1 / f, true};
  });
  const TableInterpolator table(t);
  for (std::size_t j = 0; j < frequencies.size(); ++j) {
    for (std::size_t i = 0; i < amplitudes.size(); ++i) {
      const auto v = table.at(amplitudes[i], frequencies[j]);
      REQUIRE(v);
      CHECK(v->m_app_kg == t.at(i, j).m_app_kg);
      CHECK(v->c_eq_N_s_m == t.at(i, j).c_eq_N_s_m);
      CHECK(v->m_app_spread_kg == t.at(i, j).m_app_spread_kg);
      CHECK(v->c_eq_spread_N_s_m == t.at(i, j).c_eq_spread_N_s_m);
      if (i + 1 == amplitudes.size()) continue;
      // A quarter of the way in ln A from node i to node i + 1.
      const double a = std::exp(0.75 * std::log(amplitudes[i]) + 0.25 * std::log(amplitudes[i + 1]));
      const auto w = table.at(a, frequencies[j]);
      REQUIRE(w);
      CHECK(w->m_app_kg ==
            doctest::Approx(0.75 * t.at(i, j).m_app_kg + 0.25 * t.at(i + 1, j).m_app_kg).scale(1.0).epsilon(1e-13));
      CHECK(w->c_eq_N_s_m ==
            doctest::Approx(0.75 * t.at(i, j).c_eq_N_s_m + 0.25 * t.at(i + 1, j).c_eq_N_s_m).scale(1.0).epsilon(1e-13));
    }
  }
  // Never extrapolated: outside the amplitudes or the frequencies there is no value.
  CHECK(!table.at(0.99e-4, 10));
  CHECK(!table.at(2.01e-2, 10));
  CHECK(!table.at(1e-3, 9.99));
  CHECK(!table.at(1e-3, 31.01));
}

TEST_CASE("rom: between frequency columns the table is interpolated at constant Gamma, linearly in f") {
  // Amplitudes 4^i and frequencies 2^j: node (i + 1, j) and node (i, j + 1) share one Γ.
  const std::vector<double> amplitudes{1e-4, 4e-4, 16e-4, 64e-4}, frequencies{5, 10, 20};
  const DamperTable t = table_of(amplitudes, frequencies, [](double a, double f) {
    return TablePoint{1e3 * a + f, a * f * f, 0, 0, true};
  });
  const TableInterpolator table(t);
  for (std::size_t j = 0; j + 1 < frequencies.size(); ++j) {
    for (std::size_t i = 0; i + 1 < amplitudes.size(); ++i) {
      for (const double weight : {0.25, 0.5, 0.9}) {
        const double f = (1 - weight) * frequencies[j] + weight * frequencies[j + 1];
        // The Γ of node (i + 1, j): A = A_{i+1} (f_j / f)².
        const double a = amplitudes[i + 1] * std::pow(frequencies[j] / f, 2);
        const auto v = table.at(a, f);
        REQUIRE(v);
        CHECK(v->m_app_kg == doctest::Approx((1 - weight) * t.at(i + 1, j).m_app_kg + weight * t.at(i, j + 1).m_app_kg)
                                 .scale(1.0)
                                 .epsilon(1e-12));
      }
    }
  }
  // Weightless: at constant A instead.
  const DamperTable w = table_of(
      amplitudes, frequencies,
      [](double a, double f) {
        return TablePoint{1e3 * a + f, a * f * f, 0, 0, true};
      },
      0.0);
  const auto v = TableInterpolator(w).at(4e-4, 7.5);
  REQUIRE(v);
  CHECK(v->m_app_kg == doctest::Approx(0.5 * (0.4 + 5) + 0.5 * (0.4 + 10)).scale(1.0).epsilon(1e-13));
}

TEST_CASE("rom: a table of Gamma rows is read at the query's Gamma: exact on its nodes, linear in ln Gamma and f") {
  const std::vector<double> gammas{0.5, 1.0, 2.5, 6.0, 15.0}, frequencies{15, 19.5, 24, 30};
  // Linear in ln Γ and in f: the interpolation reproduces it everywhere inside.
  const auto m = [](double gamma, double f) { return 0.004 * (1 - 0.1 * std::log(gamma)) + 1e-5 * f; };
  const DamperTable t = gamma_table_of(gammas, frequencies, [&](double gamma, double f) {
    return TablePoint{m(gamma, f), 0.01 * gamma * f, gamma / f, f, true};
  });
  const TableInterpolator table(t);
  const auto amplitude = [&](double gamma, double f) { return gamma * t.gravity_m_s2 / std::pow(2 * pi * f, 2); };
  for (std::size_t j = 0; j < frequencies.size(); ++j) {
    for (std::size_t i = 0; i < gammas.size(); ++i) {
      CHECK(t.gamma(i, j) == gammas[i]);
      CHECK(t.amplitude_m(i, j) == test::relative(amplitude(gammas[i], frequencies[j])).epsilon(1e-15));
      const auto v = table.at(t.amplitude_m(i, j), frequencies[j]);
      REQUIRE(v);
      CHECK(*v == static_cast<const DamperValues&>(t.at(i, j)));
    }
  }
  for (const double f : {15.0, 17.0, 21.3, 27.0, 30.0}) {
    CAPTURE(f);
    for (const double gamma : {0.5, 0.7, 1.9, 9.0, 15.0}) {
      const auto v = table.at(amplitude(gamma, f), f);
      REQUIRE(v);
      CHECK(v->m_app_kg == test::relative(m(gamma, f)).epsilon(1e-12));
    }
    // Every frequency covers the whole Γ range (amplitude rows cover a little less between columns).
    const AmplitudeProfile p = table.profile(f);
    CHECK(p.lowest_amplitude_m() == test::relative(amplitude(0.5, f)).epsilon(1e-12));
    CHECK(p.highest_amplitude_m() == test::relative(amplitude(15.0, f)).epsilon(1e-12));
    CHECK(!table.at(amplitude(0.499, f), f));
    CHECK(!table.at(amplitude(15.01, f), f));
  }
  // Γ needs gravity.
  DamperTable weightless = t;
  weightless.gravity_m_s2 = 0;
  CHECK_THROWS_WITH_AS(validate_damper_table(weightless, "w"),
                       doctest::Contains("the rows are gammas but gravity_m_s2 = 0"), InputError);
}

TEST_CASE("rom: a frequency's amplitude profile is the interpolation itself, and never leaves the nodes' range") {
  const TableInterpolator table = liftoff_table();
  const DamperTable& t = table.table();
  double m_min = HUGE_VAL, m_max = -HUGE_VAL;
  for (const auto& p : t.points) m_min = std::min(m_min, p.m_app_kg), m_max = std::max(m_max, p.m_app_kg);
  // c_eq is 0 up to lift-off: it is compared on the scale of the table's largest.
  double c_max = 0.0;
  for (const auto& p : t.points) c_max = std::max(c_max, p.c_eq_N_s_m);
  for (double f = 10; f <= 28; f += 0.37) {
    const AmplitudeProfile p = table.profile(f);
    REQUIRE(p.covers_anything());
    for (std::size_t k = 0; k < p.segment_count(); ++k) {
      for (const double u : {0.0, 0.3, 0.71, 1.0}) {
        const double s = p.log_amplitude[k] + u * (p.log_amplitude[k + 1] - p.log_amplitude[k]);
        const auto direct = table.at(std::exp(s), f);
        REQUIRE(direct);
        const DamperValues along = p.in_segment(k, s);
        CHECK(along.m_app_kg == test::relative(direct->m_app_kg).epsilon(1e-12));
        CHECK(along.c_eq_N_s_m == doctest::Approx(direct->c_eq_N_s_m).scale(c_max).epsilon(1e-12));
        CHECK(along.m_app_kg >= m_min * (1 - 1e-15));
        CHECK(along.m_app_kg <= m_max * (1 + 1e-15));
      }
    }
  }
}

TEST_CASE("rom: the lift-off table has three solutions near resonance, the middle one a saddle, all found") {
  const TableInterpolator table = liftoff_table();
  const Excitation force{ExcitationKind::force, 0.05};
  const auto f = frequencies_of({14.0, 22.0, 401, Spacing::linear});
  const ResponseCurve curve = predict_response(table, table1_host, force, f);
  int three = 0;
  for (const FrequencyResponse& p : curve.points) {
    CAPTURE(p.frequency_hz);
    // Every root is a root of the point-wise interpolation, to the refinement's tolerance.
    for (const Solution& s : p.solutions) {
      CHECK(std::abs(residual(table, table1_host, 0.05, s.amplitude_m, p.frequency_hz)) <= 1e-11 * 0.05);
    }
    // The same count as a dense scan of the residual, where the scan can resolve the roots.
    const Samples samples = sample(table, table1_host, 0.05, p.frequency_hz, 5000);
    const auto changes = sign_changes(samples);
    bool resolvable = true;
    for (std::size_t i = 1; i < p.solutions.size(); ++i) {
      resolvable = resolvable && p.solutions[i].amplitude_m / p.solutions[i - 1].amplitude_m > 1.01;
    }
    if (resolvable) {
      REQUIRE(changes.size() == p.solutions.size());
      for (std::size_t r = 0; r < changes.size(); ++r) {
        CHECK(p.solutions[r].amplitude_m >= samples.amplitude_m[changes[r]] * (1 - 1e-12));
        CHECK(p.solutions[r].amplitude_m <= samples.amplitude_m[changes[r] + 1] * (1 + 1e-12));
      }
    }
    CHECK(p.solution_below == (samples.residual.front() > 0));
    CHECK(p.solution_above == (samples.residual.back() < 0));
    if (p.solutions.size() == 3) {
      ++three;
      CHECK(p.solutions[0].stability == Stability::stable);
      CHECK(p.solutions[1].stability == Stability::unstable);
      CHECK(p.solutions[1].saddle);
      CHECK(p.solutions[2].stability == Stability::stable);
      CHECK(p.solutions[0].branch != p.solutions[1].branch);
      CHECK(p.solutions[1].branch != p.solutions[2].branch);
    } else {
      REQUIRE(p.solutions.size() <= 1);
    }
  }
  CHECK(three >= 10);  // 17.5 to 17.9 Hz at a step of 0.02 Hz
}

TEST_CASE("rom: stepped sines up and down jump where the stable branches end, at the turning points") {
  const TableInterpolator table = liftoff_table();
  const auto f = frequencies_of({14.0, 22.0, 401, Spacing::linear});
  const ResponseCurve curve = predict_response(table, table1_host, {ExcitationKind::force, 0.05}, f);
  REQUIRE(curve.jumps_up.size() == 1);
  REQUIRE(curve.jumps_down.size() == 1);
  const Jump& up = curve.jumps_up[0];
  const Jump& down = curve.jumps_down[0];
  CHECK(up.to_amplitude_m < up.from_amplitude_m);      // falls off the resonant branch
  CHECK(down.to_amplitude_m > down.from_amplitude_m);  // jumps up onto it
  CHECK(up.to_frequency_hz > down.to_frequency_hz);    // hysteresis: the up-jump is the higher

  // The turning points from the residual alone: the local extrema of A|Z(A)| over A cross F0
  // between the two frequencies of each jump.
  auto extremes = [&](double frequency_hz) {
    const Samples s = sample(table, table1_host, 0.05, frequency_hz, 20000);
    std::vector<double> minima, maxima;
    for (std::size_t i = 1; i + 1 < s.residual.size(); ++i) {
      if (s.residual[i] < s.residual[i - 1] && s.residual[i] <= s.residual[i + 1]) minima.push_back(s.residual[i]);
      if (s.residual[i] > s.residual[i - 1] && s.residual[i] >= s.residual[i + 1]) maxima.push_back(s.residual[i]);
    }
    return std::pair{minima, maxima};
  };
  auto lowest = [](const std::vector<double>& v) {
    return v.empty() ? HUGE_VAL : *std::min_element(v.begin(), v.end());
  };
  auto highest = [](const std::vector<double>& v) {
    return v.empty() ? -HUGE_VAL : *std::max_element(v.begin(), v.end());
  };
  // Sweeping up, the resonant branch ends where the residual's local minimum rises through 0.
  CHECK(lowest(extremes(up.from_frequency_hz).first) < 0);
  CHECK(lowest(extremes(up.to_frequency_hz).first) > 0);
  // Sweeping down, the low branch ends where the local maximum falls through 0.
  CHECK(highest(extremes(down.from_frequency_hz).second) > 0);
  CHECK(highest(extremes(down.to_frequency_hz).second) < 0);

  // Between the jumps the sweeps hold different stable solutions; elsewhere the same one.
  for (const FrequencyResponse& p : curve.points) {
    int up_count = 0, down_count = 0;
    double up_a = 0, down_a = 0;
    for (const Solution& s : p.solutions) {
      if (s.on_sweep_up) ++up_count, up_a = s.amplitude_m;
      if (s.on_sweep_down) ++down_count, down_a = s.amplitude_m;
      CHECK((!(s.on_sweep_up || s.on_sweep_down) || s.stability == Stability::stable));
    }
    if (p.solutions.empty()) continue;
    CHECK(up_count == 1);
    CHECK(down_count == 1);
    const bool hysteresis = p.frequency_hz > down.to_frequency_hz && p.frequency_hz < up.to_frequency_hz;
    CHECK((up_a > down_a) == hysteresis);
  }
}

TEST_CASE("rom: the stability classification is the slow flow's, by its numerical Jacobian") {
  // Slow flow Ẋ = (R − Z(|X|) X) / (2iω(M + m_app)); stable iff both eigenvalues of its
  // Jacobian have negative real parts. Checked on the lift-off table and on a weightless table
  // whose c_eq falls steeply with A up to 1 mm (negative slow-flow damping off resonance).
  const DamperTable falling = table_of(
      geometric(1e-5, 1e-1, 9), {5.0, 40.0},
      [](double a, double) {
        return TablePoint{0.0, 0.004 * std::max(0.0, std::log(1e-3 / a)), 0, 0, true};
      },
      0.0);
  struct Case {
    TableInterpolator table;
    HostSdof host;
    double force_N;
    std::vector<double> frequencies;
  };
  const Case cases[] = {
      {liftoff_table(), table1_host, 0.05, frequencies_of({17.0, 18.2, 61, Spacing::linear})},
      {TableInterpolator(falling), {0.0376, 470, 0.0002}, 0.2, frequencies_of({12, 24, 121, Spacing::linear})}};
  int unstable_growth = 0, checked = 0;
  for (const Case& c : cases) {
    const ResponseCurve curve = predict_response(c.table, c.host, {ExcitationKind::force, c.force_N}, c.frequencies);
    for (const FrequencyResponse& p : curve.points) {
      const double omega = 2 * pi * p.frequency_hz;
      const AmplitudeProfile profile = c.table.profile(p.frequency_hz);
      for (const Solution& s : p.solutions) {
        // Finite differences must not straddle a knot of the piecewise-linear table.
        const double sa = std::log(s.amplitude_m);
        bool near_knot = false;
        for (const double k : profile.log_amplitude) near_knot = near_knot || std::abs(k - sa) < 1e-5;
        if (near_knot) continue;
        const std::complex<double> x0 = s.ratio * (c.force_N / c.host.stiffness_N_m);
        auto flow = [&](std::complex<double> x) {
          const auto v = c.table.at(std::abs(x), p.frequency_hz);
          REQUIRE(v);
          const auto z = dynamic_stiffness(c.host, v->m_app_kg, v->c_eq_N_s_m, omega);
          return (c.force_N - z * x) / (std::complex<double>(0, 2 * omega) * (c.host.mass_kg + v->m_app_kg));
        };
        const double h = 1e-7 * s.amplitude_m;
        const std::complex<double> d_re = (flow(x0 + h) - flow(x0 - h)) / (2 * h);
        const std::complex<double> d_im =
            (flow(x0 + std::complex<double>(0, h)) - flow(x0 - std::complex<double>(0, h))) / (2 * h);
        const double trace = d_re.real() + d_im.imag();
        const double det = d_re.real() * d_im.imag() - d_im.real() * d_re.imag();
        const bool stable = det > 0 && trace < 0;
        CAPTURE(p.frequency_hz);
        CAPTURE(s.amplitude_m);
        CHECK(stable == (s.stability == Stability::stable));
        CHECK(s.saddle == (det < 0));
        unstable_growth += s.slow_flow_growth && det > 0;
        ++checked;
      }
    }
  }
  CHECK(checked > 100);
  CHECK(unstable_growth > 0);
}

TEST_CASE("rom: a response outside the characterised amplitudes is flagged on its side, never extrapolated") {
  // A constant table on a narrow band of amplitudes: the exact response says where it lies.
  const double m = 0.004, c = 0.03;
  const DamperTable t = table_of({1e-4, 1e-3}, {12.0, 24.0}, [&](double, double) {
    return TablePoint{m, c, 0, 0, true};
  });
  const TableInterpolator table(t);
  const auto f = frequencies_of({12.0, 24.0, 241, Spacing::linear});
  const ResponseCurve curve = predict_response(table, table1_host, {ExcitationKind::force, 0.02}, f);
  int below = 0, above = 0, inside = 0;
  for (const FrequencyResponse& p : curve.points) {
    const double exact = 0.02 / std::abs(dynamic_stiffness(table1_host, m, c, 2 * pi * p.frequency_hz));
    CAPTURE(p.frequency_hz);
    CHECK(p.solution_below == (exact < p.lowest_amplitude_m));
    CHECK(p.solution_above == (exact > p.highest_amplitude_m));
    CHECK(p.solutions.size() == (exact >= p.lowest_amplitude_m && exact <= p.highest_amplitude_m ? 1u : 0u));
    below += p.solution_below;
    above += p.solution_above;
    inside += !p.solutions.empty();
  }
  CHECK(below > 0);
  CHECK(above > 0);
  CHECK(inside > 0);
  CHECK(covers_something(curve));
  // At constant Γ between the columns, 12 and 24 Hz, the band narrows: A from 1e-4 (24/f)² to 1e-3 (12/f)².
  const AmplitudeProfile p = table.profile(18.0);
  CHECK(std::abs(p.lowest_amplitude_m() / (1e-4 * 16 / 9) - 1) < 1e-12);
  CHECK(std::abs(p.highest_amplitude_m() / (1e-3 * 4 / 9) - 1) < 1e-12);
  // Nothing covered: all outside.
  const ResponseCurve none = predict_response(table, table1_host, {ExcitationKind::force, 100.0}, f);
  CHECK(!covers_something(none));
  CHECK(coverage_summary(none).find("above") != std::string::npos);
}

TEST_CASE("rom: a solution that leans on an unsettled table point is flagged") {
  DamperTable t = constant_table(0.004, 0.03);
  // The node nearest the 11 Hz solution is unsettled.
  const TableInterpolator clean(t);
  const double a =
      predict_response(clean, table1_host, {ExcitationKind::force, 0.05}, {11.0}).points[0].solutions[0].amplitude_m;
  const auto& amplitudes = t.rows;
  const std::size_t i =
      static_cast<std::size_t>(std::upper_bound(amplitudes.begin(), amplitudes.end(), a) - amplitudes.begin());
  t.at(i, 2).settled = false;  // column 2 is 11 Hz
  const TableInterpolator flagged(t);
  const ResponseCurve curve = predict_response(flagged, table1_host, {ExcitationKind::force, 0.05}, {11.0, 30.0});
  CHECK(curve.points[0].solutions[0].unsettled);
  CHECK(curve.points[0].solutions[0].amplitude_m == a);  // values still used
  CHECK(!curve.points[1].solutions[0].unsettled);
  bool unsettled = false;
  CHECK(flagged.at(amplitudes[i], 11.0, &unsettled).has_value());
  CHECK(unsettled);
  CHECK(flagged.at(amplitudes[i], 5.0, &unsettled).has_value());
  CHECK(!unsettled);
}

TEST_CASE("rom: the table's CSV and JSON read back to the same bits") {
  const DamperTable t = table_of(geometric(1.234e-5, 0.0456, 5), {3.3, 7.1, 19.0}, [](double a, double f) {
    return TablePoint{std::sin(a * 1e4) / 3, std::exp(-f) * 7, a / 3, f / 7, std::fmod(a * 1e5, 2.0) < 1};
  });
  validate_damper_table(t, "t");
  CHECK(parse_damper_table_csv(damper_table_csv(t), "csv") == t);
  CHECK(parse_damper_table_json(damper_table_json(t), "json") == t);
  // Rows in any order, CRLF line ends, spaces around fields and no gamma column read the same.
  std::string shuffled =
      "# format = pdamp damper table 1\r\n# source = test\r\n# bed_mass_kg = 0.01\r\n"
      "# gravity_m_s2 = 9.81\r\n"
      "settled , c_eq_spread_N_s_m, m_app_spread_kg, c_eq_N_s_m, m_app_kg, frequency_hz, amplitude_m\r\n";
  for (std::size_t k = t.points.size(); k-- > 0;) {
    const TablePoint& p = t.points[k];
    const std::size_t i = k % t.rows.size(), j = k / t.rows.size();
    char line[512];
    std::snprintf(line, sizeof line, "%d, %.17g, %.17g, %.17g, %.17g, %.17g, %.17g\r\n", p.settled ? 1 : 0,
                  p.c_eq_spread_N_s_m, p.m_app_spread_kg, p.c_eq_N_s_m, p.m_app_kg, t.frequencies_hz[j], t.rows[i]);
    shuffled += line;
  }
  CHECK(parse_damper_table_csv(shuffled, "shuffled") == t);
  // A table of Γ rows: '# rows = gamma' and the gammas member; amplitude_m derived, may be left out.
  const DamperTable g = gamma_table_of({0.4, 1.7, 12.0}, {3.3, 7.1, 19.0}, [](double gamma, double f) {
    return TablePoint{std::sin(gamma) / 3, std::exp(-f) * 7, gamma / 3, f / 7, gamma > 1};
  });
  const std::string g_csv = damper_table_csv(g);
  CHECK(g_csv.find("\n# rows = gamma\n") != std::string::npos);
  CHECK(parse_damper_table_csv(g_csv, "csv") == g);
  CHECK(damper_table_json(g).find("\"gammas\": [0.4, 1.7, 12]") != std::string::npos);
  CHECK(parse_damper_table_json(damper_table_json(g), "json") == g);
  std::string without_amplitudes;
  std::istringstream lines(g_csv);
  for (std::string line; std::getline(lines, line);) {
    without_amplitudes += (line[0] == '#' ? line : line.substr(line.find(',') + 1)) + "\n";
  }
  CHECK(parse_damper_table_csv(without_amplitudes, "csv") == g);
  // A weightless table: gamma left empty.
  DamperTable w = t;
  w.gravity_m_s2 = 0;
  CHECK(parse_damper_table_csv(damper_table_csv(w), "csv") == w);
  CHECK(parse_damper_table_json(damper_table_json(w), "json") == w);
}

TEST_CASE("rom: a bad table is refused with the reason") {
  const DamperTable good = table_of({1e-4, 1e-3, 1e-2}, {10, 20}, [](double, double) {
    return TablePoint{0.01, 0.1, 0.001, 0.01, true};
  });
  const std::string csv = damper_table_csv(good);
  auto replaced = [](std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    REQUIRE(at != std::string::npos);
    return text.replace(at, from.size(), to);
  };
  auto refuses = [](const std::function<void()>& read, const std::string& reason) {
    try {
      read();
      FAIL("accepted; expected: " << reason);
    } catch (const InputError& e) {
      const std::string message = e.what();
      CAPTURE(message);
      CHECK(message.find(reason) != std::string::npos);
    }
  };
  auto csv_refuses = [&](const std::string& text, const std::string& reason) {
    refuses([&] { parse_damper_table_csv(text, "t.csv"); }, reason);
  };
  const auto first_row = csv.find("\n1e-04,10,") + 1;
  csv_refuses(csv.substr(0, first_row) + csv.substr(csv.find('\n', first_row) + 1), "not rectangular");
  csv_refuses(replaced(csv, "\n0.001,20,", "\n1e-04,20,"), "is also on line");
  csv_refuses(replaced(csv, "0.1,0.001,", "nan,0.001,"), "c_eq_N_s_m = 'nan': not a finite number");
  csv_refuses(replaced(csv, "0.1,0.001,", "inf,0.001,"), "not a finite number");
  csv_refuses(replaced(csv, "0.001,0.01,1\n", "-0.001,0.01,1\n"), "a spread (standard deviation) must be >= 0");
  csv_refuses(replaced(csv, "\n0.001,20,", "\n-0.001,20,"), "amplitude_m = -0.001: must be > 0");
  csv_refuses(replaced(csv, "\n0.001,20,", "\n0.001,-20,"), "frequency_hz = -20: must be > 0");
  csv_refuses(replaced(csv, "pdamp damper table 1", "pdamp damper table 2"), "this pdamp reads 'pdamp damper table 1'");
  csv_refuses(replaced(csv, "# bed_mass_kg = 0.01\n", ""), "'# bed_mass_kg = ...' is missing");
  csv_refuses(replaced(csv, "# bed_mass_kg = 0.01", "# bed_mass_kg = -1"), "bed_mass_kg = -1");
  csv_refuses(replaced(csv, ",settled\n", ",setled\n"), "unknown column 'setled'");
  csv_refuses(replaced(csv, ",settled\n", "\n"), "column 'settled' is missing");
  csv_refuses(replaced(csv, ",1\n0.001,10,", ",yes\n0.001,10,"), "settled = 'yes'");
  // Γ that does not match A, f and g.
  csv_refuses(replaced(csv, "\n0.001,20,", "\n0.001,20,1.2,"), "fields for");
  const auto gamma_at = csv.find("\n0.01,20,") + 9;
  csv_refuses(csv.substr(0, gamma_at) + "1" + csv.substr(gamma_at), "but A (2 pi f)^2 / g");
  // A table of Γ rows: its amplitudes follow from Γ, f and g; it needs its gamma column.
  const DamperTable gammas = gamma_table_of({0.5, 2}, {10, 20}, [](double, double) { return TablePoint{}; });
  const std::string g_csv = damper_table_csv(gammas);
  csv_refuses(replaced(g_csv, "\n0.0012424", "\n0.0012425"), "but gamma g / (2 pi f)^2 = 0.0012424");
  csv_refuses(replaced(g_csv, ",gamma,", ",gama,"), "unknown column 'gama'");
  csv_refuses(replaced(g_csv, ",gamma,", ","), "column 'gamma' is missing (the table's rows are gammas");
  csv_refuses(replaced(g_csv, "# rows = gamma", "# rows = gammas"), "rows = 'gammas': must be amplitude or gamma");
  csv_refuses(replaced(g_csv, "# rows = gamma\n", "") + "# rows = gamma\n", "must come before the header row");
  csv_refuses(replaced(g_csv, "# gravity_m_s2 = 9.81", "# gravity_m_s2 = 0"), "the rows are gammas but gravity_m_s2");
  // One frequency only.
  const DamperTable one = table_of({1e-4, 1e-3}, {10}, [](double, double) { return TablePoint{}; });
  refuses([&] { validate_damper_table(one, "t"); }, "1 frequency: the table needs at least two on each axis");
  refuses([&] { parse_damper_table_csv(damper_table_csv(one), "t.csv"); }, "1 frequency");

  const std::string json = damper_table_json(good);
  auto json_refuses = [&](const std::string& text, const std::string& reason) {
    refuses([&] { parse_damper_table_json(text, "t.json"); }, reason);
  };
  json_refuses("{\"format\": ", "not valid JSON");
  json_refuses("[1, 2]", "must be a JSON object");
  json_refuses(replaced(json, "\"source\"", "\"sauce\""), "unknown member \"sauce\"");
  json_refuses(replaced(json, "\"source\": \"test\",", ""), "member \"source\" is missing");
  json_refuses(replaced(json, "\"source\": \"test\",", "\"source\": \"test\", \"source\": \"x\","), "given twice");
  json_refuses(replaced(json, "\"format_version\": 1", "\"format_version\": 2"), "version 2");
  json_refuses(replaced(json, "[1e-04, 0.001, 0.01]", "[1e-04, 0.001]"), "3 values for 2 amplitudes");
  json_refuses(replaced(json, "[1e-04, 0.001, 0.01]", "[0.01, 0.001, 1e-04]"), "strictly increasing");
  json_refuses(replaced(json, "[1e-04, 0.001, 0.01]", "[-1e-04, 0.001, 0.01]"), "amplitude -1e-04 m");
  json_refuses(replaced(json, "[10, 20]", "[10]"), "rows for 1 frequencies");
  json_refuses(replaced(json, "[0.1, 0.1, 0.1]", "[0.1, 1e999, 0.1]"), "must be a finite number");
  json_refuses(replaced(json, "[0.1, 0.1, 0.1]", "[0.1, \"0.1\", 0.1]"),
               "$.c_eq_N_s_m[0][1] is text: must be a number");
  json_refuses(replaced(json, "[true, true, true]", "[true, 1, true]"), "must be true or false");
  json_refuses(replaced(json, "\"amplitudes_m\"", "\"gammas\": [1, 2], \"amplitudes_m\""),
               "give exactly one of the members \"amplitudes_m\" (rows of amplitudes, m) and \"gammas\"");
  json_refuses(replaced(json, "\"amplitudes_m\": [1e-04, 0.001, 0.01],", ""), "give exactly one of the members");
  // A source that would reach a terminal as an escape sequence.
  json_refuses(replaced(json, "\"source\": \"test\"", "\"source\": \"\\u001b[2Jx\""),
               "without control characters (27 at character 1)");
}

TEST_CASE("rom: bad hosts, excitations and frequency ranges are refused with the reason") {
  const TableInterpolator table(constant_table(0.004, 0.03));
  auto refuses = [&](const HostSdof& h, const Excitation& e, const std::vector<double>& f, const std::string& reason) {
    try {
      predict_response(table, h, e, f);
      FAIL("accepted; expected: " << reason);
    } catch (const InputError& error) {
      const std::string message = error.what();
      CAPTURE(message);
      CHECK(message.find(reason) != std::string::npos);
    }
  };
  const Excitation force{ExcitationKind::force, 0.05};
  refuses({0, 470, 0.01}, force, {10}, "host mass M (kg) = 0");
  refuses({0.0376, -1, 0.01}, force, {10}, "host stiffness K (N/m) = -1");
  refuses({0.0376, 470, -0.01}, force, {10}, "host damping C (N s/m) = -0.01: must be a finite number >= 0");
  refuses({0.0376, 470, NAN}, force, {10}, "host damping C");
  refuses(table1_host, {ExcitationKind::force, 0}, {10}, "force amplitude F0 (N) = 0");
  refuses(table1_host, {ExcitationKind::base, -1e-3}, {10}, "base amplitude Y (m) = -0.001");
  refuses(table1_host, force, {1.0, 10}, "frequency 1 Hz is outside the table's frequencies, 2 to 60 Hz");
  refuses(table1_host, force, {61.0}, "outside the table's frequencies");

  auto range_refuses = [](const std::string& text, const std::string& reason) {
    try {
      frequencies_of(parse_frequency_range(text, Spacing::linear, "--freq"));
      FAIL("accepted " << text);
    } catch (const InputError& error) {
      const std::string message = error.what();
      CAPTURE(message);
      CHECK(message.find(reason) != std::string::npos);
    }
  };
  range_refuses("10:30", "expected three fields");
  // An empty field, a trailing colon included, is no value taken as missing.
  range_refuses("15:20:5:", "--freq '15:20:5:': expected three fields separated by ':', not 4 (write START:STOP:COUNT");
  range_refuses(":15:20:5", "not 4");
  range_refuses("15:20:", "'' is not a whole number of frequencies");
  range_refuses("15::5", "'' is not a number of Hz");
  range_refuses("10:x:5", "'x' is not a number of Hz");
  range_refuses("10:30:5.5", "'5.5' is not a whole number");
  range_refuses("30:10:5", "needs 0 < start < stop");
  range_refuses("0:10:5", "needs 0 < start < stop");
  range_refuses("-5:10:5", "needs 0 < start < stop");
  range_refuses("5:10:1", "frequency count 1: must be 2 to 100000");
  range_refuses("5:10:100001", "must be 2 to 100000");
  const auto lin = frequencies_of(parse_frequency_range("10:30:5", Spacing::linear, "--freq"));
  CHECK(lin == std::vector<double>{10, 15, 20, 25, 30});
  const auto log = frequencies_of(parse_frequency_range("1:100:3", Spacing::log, "--freq"));
  REQUIRE(log.size() == 3);
  CHECK(log[0] == 1);
  CHECK(log[1] == doctest::Approx(10).scale(1.0).epsilon(1e-14));
  CHECK(log[2] == 100);
}

TEST_CASE("rom: the prediction's CSV and JSON hold one row per solution and per flagged side") {
  const TableInterpolator table = liftoff_table();
  PredictionSetup setup;
  setup.table_name = "synthetic_liftoff.csv";
  setup.table = &table.table();
  setup.host = table1_host;
  setup.excitation = {ExcitationKind::force, 0.05};
  setup.range = {14.0, 26.0, 121, Spacing::linear};
  const ResponseCurve curve = predict_response(table, setup.host, setup.excitation, frequencies_of(setup.range));
  const auto rows = prediction_rows(setup, curve);
  std::size_t expected = 0, flagged_below = 0;
  for (const auto& p : curve.points) {
    expected += p.solutions.size() + p.solution_below + p.solution_above + p.not_covered;
    flagged_below += p.solution_below;
  }
  CHECK(flagged_below > 0);  // above 20 Hz the response falls below 0.1 mm
  CHECK(rows.size() == expected);
  const std::string csv = prediction_csv(setup, curve);
  CHECK(std::count(csv.begin(), csv.end(), '\n') == static_cast<long>(expected + 8));
  CHECK(csv.find("frequency_hz,branch,stability,amplitude_m,response_ratio,phase_deg,gamma,m_app_kg,c_eq_N_s_m,"
                 "m_app_spread_kg,c_eq_spread_N_s_m,loss_factor,loss_factor_bed,sweep_up,sweep_down,flags\n") !=
        std::string::npos);
  CHECK(csv.find(",,,,,,,,,,,,,,solution_below_grid\n") != std::string::npos);
  CHECK(csv.find(",unstable,") != std::string::npos);
  // The JSON is valid and holds the same rows (checked with SQLite's JSON functions).
  const std::string json = prediction_json(setup, curve);
  sqlite::Database db(":memory:");
  sqlite::Statement q(db,
                      "SELECT json_valid(?1), json_array_length(?1, '$.points'), "
                      "json_array_length(?1, '$.jumps.sweep_up'), json_extract(?1, '$.points[0].frequency_hz')");
  q.bind(1, json);
  REQUIRE(q.step());
  CHECK(q.column_int(0) == 1);
  CHECK(q.column_int(1) == static_cast<std::int64_t>(expected));
  CHECK(q.column_int(2) == static_cast<std::int64_t>(curve.jumps_up.size()));
  CHECK(q.column_double(3) == 14.0);
  // Each row's loss factor is ω (C + c_eq) / K.
  for (const auto& row : rows) {
    if (!row.solution) continue;
    const double omega = 2 * pi * row.frequency_hz;
    CHECK(row.loss_factor == test::relative(omega * (0.01 + row.solution->damper.c_eq_N_s_m) / 470).epsilon(1e-14));
    CHECK(row.amplitude_ratio == test::relative(row.solution->amplitude_m * 470 / 0.05).epsilon(1e-12));
  }
}
