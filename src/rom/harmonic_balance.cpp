#include "pdamp/rom/harmonic_balance.hpp"

#include <algorithm>
#include <boost/math/tools/toms748_solve.hpp>
#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include "pdamp/errors.hpp"
#include "text_format.hpp"

namespace pdamp::rom {
namespace {

/// Roots are refined until their bracket is this narrow in ln A (a relative 1e-14 in A).
constexpr double root_tolerance_log_amplitude = 1e-14;

void require(bool ok, const std::string& name, double value, const std::string& rule) {
  if (!ok) throw InputError(name + " = " + text::number(value) + ": must be " + rule);
}

/// The balance along one segment of the profile, in u = ln A − s_a: m_app and c_eq are linear
/// in u, so Z = α + iβ with α, β linear and the residual h(u) = A²|Z|² − |R|² is e^{2s}
/// times a quadratic, minus a constant.
class SegmentResidual {
 public:
  SegmentResidual(const AmplitudeProfile& profile, std::size_t k, const HostSdof& host, double omega,
                  double reference_squared)
      : s_a_(profile.log_amplitude[k]), length_(profile.log_amplitude[k + 1] - s_a_), r2_(reference_squared) {
    const DamperValues& a = profile.values[k];
    const DamperValues& b = profile.values[k + 1];
    const double w2 = omega * omega;
    alpha0_ = host.stiffness_N_m - w2 * (host.mass_kg + a.m_app_kg);
    alpha1_ = -w2 * (b.m_app_kg - a.m_app_kg) / length_;
    beta0_ = omega * (host.damping_N_s_m + a.c_eq_N_s_m);
    beta1_ = omega * (b.c_eq_N_s_m - a.c_eq_N_s_m) / length_;
  }

  double length() const { return length_; }
  double start() const { return s_a_; }
  /// dc_eq / d ln A along the segment.
  double c_eq_slope(double omega) const { return beta1_ / omega; }

  double operator()(double u) const {
    const double alpha = alpha0_ + alpha1_ * u, beta = beta0_ + beta1_ * u;
    return std::exp(2 * (s_a_ + u)) * (alpha * alpha + beta * beta) - r2_;
  }

  /// Where h'(u) = e^{2s} (2q + q') vanishes inside (0, length): h is monotone between them.
  std::vector<double> turning_points() const {
    const double a2 = alpha1_ * alpha1_ + beta1_ * beta1_;
    const double a1 = 2 * (alpha0_ * alpha1_ + beta0_ * beta1_) + a2;
    const double a0 = alpha0_ * alpha0_ + beta0_ * beta0_ + alpha0_ * alpha1_ + beta0_ * beta1_;
    std::vector<double> roots;
    if (a2 == 0) {
      if (a1 != 0) roots.push_back(-a0 / a1);
    } else {
      const double discriminant = a1 * a1 - 4 * a2 * a0;
      if (discriminant >= 0) {
        const double q = -0.5 * (a1 + std::copysign(std::sqrt(discriminant), a1));
        roots.push_back(q / a2);
        if (q != 0) roots.push_back(a0 / q);
      }
    }
    std::vector<double> inside;
    for (const double u : roots) {
      if (u > 0 && u < length_) inside.push_back(u);
    }
    std::sort(inside.begin(), inside.end());
    return inside;
  }

 private:
  double s_a_, length_, r2_;
  double alpha0_, alpha1_, beta0_, beta1_;
};

/// A stretch of one segment on which the residual is monotone.
struct Piece {
  std::size_t segment;
  double u_a, u_b;  ///< in the segment's u
  double h_a, h_b;
};

std::vector<Piece> monotone_pieces(const std::vector<SegmentResidual>& segments) {
  std::vector<Piece> pieces;
  for (std::size_t k = 0; k < segments.size(); ++k) {
    const SegmentResidual& h = segments[k];
    std::vector<double> cuts{0.0};
    for (const double u : h.turning_points()) cuts.push_back(u);
    cuts.push_back(h.length());
    for (std::size_t i = 0; i + 1 < cuts.size(); ++i)
      pieces.push_back({k, cuts[i], cuts[i + 1], h(cuts[i]), h(cuts[i + 1])});
  }
  return pieces;
}

int sign(double x) { return (x > 0) - (x < 0); }

/// +1 where the residual rises through a root, −1 where it falls, 0 where it only touches.
int crossing(std::optional<double> before, std::optional<double> after) {
  const int b = before ? sign(*before) : -(after ? sign(*after) : 0);
  const int a = after ? sign(*after) : -b;
  if (b < 0 && a > 0) return 1;
  if (b > 0 && a < 0) return -1;
  return 0;
}

double refine(const SegmentResidual& h, const Piece& piece) {
  std::uintmax_t iterations = 200;
  const auto bracket = boost::math::tools::toms748_solve(
      h, piece.u_a, piece.u_b, piece.h_a, piece.h_b,
      [](double a, double b) { return std::abs(b - a) <= root_tolerance_log_amplitude; }, iterations);
  if (iterations >= 200) throw RuntimeFailure("harmonic balance: a root did not converge in 200 iterations");
  return 0.5 * (bracket.first + bracket.second);
}

Solution solution_at(const AmplitudeProfile& profile, const SegmentResidual& h, std::size_t segment, double u,
                     int rising, const HostSdof& host, const Excitation& excitation, double omega) {
  Solution s;
  const double log_a = h.start() + u;
  s.amplitude_m = std::exp(log_a);
  s.damper = profile.in_segment(segment, log_a);
  s.unsettled = profile.segment_unsettled[segment];
  const double effective_mass = host.mass_kg + s.damper.m_app_kg;
  const double effective_damping = host.damping_N_s_m + s.damper.c_eq_N_s_m;
  const std::complex<double> z(host.stiffness_N_m - omega * omega * effective_mass, omega * effective_damping);
  const std::complex<double> reference = excitation.kind == ExcitationKind::force
                                             ? std::complex<double>(host.stiffness_N_m, 0.0)
                                             : std::complex<double>(host.stiffness_N_m, omega * host.damping_N_s_m);
  s.ratio = reference / z;
  // The slow flow's Jacobian (docs/rom.md, "Stability"): det ∝ d(A|Z|)/dA,
  // trace = −(2(C + c_eq) + dc_eq/d ln A) / (2(M + m_app)).
  s.crossing = rising;
  s.saddle = rising < 0;
  const double growth = 2 * effective_damping + h.c_eq_slope(omega);
  s.slow_flow_growth = growth < 0;
  if (effective_mass <= 0) {
    s.stability = Stability::unknown;
  } else if (s.saddle || s.slow_flow_growth) {
    s.stability = Stability::unstable;
  } else if (rising == 0 || growth == 0) {
    s.stability = Stability::marginal;
  } else {
    s.stability = Stability::stable;
  }
  return s;
}

}  // namespace

void validate_host(const HostSdof& host, const Excitation& excitation) {
  require(std::isfinite(host.mass_kg) && host.mass_kg > 0, "host mass M (kg)", host.mass_kg, "a finite number > 0");
  require(std::isfinite(host.stiffness_N_m) && host.stiffness_N_m > 0, "host stiffness K (N/m)", host.stiffness_N_m,
          "a finite number > 0");
  require(std::isfinite(host.damping_N_s_m) && host.damping_N_s_m >= 0, "host damping C (N s/m)", host.damping_N_s_m,
          "a finite number >= 0");
  const bool force = excitation.kind == ExcitationKind::force;
  require(std::isfinite(excitation.amplitude) && excitation.amplitude > 0,
          force ? "force amplitude F0 (N)" : "base amplitude Y (m)", excitation.amplitude, "a finite number > 0");
}

const char* to_string(Stability stability) {
  switch (stability) {
    case Stability::stable:
      return "stable";
    case Stability::unstable:
      return "unstable";
    case Stability::marginal:
      return "marginal";
    case Stability::unknown:
      break;
  }
  return "unknown";
}

FrequencyResponse solve_frequency(const AmplitudeProfile& profile, const HostSdof& host, const Excitation& excitation) {
  FrequencyResponse response;
  response.frequency_hz = profile.frequency_hz;
  if (!profile.covers_anything()) {
    response.not_covered = true;
    return response;
  }
  response.lowest_amplitude_m = profile.lowest_amplitude_m();
  response.highest_amplitude_m = profile.highest_amplitude_m();
  const double omega = 2 * std::numbers::pi * profile.frequency_hz;
  const double reference =
      excitation.kind == ExcitationKind::force
          ? excitation.amplitude
          : std::abs(std::complex<double>(host.stiffness_N_m, omega * host.damping_N_s_m)) * excitation.amplitude;
  std::vector<SegmentResidual> segments;
  for (std::size_t k = 0; k < profile.segment_count(); ++k) {
    segments.emplace_back(profile, k, host, omega, reference * reference);
  }
  const std::vector<Piece> pieces = monotone_pieces(segments);
  for (const Piece& p : pieces) {
    if (!std::isfinite(p.h_a) || !std::isfinite(p.h_b)) {
      throw InputError("harmonic balance at " + text::number(profile.frequency_hz) +
                       " Hz: the residual A|Z| - |R| overflows; the table's amplitudes or the host's values are too "
                       "large to evaluate in double precision");
    }
  }

  auto add = [&](const Piece& p, double u, int rising) {
    response.solutions.push_back(
        solution_at(profile, segments[p.segment], p.segment, u, rising, host, excitation, omega));
  };
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const Piece& p = pieces[i];
    if (p.h_a == 0) {  // exactly on a piece boundary: counted once, as the left end of its piece
      add(p, p.u_a, crossing(i > 0 ? std::optional(pieces[i - 1].h_a) : std::nullopt, p.h_b));
    } else if (sign(p.h_a) * sign(p.h_b) < 0) {
      add(p, refine(segments[p.segment], p), sign(p.h_b));
    }
  }
  const Piece& last = pieces.back();
  if (last.h_b == 0) add(last, last.u_b, crossing(last.h_a, std::nullopt));

  response.solution_below = pieces.front().h_a > 0;
  response.solution_above = last.h_b < 0;
  return response;
}

}  // namespace pdamp::rom
