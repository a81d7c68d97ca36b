// Per-wheel contact evaluation (paper section 4.1, eqs. 9-13 and 15): detection of the tread and flange
// contacts of one wheel on its rail (contact_detection.hpp), Hertz normal force with hysteresis damping
// (hertz.hpp), creepages from the material-point velocities (creepage.hpp), creep forces (polach.hpp),
// contact force vectors (eq. 12) and their equivalent wrenches at the wheel centre (eq. 13) and on the
// rail cross-section (eq. 15) (wrench_transfer.hpp).
//
// Contact frame of each contact: t_rolling (wheel circumferential direction, forward along the track),
// t_lateral = n x t_rolling, n the unit normal from the rail into the wheel. Forces act on the wheel;
// the rail receives the opposite forces. World frame x forward, y left, z up.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "rail_contact/contact_cost.hpp"
#include "rail_contact/contact_detection.hpp"
#include "rail_contact/creepage.hpp"
#include "rail_contact/hertz.hpp"
#include "rail_contact/kalker.hpp"
#include "rail_contact/polach.hpp"
#include "rail_contact/wheel_defects.hpp"
#include "rail_contact/wheel_state.hpp"
#include "rail_contact/wrench_transfer.hpp"

namespace rail {
namespace contact {

/// Tangential creep-force law. Only Polach's method for now; the enum leaves room for another law.
enum class CreepLaw : std::uint8_t { kPolach = 0 };

/// Scene effects and material data (constant after building the model).
struct WheelContactOptions {
  bool flange_contact = true;  ///< false: the flange search is not run at all
  bool spin = true;            ///< spin creepage in the creep forces (Polach's F_yS, nu_C)
  CreepLaw creep_law = CreepLaw::kPolach;
  double friction = 0.3;           ///< mu0, maximum friction coefficient [-] (scene value; no default implied)
  PolachOptions polach;            ///< kA, kS, A, B (its `spin` field is overridden by `spin`)
  ElasticMaterial wheel_material;  ///< E, nu of the wheel
  ElasticMaterial rail_material;   ///< E, nu of the rail
  NormalDampingParams damping;     ///< restitution e, exponent n, impact-velocity floor (eq. 9)
  CreepageOptions creepage;        ///< speed regularisation at standstill
  HertzOptions hertz;              ///< degenerate-geometry clamps
  DetectionOptions detection;      ///< Newton and search settings
  /// Largest lateral semi-axis b of a contact ellipse [m] (limitLateralWidth, hertz.hpp); 0 = no limit.
  /// Hertz's theory needs the patch small against the profile arcs around it; at the flange root those
  /// are the UIC60 gauge-corner arc (R 13 mm, EN 13674-1) and the S1002 throat, so a near-conformal patch
  /// spans at most about half that arc's width. 10 mm is also above every non-conformal patch of these
  /// profiles up to 1 MN (tread b 3.2 mm at 73 kN, b ~ N^(1/3): 7.7 mm at 1 MN). Why: doc/forces.md.
  double max_lateral_semi_axis = 0.010;
  /// Tread and flange contacts closer than this (wheel points, m) are one conformal patch across the
  /// tread/flange split: only the deeper one is kept (the other is flagged merged).
  double merge_distance = 3e-3;
  /// Contact patches. Each evaluation samples the profile's distance to the rail (ContactDetector::scanProfile).
  /// Every maximum of the interpenetration is a patch of its own unless the interpenetration between it and
  /// a deeper one dips by less than patch_dip of its depth and less than patch_min_dip (then both are one
  /// patch, ProfileScan::samePatch), or the two are closer than merge_distance. A patch is one contact, at
  /// its deepest point: a tread or flange contact elsewhere in a patch is dropped (its surface searches
  /// afresh), two of them in one patch are merged, and up to two patches they do not hold are carried in
  /// the slots kTreadSecond and kFlangeSecond, the deepest first. A profile pair can offer more candidates
  /// than two surfaces hold: S1002 on UIC60 1:20 in curves has the taping line, a tread point near
  /// 0.11 rad, the flange root and the flange face, and with one point per surface which of them are carried
  /// depends on the path that led to the pose. false: one point per surface (contact geometry tables, whose
  /// rows are one point per surface by definition).
  bool second_contacts = true;
  double patch_dip = 0.1;       ///< [0, 1)
  double patch_min_dip = 5e-6;  ///< m, about the rail grid's bilinear error near the gauge corner (search_cell)
  /// Flats and out-of-roundness per wheel (WheelState::id), applied to each contact's penetration and its
  /// rate; empty: nothing is evaluated.
  WheelDefects wheel_defects;
};

/// Throws std::runtime_error naming the field and value when an option is non-physical.
void validate(const WheelContactOptions& options);

/// Slots of a wheel's contacts: the first contact of each surface, then the second of each.
constexpr int kTread = 0;
constexpr int kFlange = 1;
constexpr int kTreadSecond = 2;
constexpr int kFlangeSecond = 3;
constexpr int kContactSlots = 4;

/// One contact (what rail_msgs/ContactPoint carries, plus the force vectors and the detection details).
struct ContactPointResult {
  bool active = false;  ///< surfaces interpenetrate and N > 0 is evaluated
  DetectionStatus status = DetectionStatus::kOutOfBounds;
  bool searched = false;  ///< false: the search was not run (flange contact off)
  bool merged = false;    ///< in contact but merged into the other surface's contact (one patch, see merge_distance)
  int surface = kTread;   ///< wheel surface the point was detected on (kTread or kFlange)
  double s_r = 0.0;       ///< rail arc length of the contact, m
  Eigen::Vector3d p_contact_in_world = Eigen::Vector3d::Zero();      ///< midpoint of wheel and rail points, m
  Eigen::Vector3d p_wheel_in_world = Eigen::Vector3d::Zero();        ///< wheel surface point, m
  Eigen::Vector3d p_rail_in_world = Eigen::Vector3d::Zero();         ///< rail surface point, m
  Eigen::Vector3d normal_in_world = Eigen::Vector3d::UnitZ();        ///< unit normal, rail into wheel
  Eigen::Matrix3d R_contact_to_world = Eigen::Matrix3d::Identity();  ///< columns t_rolling, t_lateral, n
  double N = 0.0;                                                    ///< normal force, N (>= 0)
  double F_long = 0.0;                                               ///< creep force along t_rolling on the wheel, N
  double F_lat = 0.0;                                                ///< creep force along t_lateral on the wheel, N
  double nu_x = 0.0, nu_y = 0.0;                                     ///< longitudinal and lateral creepages, -
  double phi = 0.0;                                                  ///< spin creepage, 1/m (0 with spin off)
  double a = 0.0, b = 0.0;        ///< contact ellipse semi-axes (rolling, lateral), m
  double penetration = 0.0;       ///< delta, m (> 0 in contact; finite gap otherwise)
  double penetration_rate = 0.0;  ///< d delta / dt, m/s (> 0 approaching)
  double rolling_radius = 0.0;    ///< wheel radius at the contact, m
  double contact_angle = 0.0;  ///< normal's inclination to the plane normal to the axle, toward the track centre, rad
                               ///< (to the track plane: add the wheelset's roll toward this wheel)
  Eigen::Vector3d force_on_wheel_in_world = Eigen::Vector3d::Zero();  ///< eq. 12, N
  RailWrench rail_wrench;  ///< eq. 15 for this contact alone, about its own section centre at s_r
  Eigen::Vector3d p_section_centre_in_world = Eigen::Vector3d::Zero();  ///< rail section centre at s_r, m
  std::uint32_t hertz_flags = 0;                                        ///< HertzFlag bits of the contact geometry
};

/// Output of one wheel's evaluation.
struct WheelContactResult {
  ContactPointResult contact[kContactSlots];  ///< [kTread], [kFlange], [kTreadSecond], [kFlangeSecond]
  WheelsetWrench wheel_centre;  ///< eq. 13: force (world) and moment about the wheel centre (wheelset frame)
  RailWrench rail_section;      ///< eq. 15: every contact about the section centre at rail_section_s
  double rail_section_s = 0.0;  ///< s_r of that section (the first active contact in slot order), m
};

/// Eq. 13 and 15 summed over a wheel's active contacts into out.wheel_centre, out.rail_section and
/// out.rail_section_s (zero wrenches if not finite).
void sumContactWrenches(const Eigen::Vector3d& p_wheel_in_world, const Eigen::Matrix3d& R_wheelset_to_world,
                        WheelContactResult& out) noexcept;

/// Caller-owned per-wheel work state: detection warm starts and impact memories of every contact slot.
struct WheelContactWork {
  DetectionWork detection[kContactSlots];
  ImpactMemory impact[kContactSlots];
  /// false: each evaluation updates impact[]. true: an evaluation reads impact[] and writes the updated
  /// memory to impact_next[], which the caller commits (commitImpactMemory) once the state it evaluated is
  /// accepted, so that the trial states of an implicit integrator (Newton iterates, rejected steps) do not
  /// enter the memory and the force is a function of the state and the accepted history.
  bool hold_impact_memory = false;
  ImpactMemory impact_next[kContactSlots];
  void commitImpactMemory() {
    for (int k = 0; k < kContactSlots; ++k) impact[k] = impact_next[k];
  }
  /// What the caller commits at an accepted step: the held impact memories and warm starts.
  void commitAcceptedStep() {
    if (hold_impact_memory) commitImpactMemory();
    for (DetectionWork& d : detection) {
      if (d.hold_warm_start) d.commitWarmStart();
    }
  }
  void reset() {
    const bool hold = hold_impact_memory;
    bool hold_warm[kContactSlots];
    for (int k = 0; k < kContactSlots; ++k) hold_warm[k] = detection[k].hold_warm_start;
    *this = WheelContactWork();
    hold_impact_memory = hold;
    for (int k = 0; k < kContactSlots; ++k) detection[k].hold_warm_start = hold_warm[k];
  }
};

/// Contact model for one wheel profile on one rail profile. Constant after building.
class WheelContactModel {
 public:
  /// Throws std::runtime_error on non-physical options or geometry (see ContactDetector).
  WheelContactModel(const WheelProfile& wheel, double nominal_radius, const ProfileCurve& rail,
                    const Eigen::Vector2d& rail_section_centre_yz, const WheelContactOptions& options);

  /// Evaluates the contacts of one wheel on the rail of the same side. No allocation, no exception;
  /// finite output for any finite input (invalid input gives inactive contacts and zero wrenches).
  /// cost: when not null, the search and force times and the counts of this evaluation are added to it
  /// (a few steady-clock reads per contact); null: no timing.
  template <class Deformation>
  void evaluate(const WheelState& wheel, RailSide side, const TrackGeometry& track, const Deformation& deformation,
                WheelContactWork& work, WheelContactResult& out, ContactCost* cost = nullptr) const noexcept;

  const ContactDetector& detector() const { return detector_; }
  const WheelContactOptions& options() const { return options_; }
  double contactModulus() const { return E_star_; }
  double shearModulus() const { return G_; }
  double poissonRatio() const { return nu_; }

 private:
  WheelContactOptions options_;
  ContactDetector detector_;
  PolachOptions polach_;
  double E_star_ = 0.0, G_ = 0.0, nu_ = 0.0;
  const KalkerTable* kalker_ = nullptr;
};

}  // namespace contact
}  // namespace rail
