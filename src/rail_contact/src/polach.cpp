#include "rail_contact/polach.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rail::contact {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// atan(x)/x, finite at x = 0 (Taylor series below 1e-4: error < x^4/5 ~ 2e-17).
double atanOverX(double x) noexcept {
  const double ax = std::abs(x);
  if (ax < 1.0e-4) return 1.0 - x * x / 3.0;
  return std::atan(x) / x;
}

void throwOption(const char* name, double value, const char* rule) {
  std::ostringstream os;
  os << "Polach options: " << name << " " << rule << " (got " << value << ")";
  throw std::runtime_error(os.str());
}

PolachOptions withParameters(double kA, double kS, double A, double B) noexcept {
  PolachOptions o;
  o.kA = kA;
  o.kS = kS;
  o.A = A;
  o.B = B;
  return o;
}

}  // namespace

void validate(const PolachOptions& o) {
  if (!(o.kA > 0.0 && o.kA <= 1.0)) throwOption("kA", o.kA, "must be in (0, 1]");
  if (!(o.kS > 0.0 && o.kS <= 1.0)) throwOption("kS", o.kS, "must be in (0, 1]");
  if (!(o.A > 0.0) || !std::isfinite(o.A)) throwOption("A", o.A, "must be > 0");
  if (!(o.B >= 0.0) || !std::isfinite(o.B)) throwOption("B", o.B, "must be >= 0 s/m");
}

// Polach, Wear 258 (2005) 992-1000, recommended parameters: kA, kS, A, B (s/m) for dry and for wet rail.
PolachOptions polach2005DryOptions() noexcept { return withParameters(1.00, 0.40, 0.40, 0.60); }
PolachOptions polach2005WetOptions() noexcept { return withParameters(0.30, 0.10, 0.40, 0.20); }

PolachResult polachForces(const PolachInput& in, const PolachOptions& o) noexcept {
  PolachResult r;
  if (!(in.N > 0.0) || !(in.a > 0.0) || !(in.b > 0.0) || !(in.G > 0.0) || !(in.mu0 > 0.0)) return r;

  const double nx = in.nu_x, ny = in.nu_y, phi = in.phi;
  const double s = std::hypot(nx, ny);  // translational creepage
  // Modified translational creepage (Polach 1999): spin shifts the lateral creepage by phi*a
  // when that increases its magnitude.
  double s_C = s;
  if (o.spin) {
    const double ny_shift = ny + phi * in.a;
    if (std::abs(ny_shift) > std::abs(ny)) s_C = std::hypot(nx, ny_shift);
  }
  // Friction falling with the slip velocity w = s_C V (Polach 2005).
  const double w = s_C * std::abs(in.V);
  const double mu = in.mu0 * ((1.0 - o.A) * std::exp(-o.B * w) + o.A);
  const double muN = mu * in.N;

  // Kalker coefficient in the direction of the translational creepage (Polach 1999).
  double c_jj = in.c.c11;
  if (s > 0.0) c_jj = std::hypot(in.c.c11 * nx / s, in.c.c22 * ny / s);

  // epsilon = (2/3) C pi a^2 b s_C / (mu N) with C = 3 G c_jj / (8 a)
  //         = G pi a b c_jj s_C / (4 mu N).
  const double eps_per_s = in.G * kPi * in.a * in.b * c_jj / (4.0 * muN);
  const double eps = eps_per_s * s_C;
  // F = 2 mu N / pi (kA eps / (1 + (kA eps)^2) + atan(kS eps)); F / s_C written finite at s_C = 0.
  const double kAe = o.kA * eps;
  const double F_over_sC = (2.0 * muN / kPi) * eps_per_s * (o.kA / (1.0 + kAe * kAe) + o.kS * atanOverX(o.kS * eps));
  r.Fx = -F_over_sC * nx;
  r.Fy = -F_over_sC * ny;

  if (o.spin) {
    // Spin-induced lateral force (Polach 1999):
    //   F_yS = -9/16 a mu N K_M [1 + 6.3 (1 - e^{-a/b})] phi / s_C
    //   K_M = |eps_S| (delta^3/3 - delta^2/2 + 1/6) - 1/3 sqrt((1 - delta^2)^3)
    //   delta = (eps_S^2 - 1) / (eps_S^2 + 1)
    //   eps_S = 8/3 G b sqrt(a b) c23 s_C / (mu N [1 + 6.3 (1 - e^{-a/b})])
    // K_M / |eps_S| = (delta^3/3 - delta^2/2 + 1/6) - 8/3 eps_S^2 / (1 + eps_S^2)^3 is finite at
    // eps_S = 0 (-> -2/3) and negative for all eps_S; its magnitude is used so that the small
    // creepage limit is Kalker's linear term -G (ab)^1.5 c23 phi.
    const double shape = 1.0 + 6.3 * (1.0 - std::exp(-in.a / in.b));
    const double epsS_per_sC = (8.0 / 3.0) * in.G * in.b * std::sqrt(in.a * in.b) * in.c.c23 / (muN * shape);
    const double eS = epsS_per_sC * s_C;
    const double e2 = eS * eS;
    const double d = (e2 - 1.0) / (e2 + 1.0);
    const double q = 1.0 + e2;
    const double KM_over_eps = (d * d * d / 3.0 - d * d / 2.0 + 1.0 / 6.0) - (8.0 / 3.0) * e2 / (q * q * q);
    r.Fy_spin = -(9.0 / 16.0) * in.a * muN * shape * std::abs(KM_over_eps) * epsS_per_sC * phi;
    r.Fy += r.Fy_spin;
  }
  r.mu = mu;
  r.nu_C = s_C;
  r.epsilon = eps;
  return r;
}

}  // namespace rail::contact
