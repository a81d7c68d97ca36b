#include "rail_contact/hertz.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "rail_contact/illinois.hpp"

namespace rail::contact {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// Complete elliptic integrals K(e) and E(e) of modulus e (0 <= e < 1) by the arithmetic-
/// geometric mean (Abramowitz & Stegun 17.6): a_0 = 1, b_0 = sqrt(1 - e^2), c_0 = e,
/// K = pi / (2 a_N), E = K (1 - sum_n 2^(n-1) c_n^2). Quadratic convergence: <= 6 steps to
/// machine precision for e^2 <= 1 - 1e-8.
void completeElliptic(double e, double& Kc, double& Ec) noexcept {
  double a = 1.0, b = std::sqrt((1.0 - e) * (1.0 + e)), c = e;
  double sum = 0.5 * c * c, pow2 = 0.5;
  for (int n = 0; n < 30 && std::abs(c) > 1.0e-17 * a; ++n) {
    c = 0.5 * (a - b);
    const double a_next = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = a_next;
    pow2 *= 2.0;
    sum += pow2 * c * c;
  }
  Kc = 0.5 * kPi / a;
  Ec = Kc * (1.0 - sum);
}

/// K(e) - E(e) divided by m = e^2; series near m = 0 (from the power series of K and E):
/// (K - E)/m = pi/4 (1 + 3m/8 + 15m^2/64 + ...).
double kMinusEOverM(double m, double Kc, double Ec) noexcept {
  if (m < 1.0e-6) return 0.25 * kPi * (1.0 + 0.375 * m + 0.234375 * m * m);
  return (Kc - Ec) / m;
}

/// g(k) = (E/k^2 - K)/(K - E) for axis ratio k = minor/major in (0,1), where e^2 = 1 - k^2.
/// Equals B/A (A the smaller relative curvature). g(1) = 1, g(0+) = +inf, decreasing.
double curvatureRatioOfAxisRatio(double k) noexcept {
  const double m = 1.0 - k * k;
  if (m < 1.0e-6) {
    // Series: numerator pi/2 m (1/2 + 9m/16), denominator pi/2 m (1/2 + 3m/16).
    return (0.5 + 0.5625 * m) / (0.5 + 0.1875 * m);
  }
  double Kc = 0.0, Ec = 0.0;
  completeElliptic(std::sqrt(m), Kc, Ec);
  return (Ec / (k * k) - Kc) / (Kc - Ec);
}

/// ln g(k) and its derivative with respect to ln k, from one AGM, for m = 1 - k^2 >= 1e-6. With
/// dK/dm = (E - (1-m) K) / (2 m (1-m)) and dE/dm = (E - K) / (2 m) (A&S 17.3.10, 17.3.11) and
/// dm/d(ln k) = -2 k^2.
void logCurvatureRatio(double k, double& ln_g, double& slope) noexcept {
  const double k2 = k * k;
  const double m = 1.0 - k2;
  double Kc = 0.0, Ec = 0.0;
  completeElliptic(std::sqrt(m), Kc, Ec);
  const double dK = (Ec - k2 * Kc) / (2.0 * m * k2);
  const double dE = (Ec - Kc) / (2.0 * m);
  const double num = Ec / k2 - Kc, den = Kc - Ec;
  const double d_num = dE / k2 + Ec / (k2 * k2) - dK;
  const double d_den = dK - dE;
  ln_g = std::log(num / den);
  slope = -2.0 * k2 * (d_num / num - d_den / den);
}

/// Solves g(k) = ratio (ratio >= 1) for k by the Illinois (modified regula falsi) method on
/// ln g(k) - ln(ratio), bracketed; the start bracket comes from the Brewe-Hamrock fit
/// k ~ ratio^-0.636 / 1.0339 (Brewe & Hamrock, J. Lubr. Technol. 99 (1977) 485-487).
double solveAxisRatioBracketed(double ratio) noexcept {
  const double target = std::log(ratio);
  auto f = [target](double k) { return std::log(curvatureRatioOfAxisRatio(k)) - target; };
  const double guess = std::min(1.0, std::pow(ratio, -0.636) / 1.0339);
  double lo = 0.5 * guess;
  double f_lo = f(lo);
  for (int i = 0; i < 60 && f_lo <= 0.0; ++i) {  // f decreasing: need f(lo) > 0
    lo *= 0.5;
    f_lo = f(lo);
  }
  double hi = std::min(1.0, 2.0 * guess);
  double f_hi = f(hi);
  if (f_hi > 0.0) {
    hi = 1.0;
    f_hi = -target;
  }
  int side = 0;
  double k = hi;
  for (int it = 0; it < 100; ++it) {
    k = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
    if (!(k > lo && k < hi)) k = 0.5 * (lo + hi);
    const double fk = f(k);
    if (fk == 0.0 || (hi - lo) < 1.0e-15 * hi) break;
    if (fk > 0.0) {
      lo = k;
      f_lo = fk;
      if (side == +1) f_hi *= 0.5;
      side = +1;
    } else {
      hi = k;
      f_hi = fk;
      if (side == -1) f_lo *= 0.5;
      side = -1;
    }
    if (std::abs(fk) < 1.0e-15) break;
  }
  return k;
}

/// Solves g(k) = ratio by Newton's method on ln g against ln k, where g is close to a power of k (the
/// Brewe-Hamrock fit, also the start): three to four AGMs instead of the bracketed solve's ten or more.
/// Near the circle (ratio < 1.01, where g's terms cancel) and on any step that leaves (0, 1) it takes
/// the bracketed solve.
double solveAxisRatio(double ratio) noexcept {
  if (ratio < 1.01) return solveAxisRatioBracketed(ratio);
  const double target = std::log(ratio);
  double u = std::log(std::min(0.99, std::pow(ratio, -0.636) / 1.0339));  // ln k
  for (int it = 0; it < 20; ++it) {
    double ln_g = 0.0, slope = 0.0;
    logCurvatureRatio(std::exp(u), ln_g, slope);
    const double step = (ln_g - target) / slope;
    if (!std::isfinite(step)) break;
    u -= step;
    if (!(u < std::log(0.9999995))) break;  // m below 1e-6: leave it to the bracketed solve
    if (std::abs(step) < 1.0e-13) return std::exp(u);
  }
  return solveAxisRatioBracketed(ratio);
}

}  // namespace

void validate(const ElasticMaterial& m, const char* what) {
  if (!(m.youngs_modulus > 0.0) || !std::isfinite(m.youngs_modulus)) {
    std::ostringstream os;
    os << what << ": Young's modulus must be > 0 Pa (got " << m.youngs_modulus << ")";
    throw std::runtime_error(os.str());
  }
  if (!(m.poisson_ratio > -1.0 && m.poisson_ratio <= 0.5)) {
    std::ostringstream os;
    os << what << ": Poisson ratio must be in (-1, 0.5] (got " << m.poisson_ratio << ")";
    throw std::runtime_error(os.str());
  }
}

double contactModulus(const ElasticMaterial& w, const ElasticMaterial& r) {
  validate(w, "wheel material");
  validate(r, "rail material");
  const double inv = (1.0 - w.poisson_ratio * w.poisson_ratio) / w.youngs_modulus +
                     (1.0 - r.poisson_ratio * r.poisson_ratio) / r.youngs_modulus;
  return 1.0 / inv;
}

double combinedShearModulus(const ElasticMaterial& w, const ElasticMaterial& r) {
  validate(w, "wheel material");
  validate(r, "rail material");
  const double Gw = w.youngs_modulus / (2.0 * (1.0 + w.poisson_ratio));
  const double Gr = r.youngs_modulus / (2.0 * (1.0 + r.poisson_ratio));
  return 2.0 / (1.0 / Gw + 1.0 / Gr);
}

double combinedPoissonRatio(const ElasticMaterial& w, const ElasticMaterial& r) {
  const double G = combinedShearModulus(w, r);
  const double Gw = w.youngs_modulus / (2.0 * (1.0 + w.poisson_ratio));
  const double Gr = r.youngs_modulus / (2.0 * (1.0 + r.poisson_ratio));
  return 0.5 * G * (w.poisson_ratio / Gw + r.poisson_ratio / Gr);
}

void relativeCurvatures(const PrincipalCurvatures& k, double& A, double& B) noexcept {
  A = 0.5 * (k.wheel_rolling + k.rail_rolling);
  B = 0.5 * (k.wheel_lateral + k.rail_lateral);
}

double HertzGeometry::a(double N) const noexcept { return N > 0.0 ? a_coeff * std::cbrt(N) : 0.0; }
double HertzGeometry::b(double N) const noexcept { return N > 0.0 ? b_coeff * std::cbrt(N) : 0.0; }
double HertzGeometry::approach(double N) const noexcept {
  if (!(N > 0.0)) return 0.0;
  const double c = std::cbrt(N);
  return delta_coeff * c * c;
}
double HertzGeometry::load(double delta) const noexcept { return delta > 0.0 ? K * delta * std::sqrt(delta) : 0.0; }

HertzGeometry computeHertz(double A, double B, double E_star, const HertzOptions& opt) noexcept {
  HertzGeometry g;
  std::uint32_t flags = kHertzOk;
  if (!std::isfinite(A) || !std::isfinite(B)) {
    flags |= kHertzBadInput;
    A = B = opt.min_curvature;
  }
  if (!(E_star > 0.0) || !std::isfinite(E_star)) {
    flags |= kHertzBadInput;
    E_star = 1.0;
  }
  const double ratio_max = std::max(1.0, opt.max_curvature_ratio);
  const double floor = opt.min_curvature > 0.0 ? opt.min_curvature : 1.0e-3;
  // Non-positive relative curvature: convex-concave conformity (flange root) or inverted input.
  if (A <= 0.0 || B <= 0.0) {
    flags |= kHertzNonPositiveCurvature;
    const double top = std::max(std::max(A, B), floor);
    if (A <= 0.0) A = top / ratio_max;
    if (B <= 0.0) B = top / ratio_max;
    A = std::max(A, floor / ratio_max);
    B = std::max(B, floor / ratio_max);
  }
  if (std::max(A, B) > ratio_max * std::min(A, B)) {
    flags |= kHertzRatioClamped;
    if (A < B)
      A = B / ratio_max;
    else
      B = A / ratio_max;
  }
  g.A = A;
  g.B = B;
  g.E_star = E_star;

  // Major axis lies along the direction of the smaller relative curvature.
  const double A_small = std::min(A, B);
  const double ratio = std::max(A, B) / A_small;
  double k = 1.0;  // minor/major
  if (ratio - 1.0 < 1.0e-10) {
    flags |= kHertzCircular;
  } else {
    k = solveAxisRatio(ratio);
  }
  const double m = 1.0 - k * k;
  const double e = std::sqrt(std::max(m, 0.0));
  double Kc = 0.5 * kPi * (1.0 + 0.25 * m), Ec = 0.5 * kPi * (1.0 - 0.25 * m);  // series, m -> 0
  if (m >= 1.0e-6) completeElliptic(e, Kc, Ec);
  // Johnson eq. 4.37 with p0 = 3N/(2 pi a b): A_small = 3N (K-E) / (2 pi E* a^3 e^2).
  const double major_coeff = std::cbrt(3.0 * kMinusEOverM(m, Kc, Ec) / (2.0 * kPi * E_star * A_small));
  const double minor_coeff = k * major_coeff;
  // delta = p0 b K(e) / E* = 3 N K(e) / (2 pi a E*).
  g.delta_coeff = 3.0 * Kc / (2.0 * kPi * major_coeff * E_star);
  g.K = 1.0 / (g.delta_coeff * std::sqrt(g.delta_coeff));
  g.eccentricity = e;
  if (A <= B) {
    g.a_coeff = major_coeff;
    g.b_coeff = minor_coeff;
  } else {
    g.a_coeff = minor_coeff;
    g.b_coeff = major_coeff;
  }
  g.flags = flags;
  return g;
}

HertzGeometry computeHertz(const PrincipalCurvatures& k, double E_star, const HertzOptions& options) noexcept {
  double A = 0.0, B = 0.0;
  relativeCurvatures(k, A, B);
  return computeHertz(A, B, E_star, options);
}

void validate(const NormalDampingParams& p) {
  if (!(p.restitution >= 0.0 && p.restitution <= 1.0)) {
    std::ostringstream os;
    os << "normal damping: restitution coefficient must be in [0, 1] (got " << p.restitution << ")";
    throw std::runtime_error(os.str());
  }
  if (!(p.exponent > 0.0)) {
    std::ostringstream os;
    os << "normal damping: exponent n must be > 0 (got " << p.exponent << ")";
    throw std::runtime_error(os.str());
  }
  if (!(p.impact_velocity_floor > 0.0)) {
    std::ostringstream os;
    os << "normal damping: impact velocity floor must be > 0 m/s (got " << p.impact_velocity_floor << ")";
    throw std::runtime_error(os.str());
  }
}

double dampedNormalForce(double K, double delta, double delta_dot, double delta_dot_impact,
                         const NormalDampingParams& p) noexcept {
  if (!(delta > 0.0) || !(K > 0.0)) return 0.0;
  const double v_impact = std::max(std::abs(delta_dot_impact), p.impact_velocity_floor);
  const double damping = 0.75 * (1.0 - p.restitution * p.restitution) * delta_dot / v_impact;
  const double elastic = p.exponent == 1.5 ? K * delta * std::sqrt(delta) : K * std::pow(delta, p.exponent);
  const double N = elastic * (1.0 + damping);
  return (N > 0.0 && std::isfinite(N)) ? N : 0.0;
}

void updateImpactMemory(ImpactMemory& memory, double delta, double delta_dot) noexcept {
  if (delta > 0.0) {
    if (!memory.in_contact) {
      memory.in_contact = true;
      memory.impact_velocity = std::max(delta_dot, 0.0);
    } else if (delta_dot > memory.impact_velocity && std::isfinite(delta_dot)) {
      memory.impact_velocity = delta_dot;  // pushed in harder than at onset: see ImpactMemory
    }
  } else {
    memory.in_contact = false;
    memory.impact_velocity = 0.0;
  }
}

HertzGeometry limitLateralWidth(const HertzGeometry& hz, double delta, double max_b,
                                const HertzOptions& options) noexcept {
  const auto width = [delta](const HertzGeometry& h) { return h.b(h.load(delta)); };
  if (!(max_b > 0.0) || !(delta > 0.0) || !(width(hz) > max_b) || !(hz.B > 0.0)) return hz;
  // b at a given approach falls as B grows (A fixed), smoothly in log B: find g(x) = ln b(e^x) - ln max_b = 0
  // by bracketing in steps of x4 and the Illinois method (modified regula falsi) to 1e-4 in ln b. Typically
  // 2-3 bracket steps and 4-6 Illinois steps: the run pays about ten computeHertz per clamped contact.
  const double target = std::log(max_b);
  double x_lo = std::log(hz.B), g_lo = std::log(width(hz)) - target;  // g_lo > 0
  double x_hi = x_lo, g_hi = g_lo;
  HertzGeometry h = hz, best = hz;
  for (int i = 0; i < 40 && g_hi > 0.0; ++i) {
    x_lo = x_hi;
    g_lo = g_hi;
    x_hi += std::log(4.0);
    h = computeHertz(hz.A, std::exp(x_hi), hz.E_star, options);
    g_hi = std::log(width(h)) - target;
  }
  if (g_hi > 0.0) return hz;  // not reached (degenerate input): leave it unclamped
  best = h;
  IllinoisBracket br{x_hi, g_hi, x_lo, g_lo};  // g_b = g_lo > 0 throughout: a g <= 0 replaces x_hi
  for (int i = 0; i < 30 && std::abs(br.g_a) > 1e-4; ++i) {
    const double x = br.next();
    const HertzGeometry m = computeHertz(hz.A, std::exp(x), hz.E_star, options);
    if (br.update(x, std::log(width(m)) - target)) best = m;
  }
  best.flags |= hz.flags | kHertzWidthClamped;
  return best;  // b <= max_b, within 1e-4 of it
}

}  // namespace rail::contact
