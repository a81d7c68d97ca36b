// Online wheel-rail contact detection for one wheel on one rail (paper section 4.1, eqs. 4, 5 and 8).
//
// Surfaces (Figure 8):
//  - wheel tread and flange: surfaces of revolution of the wheel profile curves (profile.hpp) about the
//    axle, parameters (s_w, u_w): s_w the revolution angle (rad) measured from the downward direction
//    (world -z projected on the wheel plane) toward forward, u_w the profile arc length (m);
//  - rail: the rail profile swept along the rail (track_geometry.hpp), parameters (s_r, u_r): s_r the
//    track arc length (m), u_r the profile arc length (m); deformed by a provider (rail_deformation.hpp).
// Unknowns x = (s_w, u_w, s_r, u_r); equations (eq. 4): with d = p_wheel - p_rail, t_s, t_u the rail
// tangents and n_w the wheel normal:  d.t_s = 0, d.t_u = 0, n_w.t_s = 0, n_w.t_u = 0.
// Newton's method with the analytic Jacobian (the rail's second derivative along s, of the order of the
// track curvature, is left out; exact on straight track), warm-started from the previous solution kept
// in a caller-owned DetectionWork. When Newton fails, leaves the surface bounds or finds a non-opposed
// normal pair, a robust search over the wheel profile in the rail cross-section (signed distance field of
// the rail profile, precomputed) gives a new start and Newton runs again. Contact exists when the
// penetration along the normal is positive (eq. 5).
//
// Frames: world x forward, y left, z up (track_geometry.hpp). Wheelset frame: y along the axle (left
// positive). A wheel's profile y points toward the track centre, like the rail's, so the left wheel has
// profile y along -axle, the right wheel along +axle. The wheel centre is the axle point in the plane of
// the taping line (profile y = 0).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "rail_contact/profile.hpp"
#include "rail_contact/rail_deformation.hpp"
#include "rail_contact/track_geometry.hpp"

namespace rail {
namespace contact {

/// Which wheel surface (paper Figure 8).
enum class WheelSurface : int { kTread = 0, kFlange = 1 };

/// Outcome of one detection.
enum class DetectionStatus : std::uint8_t {
  kConverged = 0,         ///< Newton from the warm start converged inside the surface bounds
  kConvergedAfterSearch,  ///< converged after a (fallback or initial) robust search
  kApproximate,           ///< Newton failed; the search's best point pair is returned (finite, usable)
  kOutOfBounds,           ///< no contact point inside the surfaces (e.g. wheel far off the rail)
  kInvalidInput,          ///< non-finite pose: nothing computed
};
const char* toString(DetectionStatus status) noexcept;

/// Detection settings (constant after building the detector).
struct DetectionOptions {
  int max_iterations = 15;             ///< Newton iterations per attempt
  double tolerance = 1e-10;            ///< convergence: step below this (m; rad times nominal radius)
  double max_step_length = 0.01;       ///< Newton step limit on u_w, u_r (m) and s_r (x 5)
  double max_step_angle = 0.1;         ///< Newton step limit on s_w, rad
  double max_penetration = 0.005;      ///< larger penetrations are rejected as spurious point pairs, m
  double min_normal_opposition = 0.9;  ///< -n_w . n_r must exceed this at a valid point pair
  double search_cell = 0.5e-3;         ///< cell of the rail signed-distance grid, m
  double search_margin = 0.04;         ///< grid margin around the rail profile, m
  double search_spacing = 0.5e-3;      ///< spacing of the wheel profile samples in the search, m
  /// Each wheel surface is continued across the tread/flange split by this profile arc length (m): a
  /// contact point drifting just past the split stays a converged point of the surface that followed it
  /// instead of a failed Newton (search fallback, grid estimate kApproximate, or no contact), which makes
  /// the force a discontinuous, history-dependent function of the pose. WheelContactModel keeps one of two
  /// reports of the same patch. 0 = no continuation (surfaces end at the split). 5 mm by default, the same
  /// for the vehicle on the rigid track and the track node, so that both sides evaluate the same contact
  /// (rail_vehicle_node doc/simulator.md has the measurements: without it the integrator's step collapses
  /// to ~1e-7 s while a flange-root contact crosses the split).
  double split_overlap = 5e-3;
  /// With DetectionWork::skip_far_searches: a surface whose last search found every sample at least this
  /// much farther from the rail than the wheel can have moved since (relative to the rail section, deformed
  /// on flexible rails) is reported out of contact without a new search, m.
  double skip_clearance = 1e-3;
  /// A search whose sampled distance has no interior minimum seeds Newton at the nearer end sample of the
  /// surface when that sample is within this distance of the rail, m; only a converged point inside the
  /// surface is taken from it. The nearest point of a yawed wheel's flange can lie in the last sample
  /// interval, where the sampled minimum is the end sample; 0 = interior minima only.
  double end_seed_reach = 1e-3;
  /// The search takes each wheel profile sample over a fan of wheel planes around the lowest one, this far
  /// apart (rad), as wide as 1.5 |psi| tan(delta_max) for a wheel yawed by psi against the rail (delta_max:
  /// the surface's steepest slope, at most 80 deg), since a yawed flange touches ahead of or behind the
  /// lowest plane. 0 = the lowest plane only.
  double search_plane_step = 0.01;
  double search_fan_max = 0.25;  ///< the fan's half-width at most, rad
  /// ContactDetector::scanProfile takes a wheel profile sample only when the samples taken before it do not
  /// already bound its distance to the rail above this (m); a sample not taken holds that lower bound. The
  /// bound is exact while the rail's signed distance is continuous along the profile, that is, everywhere but
  /// behind the rail profile's ends. 0 = every sample taken.
  double scan_skip_clearance = 1e-4;
};

/// Caller-owned per-pair state: warm start and counters (one per wheel surface and wheel).
struct DetectionWork {
  Eigen::Vector4d x = Eigen::Vector4d::Zero();  ///< last solution (s_w, u_w, s_r, u_r)
  bool has_warm_start = false;
  long long calls = 0;              ///< detections run
  long long newton_iterations = 0;  ///< total Newton iterations
  long long searches = 0;           ///< robust searches run (initial and fallback)
  long long fallbacks = 0;          ///< searches caused by a failed warm-started Newton
  /// contacts evaluated (counted by WheelContactModel) at a point past this surface's end, on the
  /// neighbouring surface's part of the profile, away from that surface's own contact: a second contact
  /// there, e.g. at the flange root beside a tread contact (ContactGeometry::past_end)
  long long past_end_contacts = 0;
  long long approximations = 0;  ///< results returned as kApproximate
  /// Set by the caller: a surface far from its rail skips the search (a flange off the rail searched ~130
  /// profile samples at every evaluation, a quarter of the vehicle's time on a straight).
  /// Its out-of-contact result then carries a lower bound of the gap, not the gap: callers that publish the
  /// gap turn this off for those evaluations. The force is the same, zero, either way.
  bool skip_far_searches = false;
  bool has_search_reference = false;                           ///< the last search failed and left the reference below
  double reference_distance = 0.0;                             ///< its smallest sample distance to the rail, m
  Eigen::Vector2d reference_centre = Eigen::Vector2d::Zero();  ///< wheel centre in the rail section (lateral, up), m
  Eigen::Vector3d reference_axle = Eigen::Vector3d::Zero();    ///< axle direction in the rail section frame
  long long skipped = 0;                                       ///< searches skipped
  /// false: a detection starts Newton from the previous detection's solution. true: from the solution
  /// committed by commitWarmStart once the state it was found at is accepted, so that the trial states of an
  /// implicit integrator (Newton iterates, Jacobian perturbations, rejected steps) do not decide which point
  /// the next detection converges to, and the contact is a function of the state and the accepted history.
  bool hold_warm_start = false;
  Eigen::Vector4d x_committed = Eigen::Vector4d::Zero();
  bool has_committed_warm_start = false;
  void commitWarmStart() {
    x_committed = x;
    x_surface_committed = x_surface;
    has_committed_warm_start = has_warm_start;
  }
  int x_surface = 0;  ///< surface (0 tread, 1 flange) whose parameters x holds
  int x_surface_committed = 0;
  /// Set by the caller for a wheel's further contacts (WheelContactModel's slots kTreadSecond and
  /// kFlangeSecond): detect runs no search but Newton from `seed`, and takes only a converged, penetrating
  /// point pair of the surface's own part (no point past its end, no approximate result).
  bool seeded = false;
  Eigen::Vector4d seed = Eigen::Vector4d::Zero();
  void reset() {
    const bool hold = hold_warm_start;
    *this = DetectionWork();
    hold_warm_start = hold;
  }
};

/// Counters of several DetectionWork summed (every wheel, both surfaces) for a run's closing summary.
struct DetectionCounts {
  long long calls = 0, newton_iterations = 0, searches = 0, fallbacks = 0, past_end_contacts = 0, approximations = 0,
            skipped = 0;
  void add(const DetectionWork& w) {
    calls += w.calls;
    newton_iterations += w.newton_iterations;
    searches += w.searches;
    fallbacks += w.fallbacks;
    past_end_contacts += w.past_end_contacts;
    approximations += w.approximations;
    skipped += w.skipped;
  }
};

/// One line for a run's log: "N detections, I Newton iterations each, S searches (F after a failed warm
/// start), K skipped far from the rail, A approximate"; with A > 0 what approximate means, with P > 0
/// contacts past a surface's end how many and what they are. Not for a time step.
std::string describe(const DetectionCounts& counts);

/// Wheel pose for the detection (world frame).
struct WheelPose {
  Eigen::Vector3d p_wheel_in_world = Eigen::Vector3d::Zero();         ///< wheel centre, m
  Eigen::Matrix3d R_wheelset_to_world = Eigen::Matrix3d::Identity();  ///< A_ws
  RailSide side = RailSide::kLeft;                                    ///< wheel side = rail side
  double arc_length = 0.0;  ///< track arc length near the wheel, m (used by the search)
};

/// Geometry of one detected point pair (world frame).
struct ContactGeometry {
  DetectionStatus status = DetectionStatus::kOutOfBounds;
  bool valid = false;           ///< point pair usable (converged or approximate)
  bool in_contact = false;      ///< valid and penetration > 0 (eq. 5)
  double s_w = 0.0, u_w = 0.0;  ///< wheel surface parameters, rad and m
  double s_r = 0.0, u_r = 0.0;  ///< rail surface parameters, m and m
  double penetration = 0.0;     ///< along the normal, m; > 0 interpenetrating, < 0 gap (finite always)
  Eigen::Vector3d p_wheel_in_world = Eigen::Vector3d::Zero();           ///< wheel surface point, m
  Eigen::Vector3d p_rail_in_world = Eigen::Vector3d::Zero();            ///< rail surface point, m
  Eigen::Vector3d n_in_world = Eigen::Vector3d::UnitZ();                ///< unit normal, from rail into wheel
  Eigen::Vector3d t_rolling_in_world = Eigen::Vector3d::UnitX();        ///< wheel circumferential unit tangent, forward
  Eigen::Vector3d p_section_centre_in_world = Eigen::Vector3d::Zero();  ///< deformed rail section centre at s_r, m
  RailSectionMotion rail_motion;                                        ///< provider's section motion at s_r
  double wheel_radius = 0.0;            ///< distance from the axle to the wheel point (rolling radius), m
  double cos_normal_radial = 1.0;       ///< |n . radial direction| (for the wheel's rolling curvature)
  double wheel_curvature = 0.0;         ///< wheel profile curvature at u_w, 1/m (convex > 0)
  double rail_curvature = 0.0;          ///< rail profile curvature at u_r, 1/m (convex > 0)
  double wheel_y = 0.0, wheel_z = 0.0;  ///< contact point in the wheel profile frame, m
  double rail_y = 0.0, rail_z = 0.0;    ///< contact point in the rail profile frame, m
  double profile_u = 0.0;               ///< u_w on the whole wheel profile (tread, then flange), m
  int iterations = 0;                   ///< Newton iterations of this call
  bool on_own_surface = true;           ///< u_w inside the surface itself, not in its continuation past the split
  /// The point pair lies past the surface's end (its continuation included), on the neighbouring surface's
  /// part of the profile, and penetrates: taken when the surface's own point is not in contact, so that a
  /// surface whose neighbour follows another point still carries a second contact (e.g. a flange-root
  /// contact beside the tread's taping-line contact). valid and in_contact are set; on_own_surface is false.
  bool past_end = false;
};

/// The wheel profile's sampled distance to the rail over its whole length, the tread's part then the
/// flange's, in one rail section (ContactDetector::scanProfile): what tells a wheel's contact patches apart.
struct ProfileScan {
  static constexpr int kMaxSamples = 1024;
  static constexpr int kMaxMinima = 16;
  struct Minimum {
    int sample = 0;                                  ///< index into profile_u and distance
    int surface = 0;                                 ///< 0 tread, 1 flange: the part of the profile it lies on
    Eigen::Vector4d seed = Eigen::Vector4d::Zero();  ///< Newton start (s_w, u_w, s_r, u_r) on that surface
  };
  int n = 0;
  double profile_u[kMaxSamples];  ///< arc position on the whole profile (ContactGeometry::profile_u), increasing, m
  /// signed distance to the rail, the smallest over the fan of wheel planes, m; above
  /// DetectionOptions::scan_skip_clearance a sample may hold a lower bound instead
  double distance[kMaxSamples];
  int n_minima = 0;
  Minimum minima[kMaxMinima];  ///< interpenetrating interior minima, deepest first
  /// Index of the sample nearest to profile position U (n > 0).
  int nearest(double U) const noexcept;
  /// Points at profile positions U_a and U_b lie in one contact patch unless the interpenetration between
  /// them dips below the shallower one's by more than `dip` of it (or by more than min_dip, m); neighbouring
  /// samples are one patch.
  bool samePatch(double U_a, double U_b, double dip, double min_dip) const noexcept;
};

/// Detector for one wheel profile on one rail profile. Constant after building; shared by all wheels
/// with these profiles. The rail profile is given in the rail profile frame of track_geometry.hpp (y
/// toward the track centre, z along the rail's up axis), the wheel profile in the frame of profile.hpp.
class ContactDetector {
 public:
  /// wheel: tread and flange curves; nominal_radius: r0 (m); rail: rail profile curve;
  /// section_centre_yz: rail section centre (beam axis) in the rail profile frame (m), e.g.
  /// (0, -uic60::kCentroidDepth) for an untilted UIC60. Throws std::runtime_error on non-physical input.
  ContactDetector(const WheelProfile& wheel, double nominal_radius, const ProfileCurve& rail,
                  const Eigen::Vector2d& section_centre_yz, const DetectionOptions& options = {});

  /// Detects the point pair of one wheel surface on its rail. No allocation, no exception.
  template <class Deformation>
  void detect(WheelSurface surface, const WheelPose& pose, const TrackGeometry& track, const Deformation& deformation,
              DetectionWork& work, ContactGeometry& out) const noexcept;

  /// Samples the tread's own part of the profile and, with include_flange, the flange's (each sample over
  /// the search's fan of wheel planes) in the rail section nearest to the wheel. No allocation.
  template <class Deformation>
  void scanProfile(const WheelPose& pose, const TrackGeometry& track, const Deformation& deformation,
                   bool include_flange, ProfileScan& out) const noexcept;

  const ProfileCurve& wheelCurve(WheelSurface s) const { return s == WheelSurface::kTread ? tread_ : flange_; }
  const ProfileCurve& railCurve() const { return rail_; }
  double nominalRadius() const { return r0_; }
  const Eigen::Vector2d& sectionCentre() const { return section_centre_; }
  const DetectionOptions& options() const { return options_; }

  /// Signed distance (m, > 0 outside the rail) of a point of the rail profile frame to the rail profile,
  /// from the precomputed grid (bilinear), and the parameter of the closest rail point (nearest cell).
  double railSignedDistance(const Eigen::Vector2d& p_yz, double* u_closest = nullptr) const noexcept;

  /// Parameter range of wheel surface `surface` (0 tread, 1 flange) including its continuation across the
  /// split (DetectionOptions::split_overlap): tread [0, L_tread + overlap], flange [-overlap, L_flange].
  double surfaceUMin(int surface) const noexcept;
  double surfaceUMax(int surface) const noexcept;
  /// Arc position on the whole wheel profile (tread, then flange) of surface `surface`'s parameter u.
  double profileU(int surface, double u) const noexcept { return surface == 0 ? u : u + tread_.uMax(); }
  /// Profile curve and local parameter of surface `surface` at its parameter u (possibly continued).
  const ProfileCurve& profileCurveAt(int surface, double u, double& u_local) const noexcept;

 private:
  struct Sample {
    double u, y, z;
    double arc;  // chord length along the samples from the surface's first, m
  };
  ProfileCurve tread_, flange_, rail_;
  double r0_ = 0.0;
  Eigen::Vector2d section_centre_;
  DetectionOptions options_;
  double wheel_normal_sign_[2] = {1.0, 1.0};
  double rail_normal_sign_ = 1.0;
  std::vector<Sample> samples_[2];  // wheel profile samples per surface
  // Signed-distance grid of the rail profile.
  double grid_y0_ = 0.0, grid_z0_ = 0.0, grid_h_ = 0.0;
  int grid_ny_ = 0, grid_nz_ = 0;
  std::vector<float> grid_dist_, grid_u_;

  double search_lever_[2] = {0.0, 0.0};            // max over a surface's samples of |y| + 2.2 |r0 - z|, m
  static constexpr double kMaxSearchSlope = 5.67;  // tan(80 deg)
  static constexpr double kPastEndScan = 0.015;    // how far a penetrating end sample's scan goes outward, m
  double search_slope_[2] = {0.0, 0.0};            // steepest |dz/dy| between a surface's samples, capped

  // The rail section nearest to the wheel centre, as the search uses it, and the wheel's pose in it.
  struct SectionPose {
    double s = 0.0;
    Eigen::Vector3d o, T, Ny, B;  // section origin and axes (deformed with the rail if not rigid)
    Eigen::Vector2d centre;       // wheel centre: (Ny, B) components of c - o
    Eigen::Vector3d axle;         // axle direction: (T, Ny, B) components
  };
  // Half-width of the fan of wheel planes searched for surface `surface` (DetectionOptions::search_plane_step).
  double fanWidth(int surface, const SectionPose& section) const noexcept;
  // Bound on how fast the grid's signed distance changes along the wheel profile (bilinear interpolation of
  // a distance: sqrt(2), with room for the grid's float rounding).
  static constexpr double kScanLipschitz = 1.5;

  template <class Deformation>
  void sectionPose(const WheelPose& pose, const TrackGeometry& track, const Deformation& deformation,
                   const Eigen::Vector3d& c, const Eigen::Vector3d& a, SectionPose& out) const noexcept;

  // min_distance: the smallest sample distance (whether or not a seed was found); end_seed: the seed is an
  // end sample of the surface (DetectionOptions::end_seed_reach), not an interior minimum.
  template <class Deformation>
  bool search(WheelSurface surface, const WheelPose& pose, const TrackGeometry& track, const Deformation& deformation,
              Eigen::Vector4d& x_seed, double& distance, Eigen::Vector3d& p_wheel_seed, double& min_distance,
              SectionPose& section, bool& end_seed) const noexcept;
};

}  // namespace contact
}  // namespace rail
