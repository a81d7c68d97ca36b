// Hertzian normal contact between wheel and rail (paper section 4.1, eq. 9).
//
// Frames: x = rolling (longitudinal) direction, y = lateral direction in the
// common tangent plane at the contact point. Curvatures are in 1/m, positive
// when the surface is convex towards the other body, negative when concave.
// SI units throughout.
#pragma once

#include <cstdint>

namespace rail::contact {

/// Isotropic linear elastic material. E in Pa, nu dimensionless.
/// Defaults: rail steel, E = 2.10e11 Pa with G = 8.08e10 Pa (so nu = E/(2G) - 1 = 0.30),
/// from Table 1 of the co-simulation paper (vehicle-track-cosimulation-paper.txt).
struct ElasticMaterial {
  double youngs_modulus = 2.10e11;  ///< E [Pa]
  double poisson_ratio = 0.30;      ///< nu [-]
};

/// Throws std::runtime_error naming `what` if E <= 0 or nu is outside (-1, 0.5].
void validate(const ElasticMaterial& material, const char* what);

/// Contact modulus E* = 1 / ((1 - nu_w^2)/E_w + (1 - nu_r^2)/E_r) [Pa] (Johnson, Contact Mechanics, eq. 4.22).
/// Throws std::runtime_error on a non-physical material.
double contactModulus(const ElasticMaterial& wheel, const ElasticMaterial& rail);

/// Combined shear modulus G with 2/G = 1/G_w + 1/G_r [Pa] (Kalker's convention for two bodies).
double combinedShearModulus(const ElasticMaterial& wheel, const ElasticMaterial& rail);

/// Combined Poisson ratio nu with nu/G = (nu_w/G_w + nu_r/G_r)/2 (Kalker's convention).
double combinedPoissonRatio(const ElasticMaterial& wheel, const ElasticMaterial& rail);

/// Principal curvatures of wheel and rail at the contact point [1/m], assumed aligned with
/// the rolling (x) and lateral (y) directions. Convex > 0, concave < 0.
struct PrincipalCurvatures {
  double wheel_rolling = 0.0;  ///< 1/R of the wheel rolling circle
  double wheel_lateral = 0.0;  ///< curvature of the wheel profile
  double rail_rolling = 0.0;   ///< 1/R of the rail in plan/elevation along the track (usually ~0)
  double rail_lateral = 0.0;   ///< curvature of the rail head profile
};

/// Options for degenerate geometry.
struct HertzOptions {
  /// Largest accepted ratio between the two relative curvatures max(A,B)/min(A,B). Beyond it
  /// (very flat in one direction, or conformal near the flange root) the smaller one is raised
  /// and kRatioClamped is flagged. 1000 gives an axis ratio b/a ~ 0.015.
  double max_curvature_ratio = 1000.0;
  /// Floor for A and B when both are non-positive [1/m] (fully conformal or inverted geometry).
  double min_curvature = 1.0e-3;
};

/// Flags raised by computeHertz (bitwise OR).
enum HertzFlag : std::uint32_t {
  kHertzOk = 0u,
  kHertzCircular = 1u << 0,              ///< A ~ B, treated as circular contact
  kHertzNonPositiveCurvature = 1u << 1,  ///< A or B <= 0 (conformal/convex-concave): clamped
  kHertzRatioClamped = 1u << 2,          ///< max(A,B)/min(A,B) above max_curvature_ratio: clamped
  kHertzBadInput = 1u << 3,              ///< non-finite curvature or E* <= 0: unit-less fallback
  kHertzWidthClamped = 1u << 4,          ///< near-conformal: B raised so b stays within the patch width limit
};

/// Load-independent Hertz solution for one contact geometry. With N the normal load [N]:
///   a = a_coeff N^(1/3)  (semi-axis along rolling x) [m]
///   b = b_coeff N^(1/3)  (semi-axis along lateral y) [m]
///   delta = delta_coeff N^(2/3)  (approach of distant points) [m]
///   N = K delta^1.5, K = delta_coeff^(-3/2) [N/m^1.5]
struct HertzGeometry {
  double A = 0.0;             ///< relative curvature coefficient along x, gap = A x^2 + B y^2 [1/m]
  double B = 0.0;             ///< relative curvature coefficient along y [1/m]
  double eccentricity = 0.0;  ///< e = sqrt(1 - (minor/major)^2) of the contact ellipse
  double a_coeff = 0.0;       ///< [m N^-1/3]
  double b_coeff = 0.0;       ///< [m N^-1/3]
  double delta_coeff = 0.0;   ///< [m N^-2/3]
  double K = 0.0;             ///< Hertz stiffness [N m^-1.5]
  double E_star = 0.0;        ///< contact modulus used [Pa]
  std::uint32_t flags = kHertzOk;

  /// Semi-axis along rolling direction for load N [m]; 0 for N <= 0.
  double a(double N) const noexcept;
  /// Semi-axis along lateral direction for load N [m]; 0 for N <= 0.
  double b(double N) const noexcept;
  /// Approach for load N [m]; 0 for N <= 0.
  double approach(double N) const noexcept;
  /// Elastic (undamped) load at approach delta [N]: K delta^1.5; 0 for delta <= 0.
  double load(double delta) const noexcept;
};

/// A near-conformal contact (flange root against the gauge corner: wheel and rail lateral curvatures almost
/// cancel, B -> 0) has a Hertz ellipse as wide as B allows and a stiffness that grows without bound, while
/// Hertz's theory holds only for a patch small against the profile radii around it. Returns hz when its
/// lateral semi-axis at the elastic load K delta^1.5 is within max_b; otherwise the geometry with B raised
/// (bisection, A kept) until it is max_b, flagged kHertzWidthClamped. No allocation.
HertzGeometry limitLateralWidth(const HertzGeometry& hz, double delta, double max_b,
                                const HertzOptions& options = {}) noexcept;

/// Relative curvature coefficients A = (k_wx + k_rx)/2, B = (k_wy + k_ry)/2 [1/m].
void relativeCurvatures(const PrincipalCurvatures& k, double& A, double& B) noexcept;

/// Hertz solution from A, B [1/m] and E* [Pa]: solves the eccentricity from
/// B/A = (E(e)/(1-e^2) - K(e)) / (K(e) - E(e)) (A the smaller; Johnson eqs. 4.37-4.39)
/// with complete elliptic integrals K, E (arithmetic-geometric mean). Never throws, never returns NaN; degenerate input
/// is clamped and flagged.
HertzGeometry computeHertz(double A, double B, double E_star, const HertzOptions& options = {}) noexcept;

/// Same, from principal curvatures.
HertzGeometry computeHertz(const PrincipalCurvatures& k, double E_star, const HertzOptions& options = {}) noexcept;

/// Parameters of the damped normal force (paper eq. 9, Lankarani-Nikravesh form).
struct NormalDampingParams {
  double restitution = 0.5;  ///< e in [0,1]; application-dependent, no published default implied
  double exponent = 1.5;     ///< n, 1.5 for Hertzian metal contact
  /// Floor on the impact (onset) penetration velocity [m/s]: the damping term divides by
  /// max(delta_dot_impact, floor), so a contact that begins at zero penetration rate (rolling
  /// wheel) gets a finite damping coefficient 3(1-e^2)/4 K delta^n / floor.
  double impact_velocity_floor = 0.01;
};

/// Throws std::runtime_error if e is outside [0,1], n <= 0 or the floor is <= 0.
void validate(const NormalDampingParams& params);

/// Normal force [N], eq. 9: N = K delta^n [1 + 3(1-e^2)/4 * delta_dot / max(delta_dot_impact, floor)],
/// clamped to N >= 0 (never tensile); 0 when delta <= 0.
/// K [N/m^n], delta penetration [m] (> 0 in contact), delta_dot [m/s] (> 0 approaching),
/// delta_dot_impact the penetration rate when this contact started [m/s].
double dampedNormalForce(double K, double delta, double delta_dot, double delta_dot_impact,
                         const NormalDampingParams& params) noexcept;

/// Per-contact memory of the impact velocity (caller-owned, one per contact pair).
///
/// Eq. 9 divides the penetration rate by the impact velocity, the rate at contact onset. In a true impact
/// that is the largest approach rate of the contact, so the damping term stays within +-3(1-e^2)/4 and the
/// force within [0.44, 1.56] K delta^n (e = 0.5). A rolling contact can start softly (onset rate ~ 0, the
/// floor applies) and then be pushed in much faster, e.g. a tread contact that reappears while its flange
/// slides down the rail: with the onset rate alone the bracket reached about 20 in the flange-climb hard
/// case's variants (N ~ 1.8 MN where K delta^1.5 is ~90 kN), and at the other end turned negative (N
/// clamped to 0) whenever a contact separated faster than 0.018 m/s. So the memory keeps the largest
/// approach rate since onset: identical to eq. 9 for an impact, bounded for a contact that is pushed in
/// after a soft start. An implicit integrator's caller holds it to accepted steps (WheelContactWork::
/// hold_impact_memory), so that its Newton iterates and rejected steps do not enter it.
struct ImpactMemory {
  bool in_contact = false;
  double impact_velocity = 0.0;  ///< largest delta_dot since contact onset [m/s], >= 0
};

/// Updates the memory: on the first step with delta > 0 stores max(delta_dot, 0), afterwards the largest
/// delta_dot seen; resets when delta <= 0.
void updateImpactMemory(ImpactMemory& memory, double delta, double delta_dot) noexcept;

}  // namespace rail::contact
