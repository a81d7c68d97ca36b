// Tangential wheel-rail creep forces by Polach's method (paper eqs. 10-11):
//   O. Polach, "A fast wheel-rail forces calculation computer code", Vehicle System Dynamics
//   33 (Suppl.) (1999/2000) 728-739  -- creep force with spin;
//   O. Polach, "Creep forces in simulations of traction vehicles running on adhesion limit",
//   Wear 258 (2005) 992-1000          -- reduction factors kA, kS and falling friction.
// Contact frame: x rolling direction, y lateral, z normal. Forces act on the wheel, and follow
// Kalker's sign convention (a positive creepage gives a negative force).
#pragma once

#include <cstdint>

#include "rail_contact/kalker.hpp"

namespace rail::contact {

/// Model options (constant after building).
struct PolachOptions {
  bool spin = true;  ///< include spin (modified creepage nu_C and lateral force F_yS); off: not computed
  double kA = 1.0;   ///< reduction of Kalker's coefficient in the area of adhesion (0 < kA <= 1)
  double kS = 1.0;   ///< reduction of Kalker's coefficient in the area of slip (0 < kS <= kA)
  double A = 1.0;    ///< ratio mu_inf / mu0 of the friction law (> 0); 1 = constant friction
  double B = 0.0;    ///< exponential friction decrease rate [s/m] (>= 0)
};

/// Throws std::runtime_error if any option is non-physical.
void validate(const PolachOptions& options);

/// Polach 2005 recommended parameter sets (Polach, Wear 258 (2005) 992-1000, table of
/// parameters "for modelling of typical wheel-rail contact conditions"):
///   dry: kA = 1.00, kS = 0.40, mu0 = 0.55, A = 0.40, B = 0.60 s/m
///   wet: kA = 0.30, kS = 0.10, mu0 = 0.30, A = 0.40, B = 0.20 s/m
PolachOptions polach2005DryOptions() noexcept;
PolachOptions polach2005WetOptions() noexcept;
constexpr double kPolach2005DryMu0 = 0.55;
constexpr double kPolach2005WetMu0 = 0.30;

/// Inputs for one contact (SI units).
struct PolachInput {
  double nu_x = 0.0;     ///< longitudinal creepage [-]
  double nu_y = 0.0;     ///< lateral creepage [-]
  double phi = 0.0;      ///< spin creepage [1/m]
  double N = 0.0;        ///< normal load [N]
  double a = 0.0;        ///< contact ellipse semi-axis along rolling direction [m]
  double b = 0.0;        ///< contact ellipse semi-axis along lateral direction [m]
  double G = 0.0;        ///< combined shear modulus [Pa]
  double mu0 = 0.0;      ///< maximum (zero slip velocity) friction coefficient [-]
  double V = 0.0;        ///< reference (rolling) speed [m/s], used for the slip velocity w = nu_C V
  KalkerCoefficients c;  ///< Kalker coefficients at a/b and nu
};

/// Result for one contact.
struct PolachResult {
  double Fx = 0.0;       ///< longitudinal creep force on the wheel [N]
  double Fy = 0.0;       ///< lateral creep force on the wheel, including Fy_spin [N]
  double Fy_spin = 0.0;  ///< part of Fy caused by spin, F_yS [N]
  double mu = 0.0;       ///< friction coefficient at the slip velocity [-]
  double nu_C = 0.0;     ///< modified translational creepage [-]
  double epsilon = 0.0;  ///< gradient of tangential stress in the adhesion area [-]
};

/// Creep forces by Polach's method. Allocation-free, no exceptions, finite at zero creepage
/// (forces -> 0 continuously); returns zeros when N, a, b, G or mu0 is not positive.
PolachResult polachForces(const PolachInput& in, const PolachOptions& options) noexcept;

}  // namespace rail::contact
